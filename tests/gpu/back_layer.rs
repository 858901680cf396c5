//! A case only the back-face layer catches: seen from straight above, the sides of a box are
//! back faces, and its top is farther than r_far from the floor around it.

use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::metrics::rmse;

use crate::harness::{Gpu, SceneSpec, plain_ao};

/// A unit box on a 10 m floor, seen from 4 m straight above.
fn box_on_floor_from_above() -> SceneSpec {
    SceneSpec::new(Transform::from_xyz(0.0, 4.0, 0.0).looking_at(Vec3::ZERO, -Vec3::Z))
        .with(
            Plane3d::default().mesh().size(10.0, 10.0).build(),
            Transform::IDENTITY,
        )
        .with(
            Cuboid::new(1.0, 1.0, 1.0),
            Transform::from_xyz(0.0, 0.5, 0.0),
        )
}

#[test]
fn back_faces_occlude_the_floor_next_to_a_box() {
    let radius = 0.75;
    let scene = box_on_floor_from_above();
    let with_back = |back_layer| {
        plain_ao()
            .with_radius(radius)
            .with_near_field(NearFieldParams {
                back_layer,
                ..default()
            })
    };
    let mut gpu = Gpu::new(&scene, with_back(true));
    let on = gpu.frame(4);
    gpu.set_ao(|ao| *ao = with_back(false));
    let off = gpu.frame(4);
    let truth = on.ground_truth(&scene.bvh(), radius);

    // Visible floor within 0.5 m of the box sides.
    let ring: Vec<bool> = (0..on.visibility.len())
        .map(|i| {
            on.position(i).is_some_and(|p| {
                let gap = p.x.abs().max(p.z.abs()) - 0.5;
                p.y.abs() < 0.01 && gap > 0.0 && gap < 0.5
            })
        })
        .collect();
    let count = ring.iter().filter(|r| **r).count();
    assert!(
        count > 500,
        "the ring of floor around the box should be visible ({count} pixels)"
    );
    let mean = |v: &[f32]| {
        v.iter()
            .zip(&ring)
            .filter(|(_, r)| **r)
            .map(|(v, _)| v)
            .sum::<f32>()
            / count as f32
    };
    let (on_mean, off_mean, truth_mean) =
        (mean(&on.visibility), mean(&off.visibility), mean(&truth));
    println!(
        "floor ring visibility: back layer on {on_mean:.3}, off {off_mean:.3}, ground truth {truth_mean:.3}"
    );
    assert!(
        off_mean > 0.97,
        "without the back layer nothing should occlude the ring: {off_mean}"
    );
    assert!(
        truth_mean < 0.9,
        "ground truth should see the box sides: {truth_mean}"
    );
    assert!(
        on_mean < off_mean - 0.05,
        "the back layer should darken the ring: {on_mean} vs {off_mean}"
    );
    assert!(
        rmse(&on.visibility, &truth, Some(&ring)) < rmse(&off.visibility, &truth, Some(&ring)),
        "the back layer should bring the ring closer to ground truth"
    );
    // The back layer itself: the box sides are there, never in front of the front layer.
    let back_pixels = on.nd.back.iter().filter(|t| t.depth > 0.0).count();
    assert!(
        back_pixels > 500,
        "the back layer should hold the box's sides ({back_pixels})"
    );
    for (front, back) in on.nd.front.iter().zip(&on.nd.back) {
        assert!(
            back.depth <= front.depth + 1e-6,
            "a back face in front of the front layer"
        );
    }
}

/// Bevy's prepass draws only meshes with a material, so the back layer skips the others too:
/// a box without a material in front of an empty background leaves both layers empty.
#[test]
fn meshes_without_a_material_are_in_neither_layer() {
    let mut gpu = Gpu::new(
        &SceneSpec::new(Transform::from_xyz(0.0, 0.0, 3.0).looking_at(Vec3::ZERO, Vec3::Y)),
        plain_ao(),
    );
    let world = gpu.app.world_mut();
    let cube = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(1.0, 1.0, 1.0));
    world.spawn((Mesh3d(cube), Transform::IDENTITY));
    let frame = gpu.frame(4);
    let front = frame.nd.front.iter().filter(|t| t.depth > 0.0).count();
    let back = frame.nd.back.iter().filter(|t| t.depth > 0.0).count();
    assert_eq!((front, back), (0, 0), "front {front}, back {back} pixels");
}

/// Only the near field reads the back layer's normals; the ray march draws the layer's depth
/// alone, without a fragment stage. The depth is the same either way, the read-back normal is
/// zero where none is drawn, and switching the technique back brings the normals back.
#[test]
fn the_back_layer_draws_normals_only_for_the_near_field() {
    let scene = box_on_floor_from_above();
    let near_field = plain_ao().with_technique(AoTechnique::NearField);
    let mut gpu = Gpu::new(&scene, near_field.clone());
    let with_normals = gpu.frame(4);
    gpu.set_ao(|ao| *ao = near_field.clone().with_technique(AoTechnique::RayMarch));
    let depth_only = gpu.frame(4);
    gpu.set_ao(|ao| *ao = near_field.clone());
    let again = gpu.frame(4);

    let drawn = |frame: &crate::harness::Frame| {
        frame
            .nd
            .back
            .iter()
            .filter(|t| t.depth > 0.0)
            .map(|t| t.normal)
            .collect::<Vec<_>>()
    };
    let (first, second, third) = (drawn(&with_normals), drawn(&depth_only), drawn(&again));
    assert!(
        first.len() > 500,
        "the back layer should hold the box's sides ({})",
        first.len()
    );
    // Seen from above, the box's back faces are its sides and its bottom: unit normals,
    // horizontal or pointing down, away from the camera.
    for normals in [&first, &third] {
        assert!(
            normals
                .iter()
                .all(|n| (n.length() - 1.0).abs() < 0.01 && n.y < 0.01),
            "near field: the back layer's normals should be the box's outward normals"
        );
    }
    assert!(
        second.iter().all(|n| *n == Vec3::ZERO),
        "ray march: the back layer should hold no normals"
    );
    for (a, b) in with_normals.nd.back.iter().zip(&depth_only.nd.back) {
        assert!(
            (a.depth - b.depth).abs() < 1e-6,
            "the depth-only layer differs: {} against {}",
            b.depth,
            a.depth
        );
    }
}

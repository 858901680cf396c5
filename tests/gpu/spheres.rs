//! The far field of sphere occluders: the splat pass against the CPU evaluation of the same
//! proxies on the same ND-buffer, a skinned character's proxies against its mesh, bad occluder
//! meshes and asynchronous fitting. Ground-truth comparisons of every far-field term are in
//! `far_field`.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::PrimitiveTopology;
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::spheres::join::{ProxyJoin, proxy_joins};

use bevy::mesh::skinning::SkinnedMesh;

use crate::far_scenes::{cpu_sphere_visibility, spheres_of};
use crate::harness::{Gpu, SceneSpec, difference_stats, plain_ao};
use crate::skinned::{LENGTH, column, column_bindposes};

fn occluder(count: u32) -> SphereOccluder {
    SphereOccluder { count, ..default() }
}

fn far_field_only() -> DynamicAo {
    DynamicAo {
        technique: AoTechnique::Off,
        ..plain_ao()
    }
}

/// A skinned column standing at `at`, bent 1 rad at its elbow so that its two bones' boxes stand
/// one beside the other as the floor around it sees them.
fn bent_column(gpu: &mut Gpu, at: Vec3) {
    let world = gpu.app.world_mut();
    let bindposes = column_bindposes(world);
    let mesh = world.resource_mut::<Assets<Mesh>>().add(column());
    let root = world.spawn(Transform::from_translation(at)).id();
    let elbow = world
        .spawn((
            Transform::from_xyz(0.0, LENGTH / 2.0, 0.0).with_rotation(Quat::from_rotation_z(-1.0)),
            ChildOf(root),
        ))
        .id();
    world.spawn((
        Mesh3d(mesh),
        SkinnedMesh {
            inverse_bindposes: bindposes,
            joints: vec![root, elbow],
        },
        SphereOccluder::default(),
        Transform::from_translation(at),
    ));
}

/// The splat against its CPU twin on rigid occluders (a ball, a lying capsule, a small ball near
/// the eye, an open cube frame with a box inside it) and a skinned column: compose joins the
/// column's proxies by their union, the frame's and the box's by their union outside the frame's
/// proxies and as independent occluders inside them (`spheres::join`), the rest as independent
/// occluders.
#[test]
fn splat_matches_the_cpu_formula_on_the_same_nd_buffer() {
    let camera = Transform::from_xyz(2.0, 1.8, 2.8).looking_at(Vec3::new(0.0, 0.35, 0.0), Vec3::Y);
    let scene = SceneSpec::new(camera)
        .with(
            Plane3d::default().mesh().size(10.0, 10.0),
            Transform::IDENTITY,
        )
        .with_occluder(
            Sphere::new(0.5).mesh().uv(32, 16),
            Transform::from_xyz(0.0, 0.5, 0.0),
            occluder(1),
        )
        .with_occluder(
            Capsule3d::new(0.15, 0.8).mesh(),
            Transform::from_xyz(1.0, 0.15, 0.3)
                .with_rotation(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2)),
            occluder(6),
        )
        // Close enough to the camera that its reach contains the eye, and near the image's
        // left edge: both ends of the billboard bounds.
        .with_occluder(
            Sphere::new(0.1).mesh().uv(16, 8),
            Transform::from_xyz(0.9, 1.2, 2.3),
            occluder(1),
        )
        .with_occluder(
            crate::scenes::window_frame(0.6, 0.4),
            Transform::from_xyz(0.9, 0.3, -0.9),
            occluder(16),
        )
        .with_occluder(
            Cuboid::new(0.4, 0.6, 0.4),
            Transform::from_xyz(0.9, 0.3, -0.9),
            occluder(1),
        );
    for orthographic in [false, true] {
        let mut gpu = Gpu::new(&scene, far_field_only());
        bent_column(&mut gpu, Vec3::new(-1.0, 0.0, 0.6));
        if orthographic {
            let camera = gpu.camera;
            gpu.app
                .world_mut()
                .entity_mut(camera)
                .insert(Projection::Orthographic(OrthographicProjection {
                    scaling_mode: bevy::camera::ScalingMode::FixedVertical {
                        viewport_height: 3.0,
                    },
                    ..OrthographicProjection::default_3d()
                }));
        }
        let frame = gpu.frame(4);
        let occluders = spheres_of(&mut gpu);
        let count: usize = occluders.iter().map(|o| o.spheres.len()).sum();
        // Compose joins a skinned mesh's proxies by their union, the frame's and the box's by
        // their union outside the frame's proxies, and the rest by their product: every kind
        // takes part.
        assert_eq!(occluders.len(), 6);
        assert_eq!(occluders.iter().filter(|o| o.articulated).count(), 1);
        let joins = proxy_joins(&occluders);
        assert_eq!(
            joins
                .iter()
                .filter(|j| matches!(j, ProxyJoin::UnionOutside { .. }))
                .count(),
            2,
            "{joins:?}"
        );
        assert!(count >= 5, "{count} proxies");

        // The far field alone counts every occluder within the camera's radius.
        let cpu = cpu_sphere_visibility(&frame, &occluders, plain_ao().radius);
        let mask = frame.geometry_mask();
        let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
        let darkest = cpu.iter().copied().fold(1.0, f32::min);
        let touched = cpu.iter().filter(|v| **v < 0.99).count();
        println!(
            "splat (orthographic {orthographic}): {count} proxies, {touched} pixels occluded, \
             darkest {darkest:.3}; GPU vs CPU mean |diff| {mean:.5}, 99th percentile {p99:.5}"
        );
        assert!(
            darkest < 0.5 && touched > 2000,
            "the proxies should darken the floor"
        );
        // Two R16Float buffers (far field, hand-off) each round to about 1e-3 near 1.
        assert!(mean < 0.002, "mean |GPU − CPU| = {mean}");
        assert!(p99 < 0.01, "99th percentile |GPU − CPU| = {p99}");
        // A billboard too small to cover a sphere's reach loses the faint outer ring (values
        // near ε): far above rounding, on a ring of pixels.
        let off = frame
            .visibility
            .iter()
            .zip(&cpu)
            .zip(&mask)
            .filter(|((g, c), m)| **m && (*g - *c).abs() > 0.004)
            .count();
        let covered = mask.iter().filter(|m| **m).count();
        println!("{off} of {covered} pixels differ by more than 0.004");
        assert!(
            off * 1000 < covered * 2,
            "{off} pixels differ by more than 0.004"
        );
    }
}

#[test]
fn bad_occluder_meshes_warn_and_fall_back() {
    let empty = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, Vec::<[f32; 3]>::new());
    let one_triangle = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(
        Mesh::ATTRIBUTE_POSITION,
        vec![[0.0f32, 0.5, 0.0], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5]],
    );
    let lines = Mesh::new(PrimitiveTopology::LineList, RenderAssetUsages::default())
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_POSITION,
            vec![[0.0f32, 0.0, 0.0], [1.0, 1.0, 1.0]],
        );
    let mut nan = Transform::from_xyz(0.0, 0.5, 0.0);
    nan.translation.x = f32::NAN;
    let scene = SceneSpec::new(
        Transform::from_xyz(2.0, 1.8, 2.8).looking_at(Vec3::new(0.0, 0.35, 0.0), Vec3::Y),
    )
    .with(
        Plane3d::default().mesh().size(10.0, 10.0),
        Transform::IDENTITY,
    )
    .with_occluder(empty, Transform::IDENTITY, occluder(8))
    .with_occluder(one_triangle, Transform::IDENTITY, occluder(100))
    .with_occluder(lines, Transform::IDENTITY, occluder(4))
    .with_occluder(Sphere::new(0.3).mesh().uv(16, 8), nan, occluder(4))
    .with_occluder(
        Sphere::new(0.3).mesh().uv(16, 8),
        Transform::from_xyz(-0.8, 0.3, 0.0),
        SphereOccluder {
            count: 0,
            reach: ProxyReach::Epsilon(f32::NAN),
            ..default()
        },
    );
    let mut gpu = Gpu::new(&scene, far_field_only());
    let frame = gpu.frame(4);
    let occluders = spheres_of(&mut gpu);
    let counts: Vec<usize> = occluders.iter().map(|o| o.spheres.len()).collect();
    println!("spheres per bad occluder: {counts:?}");
    for o in &occluders {
        assert!(
            o.spheres
                .iter()
                .all(|s| s.center.is_finite() && s.radius > 0.0)
        );
        assert!(
            matches!(o.reach, ProxyReach::Epsilon(e) if e > 0.0 && e < 1.0)
                || o.reach == ProxyReach::CameraRadius
        );
    }
    // The lone triangle gets a few flat boxes (a triangle fills half its bounding rectangle);
    // the sanitized ball (count 0 → 1) one box.
    assert!(counts.iter().all(|c| *c <= 4), "{counts:?}");
    assert!(counts.contains(&1), "{counts:?}");
    let seen = frame.geometry_visibility();
    assert!(
        seen.iter()
            .all(|v| v.is_finite() && (0.0..=1.0).contains(v))
    );
    let mean = seen.iter().sum::<f32>() / seen.len() as f32;
    assert!(mean > 0.8, "the image should stay mostly open: {mean}");

    // A despawned occluder takes its spheres with it.
    let world = gpu.app.world_mut();
    let entities: Vec<Entity> = world
        .query_filtered::<Entity, With<SphereOccluder>>()
        .iter(world)
        .collect();
    for entity in entities {
        world.despawn(entity);
    }
    let after = gpu.frame(3);
    assert!(spheres_of(&mut gpu).is_empty());
    let open = after
        .visibility
        .iter()
        .zip(&after.geometry_mask())
        .filter(|(_, m)| **m)
        .all(|(v, _)| *v > 0.999);
    assert!(open, "with no occluder left, the far field is empty");
}

/// A mesh over `ASYNC_CLUSTERING_VERTICES` is fitted on the async compute pool: the frame that
/// meets it renders without its proxies instead of waiting, and they arrive a few frames later
/// (the paper's Lloyd spheres here, 16 of them, and boxes).
#[test]
fn large_meshes_are_clustered_without_stalling_a_frame() {
    let ball = Sphere::new(0.5).mesh().uv(64, 40);
    assert!(
        ball.count_vertices() > bevy_dynamic_ao::spheres::ASYNC_CLUSTERING_VERTICES,
        "the test mesh must take the async path"
    );
    let mut gpu = Gpu::new(
        &SceneSpec::new(Transform::from_xyz(0.0, 2.0, 4.0).looking_at(Vec3::ZERO, Vec3::Y)),
        far_field_only(),
    );
    let mesh = gpu.app.world_mut().resource_mut::<Assets<Mesh>>().add(ball);
    let entity = gpu
        .app
        .world_mut()
        .spawn((
            Mesh3d(mesh.clone()),
            Transform::from_xyz(0.0, 0.5, 0.0),
            SphereOccluder {
                shape: ProxyShape::Spheres,
                ..default()
            },
        ))
        .id();
    let boxes = gpu
        .app
        .world_mut()
        .spawn((
            Mesh3d(mesh),
            Transform::from_xyz(1.5, 0.5, 0.0),
            SphereOccluder::default(),
        ))
        .id();
    gpu.update(1);
    let count = |gpu: &Gpu, entity: Entity| {
        gpu.app
            .world()
            .get::<OccluderSpheres>(entity)
            .map_or(0, |s| s.spheres.len())
    };
    assert_eq!(
        (count(&gpu, entity), count(&gpu, boxes)),
        (0, 0),
        "the first frame must not wait for the fitting"
    );
    let mut frames = 1;
    while (count(&gpu, entity) == 0 || count(&gpu, boxes) == 0) && frames < 300 {
        gpu.update(1);
        frames += 1;
    }
    println!("proxies of a large mesh arrived after {frames} frames");
    assert_eq!(count(&gpu, entity), 16);
    assert_eq!(count(&gpu, boxes), 1, "a ball is one box");
}

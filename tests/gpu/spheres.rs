//! The far field of sphere occluders: the splat pass against the CPU evaluation of eq. 2–3 on
//! the same ND-buffer, an off-screen occluder against ground truth and Bevy's SSAO, and bad
//! occluder meshes.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::PrimitiveTopology;
use bevy::prelude::*;
use bevy_dynamic_ao::FarFieldBlend;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{metrics::rmse, spheres::far_field_occlusion};

use crate::harness::{Gpu, SceneSpec, WIDTH, band, difference_stats};

fn occluder(count: u32) -> SphereOccluder {
    SphereOccluder { count, ..default() }
}

fn far_field_only() -> DynamicAo {
    DynamicAo {
        technique: AoTechnique::Off,
        ..default()
    }
}

fn spheres_of(gpu: &mut Gpu) -> Vec<OccluderSpheres> {
    let world = gpu.app.world_mut();
    world
        .query::<&OccluderSpheres>()
        .iter(world)
        .cloned()
        .collect()
}

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
        );
    for orthographic in [false, true] {
        let mut gpu = Gpu::new(&scene, far_field_only());
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
        assert_eq!(occluders.len(), 3);
        assert!(count >= 6, "{count} spheres");

        let cpu: Vec<f32> = far_field_occlusion(&frame.nd, &frame.view, &occluders)
            .into_iter()
            .map(|o| 1.0 - o.min(1.0))
            .collect();
        let mask = frame.geometry_mask();
        let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
        let darkest = cpu.iter().copied().fold(1.0, f32::min);
        let touched = cpu.iter().filter(|v| **v < 0.99).count();
        println!(
            "splat (orthographic {orthographic}): {count} spheres, {touched} pixels occluded, \
             darkest {darkest:.3}; GPU vs CPU mean |diff| {mean:.5}, 99th percentile {p99:.5}"
        );
        assert!(
            darkest < 0.5 && touched > 2000,
            "the spheres should darken the floor"
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

/// A ball just outside the view of a camera looking down at the floor.
fn off_screen_ball() -> SceneSpec {
    SceneSpec::new(Transform::from_xyz(0.0, 2.5, 0.0).looking_at(Vec3::ZERO, -Vec3::Z))
        .with(
            Plane3d::default().mesh().size(10.0, 10.0),
            Transform::IDENTITY,
        )
        .with_occluder(
            Sphere::new(0.8).mesh().uv(48, 24),
            Transform::from_xyz(2.3, 0.8, 0.0),
            occluder(1),
        )
}

/// Ground truth radius for the far field: far larger than the ball, so it is unlimited here.
const FAR_RADIUS: f32 = 5.0;

#[test]
fn an_occluder_outside_the_view_darkens_the_floor_beside_it() {
    let scene = off_screen_ball();
    let mut gpu = Gpu::new(&scene, DynamicAo::default());
    let near_only = {
        gpu.set_ao(|ao| ao.spheres = false);
        gpu.frame(4)
    };
    let visible_ball = near_only.nd.front.iter().any(|t| {
        // Any surface point above the floor would be the ball.
        t.depth > 0.0 && t.normal.y < 0.99
    });
    assert!(!visible_ball, "the ball must be outside the view");
    gpu.set_ao(|ao| ao.spheres = true);
    let with_spheres = gpu.frame(4);
    gpu.set_ao(|ao| ao.technique = AoTechnique::BevySsao);
    let bevy = gpu.frame(4);

    let truth = with_spheres.ground_truth(&scene.bvh(), FAR_RADIUS);
    let mask = with_spheres.geometry_mask();
    let error = |v: &[f32]| rmse(v, &truth, Some(&mask));
    // Mean occlusion of the strip of floor nearest the ball (the right tenth of the image) above
    // that of the farthest strip (the left tenth): what the ball adds.
    let strip = |v: &[f32]| band(v, WIDTH * 9 / 10..WIDTH) - band(v, 0..WIDTH / 10);
    println!(
        "off-screen ball, occlusion the ball adds to the nearest strip: truth {:.3}, near+spheres {:.3}, \
         near only {:.3}, Bevy SSAO {:.3}; RMSE vs truth (R = {FAR_RADIUS} m): near+spheres \
         {:.4}, near only {:.4}, Bevy SSAO {:.4}",
        strip(&truth),
        strip(&with_spheres.visibility),
        strip(&near_only.visibility),
        strip(&bevy.visibility),
        error(&with_spheres.visibility),
        error(&near_only.visibility),
        error(&bevy.visibility),
    );
    assert!(
        strip(&truth) > 0.1,
        "the scene should have off-screen occlusion"
    );
    assert!(
        strip(&bevy.visibility).abs() < 0.02,
        "Bevy's SSAO cannot see the ball"
    );
    assert!(strip(&near_only.visibility).abs() < 0.02);
    assert!(
        (strip(&with_spheres.visibility) - strip(&truth)).abs() < 0.3 * strip(&truth),
        "the far field should match ground truth beside the ball"
    );
    assert!(error(&with_spheres.visibility) < 0.5 * error(&near_only.visibility));
    assert!(error(&with_spheres.visibility) < 0.5 * error(&bevy.visibility));
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
            epsilon: f32::NAN,
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
        assert!(o.epsilon > 0.0 && o.epsilon < 1.0);
    }
    // The triangle gets at most one sphere per distinct vertex; the sanitized ball gets one.
    assert!(counts.iter().all(|c| *c <= 3), "{counts:?}");
    assert!(counts.contains(&1), "{counts:?}");
    let mask = frame.geometry_mask();
    let seen: Vec<f32> = frame
        .visibility
        .iter()
        .zip(&mask)
        .filter(|(_, m)| **m)
        .map(|(v, _)| *v)
        .collect();
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

/// On scenes whose occluders are in view the near field already sees them, so the far field
/// counts them a second time when the terms add (S&A §6). The test measures both blends against
/// ground truth over the near field's radius and over a wider one: `Max` never counts an occluder
/// twice, so it must stay close to the near field alone at its radius, and neither blend may lose
/// accuracy over the wider radius, where the far field is what reaches.
#[test]
fn far_field_on_visible_occluders() {
    for (name, scene) in crate::scenes::all() {
        // Every mesh but the floor (the first) casts spheres.
        let mut scene = scene;
        scene.occluders = (1..scene.meshes.len())
            .map(|i| (i, SphereOccluder::default()))
            .collect();
        let mut gpu = Gpu::new(&scene, DynamicAo::default());
        gpu.set_ao(|ao| ao.spheres = false);
        let near = gpu.frame(4);
        gpu.set_ao(|ao| ao.spheres = true);
        let added = gpu.frame(4);
        gpu.set_ao(|ao| ao.far_field_blend = FarFieldBlend::Max);
        let max = gpu.frame(4);
        let bvh = scene.bvh();
        let mask = near.geometry_mask();
        let mut errors = Vec::new();
        for radius in [0.73, 2.0] {
            let truth = near.ground_truth(&bvh, radius);
            let error = |v: &[f32]| rmse(v, &truth, Some(&mask));
            let e = [
                error(&near.visibility),
                error(&added.visibility),
                error(&max.visibility),
            ];
            println!(
                "{name}, R = {radius} m: RMSE near field {:.4}, near + spheres (add) {:.4}, \
                 (max) {:.4}",
                e[0], e[1], e[2]
            );
            errors.push(e);
        }
        let [near_r, added_r, max_r] = errors[0];
        let [near_wide, added_wide, max_wide] = errors[1];
        assert!(max_r < near_r + 0.035, "{name}: max blend at R = 0.73 m");
        assert!(
            max_r <= added_r + 1e-4,
            "{name}: max should not count more than add"
        );
        assert!(added_wide < near_wide + 1e-3, "{name}: add at R = 2 m");
        assert!(max_wide < near_wide + 1e-3, "{name}: max at R = 2 m");
    }
}

/// A mesh over `ASYNC_CLUSTERING_VERTICES` is clustered on the async compute pool: the frame that
/// meets it renders without its spheres instead of waiting, and they arrive a few frames later.
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
            Mesh3d(mesh),
            Transform::from_xyz(0.0, 0.5, 0.0),
            SphereOccluder::default(),
        ))
        .id();
    gpu.update(1);
    let count = |gpu: &Gpu| {
        gpu.app
            .world()
            .get::<OccluderSpheres>(entity)
            .map_or(0, |s| s.spheres.len())
    };
    assert_eq!(
        count(&gpu),
        0,
        "the first frame must not wait for the clustering"
    );
    let mut frames = 1;
    while count(&gpu) == 0 && frames < 300 {
        gpu.update(1);
        frames += 1;
    }
    println!("spheres of a large mesh arrived after {frames} frames");
    assert_eq!(count(&gpu), 16);
}

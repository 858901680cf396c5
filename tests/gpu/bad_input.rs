//! Bad input gets a warning and a working image, never a panic or a black screen.

use bevy::asset::RenderAssetUsages;
use bevy::camera::Viewport;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;

use crate::harness::{Gpu, largest_difference, plain_ao};
use crate::log_capture::assert_logged_once;
use crate::scenes;

fn mean_luminance(image: &[Vec3]) -> f32 {
    image.iter().map(|c| (c.x + c.y + c.z) / 3.0).sum::<f32>() / image.len() as f32
}

#[test]
fn zero_size_viewport_does_not_panic() {
    let mut gpu = Gpu::new(&scenes::cube_on_plane(), plain_ao());
    let camera = gpu.camera;
    gpu.app
        .world_mut()
        .entity_mut(camera)
        .insert(Name::new("empty viewport camera"));
    gpu.app
        .world_mut()
        .get_mut::<Camera>(camera)
        .unwrap()
        .viewport = Some(Viewport {
        physical_position: UVec2::ZERO,
        physical_size: UVec2::ZERO,
        ..default()
    });
    gpu.update(6);
    assert_logged_once(&["'empty viewport camera'", "zero-size viewport"]);
    gpu.app
        .world_mut()
        .get_mut::<Camera>(camera)
        .unwrap()
        .viewport = None;
    let frame = gpu.frame(6);
    assert!(
        frame.visibility.iter().any(|v| *v < 0.7),
        "AO did not come back with a real viewport"
    );
}

#[test]
fn mesh_without_normals_and_nan_transform_do_not_break_the_frame() {
    let mut no_normals = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    );
    no_normals.insert_attribute(
        Mesh::ATTRIBUTE_POSITION,
        vec![
            [-0.5, 0.0, -0.5],
            [0.5, 0.0, -0.5],
            [0.0, 0.8, 0.0],
            [0.0, 0.0, 0.5],
        ],
    );
    no_normals.insert_indices(Indices::U32(vec![0, 2, 1, 1, 2, 3, 3, 2, 0, 0, 1, 3]));
    let scene = scenes::cube_on_plane()
        .with(no_normals, Transform::from_xyz(-1.2, 0.0, 0.8))
        .with(
            Cuboid::new(0.3, 0.3, 0.3),
            Transform::from_translation(Vec3::NAN),
        )
        // A degenerate triangle.
        .with(
            Mesh::new(
                PrimitiveTopology::TriangleList,
                RenderAssetUsages::default(),
            )
            .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, vec![[0.0f32; 3]; 3])
            .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vec![[0.0f32, 1.0, 0.0]; 3]),
            Transform::IDENTITY,
        );
    let mut gpu = Gpu::new(&scene, plain_ao());
    let frame = gpu.frame(6);
    assert!(
        frame
            .visibility
            .iter()
            .all(|v| v.is_finite() && (0.0..=1.0).contains(v))
    );
    assert!(frame.visibility.iter().any(|v| *v < 0.7), "AO vanished");
    assert!(mean_luminance(&gpu.color(1)) > 0.02, "the image is black");
    // The CPU side drops what cannot be traced and says how much.
    let mut triangles = bevy_dynamic_ao::geometry::triangles::TriangleScene::default();
    for (mesh, transform) in &scene.meshes {
        triangles.add_mesh(mesh, transform.compute_affine());
    }
    assert!(
        triangles.skipped >= 13,
        "NaN and degenerate triangles should be skipped: {}",
        triangles.skipped
    );
}

/// Out-of-range settings are replaced by valid ones, each with one warning naming the value and
/// what is used instead; the image is the one the replacements give.
#[test]
fn bad_settings_fall_back_to_defaults() {
    let bad = DynamicAo {
        radius: f32::NAN,
        intensity: f32::INFINITY,
        near_field_radius: -1.0,
        horizon: HorizonParams {
            directions: 0,
            ..default()
        },
        blur: AoBlur {
            sharpness: f32::NAN,
            ..default()
        },
        temporal: AoTemporal {
            max_frames: 0,
            ..AoTemporal::OFF
        },
        ..plain_ao()
    };
    let mut gpu = Gpu::new(&scenes::cube_on_plane(), bad);
    let camera = gpu.camera;
    gpu.app
        .world_mut()
        .entity_mut(camera)
        .insert(Name::new("bad settings camera"));
    let frame = gpu.frame(4);
    let camera = "'bad settings camera'";
    assert_logged_once(&[camera, "radius NaN is out of range; using 0.75"]);
    assert_logged_once(&[camera, "intensity inf is out of range; using 1.0"]);
    assert_logged_once(&[camera, "near_field_radius -1.0 is out of range; using 0.5"]);
    assert_logged_once(&[camera, "horizon", "directions: 0", "directions: 1"]);
    assert_logged_once(&[camera, "blur", "sharpness: NaN"]);
    assert_logged_once(&[camera, "temporal.max_frames 0 is out of range; using 1"]);
    // The fallback: the image of the replacements, which are the defaults for what this
    // technique reads.
    gpu.set_ao(|ao| *ao = plain_ao());
    let valid = gpu.frame(4);
    let largest = largest_difference(&frame.visibility, &valid.visibility);
    assert!(
        largest < 1e-6,
        "bad settings should render as their replacements, off by {largest}"
    );
    assert!(
        frame.visibility.iter().any(|v| *v < 0.8),
        "defaults should still give AO"
    );
}

/// A `SphereOccluder` with no proxies and a NaN ε gets one warning and casts as one proxy with the
/// paper's ε would.
#[test]
fn bad_sphere_occluder_settings_are_replaced_with_a_warning() {
    let bad = SphereOccluder {
        count: 0,
        reach: ProxyReach::Epsilon(f32::NAN),
        ..default()
    };
    let valid = SphereOccluder {
        count: 1,
        reach: ProxyReach::Epsilon(SphereOccluder::PAPER_EPSILON),
        ..default()
    };
    let far_only = DynamicAo {
        technique: AoTechnique::Off,
        ..plain_ao()
    };
    let scene = |occluder| {
        scenes::cube_on_plane().with_occluder(
            Cuboid::new(0.6, 0.6, 0.6),
            Transform::from_xyz(1.2, 0.3, -0.6),
            occluder,
        )
    };
    let mut gpu = Gpu::new(&scene(bad), far_only.clone());
    let occluder = {
        let world = gpu.app.world_mut();
        world
            .query_filtered::<Entity, With<SphereOccluder>>()
            .single(world)
            .unwrap()
    };
    gpu.app
        .world_mut()
        .entity_mut(occluder)
        .insert(Name::new("bad proxies"));
    let replaced = gpu.frame(4);
    drop(gpu);
    assert_logged_once(&["'bad proxies'", "count: 0", "is out of range", "count: 1"]);
    let expected = Gpu::new(&scene(valid), far_only).frame(4);
    let largest = largest_difference(&replaced.visibility, &expected.visibility);
    assert!(
        replaced.visibility.iter().any(|v| *v < 0.95),
        "the replaced occluder should still cast"
    );
    assert!(largest < 1e-6, "off by {largest}");
}

/// A shader that stops compiling (the compose shader replaced by one with a syntax error, as a
/// hot reload during development can do): one error names the pipeline, and the camera goes back
/// to Bevy's SSAO, exactly the image Bevy's SSAO gives on the same view.
#[test]
fn a_pipeline_that_fails_to_compile_leaves_the_camera_on_bevys_ssao() {
    let scene = scenes::cube_on_plane();
    let bevy = Gpu::new(
        &scene,
        DynamicAo {
            technique: AoTechnique::BevySsao,
            ..plain_ao()
        },
    )
    .frame(4);
    let mut gpu = Gpu::new(&scene, plain_ao());
    let ours = gpu.frame(4);
    let world = gpu.app.world_mut();
    let mut shaders = world.resource_mut::<Assets<Shader>>();
    let (id, path) = shaders
        .iter()
        .find(|(_, shader)| shader.path.ends_with("compose/compose.wgsl"))
        .map(|(id, shader)| (id, shader.path.clone()))
        .expect("the compose shader is loaded");
    shaders
        .insert(id, Shader::from_wgsl("fn compose( {", path))
        .expect("the shader's slot is live");
    let after = gpu.frame(6);
    assert_logged_once(&[
        "'dynamic_ao_compose_pipeline'",
        "failed to compile",
        "keep Bevy's SSAO",
    ]);
    let from_bevy = largest_difference(&after.visibility, &bevy.visibility);
    let from_ours = largest_difference(&ours.visibility, &bevy.visibility);
    println!(
        "after the failure: largest difference from Bevy's SSAO {from_bevy}; ours differed by {from_ours}"
    );
    assert!(
        from_ours > 0.1,
        "ours should differ from Bevy's SSAO: {from_ours}"
    );
    assert!(
        from_bevy < 1e-3,
        "the camera should show Bevy's SSAO: {from_bevy}"
    );
    // The camera's status says so too, frames in a row counting on.
    let status = |gpu: &Gpu| *gpu.app.world().get::<DynamicAoStatus>(gpu.camera).unwrap();
    let first = status(&gpu);
    gpu.update(3);
    let later = status(&gpu);
    assert!(
        first.shown == AoShown::Fallback && later.shown == AoShown::Fallback,
        "the status should say Bevy's SSAO stands in: {first:?}, {later:?}"
    );
    assert_eq!(later.frames, first.frames + 3, "{first:?}, {later:?}");
}

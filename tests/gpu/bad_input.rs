//! Bad input gets a warning and a working image, never a panic or a black screen.

use bevy::asset::RenderAssetUsages;
use bevy::camera::Viewport;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;

use crate::harness::{Gpu, SceneSpec, plain_ao};
use crate::scenes;

fn mean_luminance(image: &[Vec3]) -> f32 {
    image.iter().map(|c| (c.x + c.y + c.z) / 3.0).sum::<f32>() / image.len() as f32
}

#[test]
fn msaa_camera_renders_without_ao() {
    let mut gpu = Gpu::new(&scenes::cube_on_plane(), plain_ao());
    let camera = gpu.camera;
    gpu.app.world_mut().entity_mut(camera).insert(Msaa::Sample4);
    let image = gpu.color(6);
    assert!(
        gpu.app
            .world()
            .get::<ScreenSpaceAmbientOcclusion>(camera)
            .is_none(),
        "an MSAA camera should drop the SSAO texture our pass writes"
    );
    assert!(mean_luminance(&image) > 0.05, "the MSAA image is black");
    // Back to Msaa::Off: AO comes back.
    gpu.app.world_mut().entity_mut(camera).insert(Msaa::Off);
    let frame = gpu.frame(6);
    assert!(
        frame.visibility.iter().any(|v| *v < 0.7),
        "AO did not come back after MSAA was turned off"
    );
}

#[test]
fn zero_size_viewport_does_not_panic() {
    let mut gpu = Gpu::new(&scenes::cube_on_plane(), plain_ao());
    let camera = gpu.camera;
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

#[test]
fn bad_settings_fall_back_to_defaults() {
    let ao = DynamicAo {
        radius: f32::NAN,
        intensity: f32::INFINITY,
        ..plain_ao()
    };
    let mut gpu = Gpu::new(
        &SceneSpec {
            ..scenes::cube_on_plane()
        },
        ao,
    );
    let frame = gpu.frame(4);
    assert!(frame.visibility.iter().all(|v| v.is_finite()));
    assert!(
        frame.visibility.iter().any(|v| *v < 0.8),
        "defaults should still give AO"
    );
}

//! Bad volumes: skipped or clamped with a warning, never a panic.

use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::voxels::{VoxelGridInfo, VoxelMarch};

use super::{spawn_volume, voxels_only};
use crate::harness::Gpu;
use crate::scenes;

/// Zero-size, inverted and NaN volumes are skipped, out-of-range settings are clamped, a NaN
/// transform skips its volume; inside a volume, a mesh with a NaN transform, a line mesh and a
/// mesh of degenerate triangles are left out; the frame still renders and a good volume works.
#[test]
fn bad_volumes_are_skipped_or_clamped_without_a_panic() {
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::new(&scene, voxels_only());
    let bad = [
        (Transform::IDENTITY, VoxelAoVolume::new(Vec3::ZERO)),
        (
            Transform::IDENTITY,
            VoxelAoVolume::new(Vec3::new(1.0, -1.0, 1.0)),
        ),
        (Transform::IDENTITY, VoxelAoVolume::new(Vec3::NAN)),
        (Transform::from_scale(Vec3::ZERO), VoxelAoVolume::default()),
        (
            Transform::from_xyz(f32::NAN, 0.0, 0.0),
            VoxelAoVolume::default(),
        ),
    ];
    let bad: Vec<Entity> = bad
        .into_iter()
        .map(|(t, v)| spawn_volume(&mut gpu, t, v))
        .collect();
    let clamped = [
        VoxelAoVolume {
            resolution: 0,
            rays: 0,
            accumulated_rays: 0,
            march: VoxelMarch::Steps(0),
            spread: -1.0,
            d_max: Some(f32::NAN),
            ..default()
        },
        VoxelAoVolume {
            resolution: 100_000,
            rays: 100_000,
            accumulated_rays: 100_000,
            march: VoxelMarch::Steps(100_000),
            spread: 7.0,
            d_max: Some(-3.0),
            ..VoxelAoVolume::new(Vec3::new(2.5, 1.0, 2.5))
        },
    ];
    // The second lies away from the scene, so its clamped 512³ grid and 256 rays cost little.
    let clamped: Vec<Entity> = clamped
        .into_iter()
        .zip([Vec3::new(0.0, 0.8, 0.0), Vec3::new(50.0, 0.0, 0.0)])
        .map(|(v, at)| spawn_volume(&mut gpu, Transform::from_translation(at), v))
        .collect();
    let world = gpu.app.world_mut();
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let cube = meshes.add(Cuboid::new(0.3, 0.3, 0.3));
    let lines = meshes.add(
        Mesh::new(
            bevy::mesh::PrimitiveTopology::LineList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_POSITION,
            vec![[0.0f32, 0.2, 0.0], [0.5, 0.2, 0.0]],
        ),
    );
    let flat = meshes.add(
        Mesh::new(
            bevy::mesh::PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_POSITION,
            vec![[0.0f32, 0.2, 0.0], [0.5, 0.2, 0.0], [1.0, 0.2, 0.0]],
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vec![[0.0f32, 1.0, 0.0]; 3]),
    );
    world.spawn((
        Mesh3d(cube),
        MeshMaterial3d(material.clone()),
        Transform::from_xyz(f32::NAN, 0.5, 0.0),
    ));
    world.spawn((Mesh3d(lines), Transform::from_xyz(0.5, 0.0, 0.8)));
    world.spawn((
        Mesh3d(flat),
        MeshMaterial3d(material),
        Transform::from_xyz(-0.5, 0.0, 0.8),
    ));
    let frame = gpu.frame(3);
    let world = gpu.app.world();
    for entity in bad {
        assert!(world.get::<VoxelGridInfo>(entity).is_none());
    }
    let resolutions: Vec<u32> = clamped
        .iter()
        .map(|&e| {
            world
                .get::<VoxelGridInfo>(e)
                .expect("clamped, in use")
                .resolution
        })
        .collect();
    assert_eq!(
        resolutions,
        [VoxelAoVolume::MIN_RESOLUTION, VoxelAoVolume::MAX_RESOLUTION]
    );
    let rays = world.get::<VoxelGridInfo>(clamped[1]).unwrap().rays;
    assert_eq!(
        (rays.rays, rays.accumulated_rays, rays.march, rays.d_max),
        (
            VoxelAoVolume::MAX_RAYS,
            VoxelAoVolume::MAX_RAYS,
            VoxelMarch::Steps(VoxelAoVolume::MAX_STEPS),
            None
        )
    );
    let fewest = world.get::<VoxelGridInfo>(clamped[0]).unwrap().rays;
    assert_eq!((fewest.rays, fewest.accumulated_rays), (1, 1));
    assert!(frame.visibility.iter().all(|v| v.is_finite()));
    let mask = frame.geometry_mask();
    let mean = frame.visibility.iter().sum::<f32>() / frame.visibility.len() as f32;
    assert!(mean > 0.7 && mean < 1.0, "mean visibility {mean}");
    assert!(mask.iter().any(|m| *m));
}

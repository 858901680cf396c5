//! The GPU's voxel grids against a CPU triangle–cell voxelization, rigid and skinned.

use bevy::camera::visibility::NoFrustumCulling;
use bevy::math::Affine3A;
use bevy::mesh::skinning::SkinnedMesh;
use bevy::prelude::*;
use bevy_dynamic_ao::geometry::{
    closed::is_closed,
    triangles::{Triangle, TriangleScene},
};
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::voxels::{VoxelGrid, voxelize};
use bevy_dynamic_ao::voxels::VoxelGridInfo;

use super::{read_grids, spawn_volume, voxels_only};
use crate::harness::{Gpu, SceneSpec};
use crate::scenes;
use crate::skinned::{LENGTH, column, column_bindposes};

/// Cells set in one grid and not the other, cells set in either, and how many of the differing
/// cells have no occupied neighbour in `cpu` (a difference away from any surface).
fn compare_grids(gpu: &VoxelGrid, cpu: &VoxelGrid) -> (u32, u32, u32) {
    let n = gpu.resolution as i32;
    let (mut differ, mut union, mut interior) = (0, 0, 0);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (g, c) = (gpu.occupied([x, y, z]), cpu.occupied([x, y, z]));
                union += u32::from(g || c);
                if g != c {
                    differ += 1;
                    let near_surface = (-1..=1).any(|dz| {
                        (-1..=1).any(|dy| {
                            (-1..=1).any(|dx| {
                                (dx, dy, dz) != (0, 0, 0) && cpu.occupied([x + dx, y + dy, z + dz])
                            })
                        })
                    });
                    interior += u32::from(!near_surface);
                }
            }
        }
    }
    (differ, union, interior)
}

/// Each mesh's world-space triangles.
fn mesh_triangles(meshes: &[(Mesh, Affine3A)]) -> Vec<Vec<Triangle>> {
    meshes
        .iter()
        .map(|(mesh, transform)| {
            let mut triangles = TriangleScene::default();
            triangles.add_mesh(mesh, *transform);
            triangles.triangles
        })
        .collect()
}

/// The CPU voxelization of `meshes` into the grid `info` describes: surfaces, and the interior
/// of the closed ones.
fn cpu_grid(meshes: &[Vec<Triangle>], info: &VoxelGridInfo) -> VoxelGrid {
    let all: Vec<Triangle> = meshes.concat();
    let mut grid = voxelize(&all, info.resolution, info.grid_from_world);
    for mesh in meshes {
        if is_closed(mesh.iter().map(|t| t.vertices)) {
            grid.fill_closed(mesh);
        }
    }
    grid
}

fn assert_grids_agree(what: &str, gpu: &VoxelGrid, cpu: &VoxelGrid) {
    let (differ, union, interior) = compare_grids(gpu, cpu);
    println!(
        "{what}: {} GPU cells, {} CPU cells, {differ} differ of {union} occupied in either",
        gpu.count(),
        cpu.count()
    );
    assert!(cpu.count() > 100, "{what}: the scene should fill cells");
    assert!(
        differ * 100 <= union,
        "{what}: {differ} of {union} cells differ"
    );
    assert_eq!(interior, 0, "{what}: differences away from any surface");
}

#[test]
fn gpu_voxelization_matches_a_cpu_triangle_cell_voxelization() {
    let scene = scenes::cube_on_plane()
        .with(
            Sphere::new(0.45).mesh().uv(32, 16),
            Transform::from_xyz(-1.2, 0.45, 0.4),
        )
        .with(
            Cuboid::new(0.6, 0.3, 0.9),
            Transform::from_xyz(1.0, 0.4, -0.8).with_rotation(Quat::from_euler(
                EulerRot::XYZ,
                0.4,
                0.7,
                0.2,
            )),
        )
        // Thin, large closed occluders that reach past both volumes: a wall across every
        // column of the grids' z axis and a slab under the floor.
        .with(
            Cuboid::new(8.0, 4.0, 0.1),
            Transform::from_xyz(0.0, 1.0, -1.3),
        )
        .with(
            Cuboid::new(8.0, 0.1, 8.0),
            Transform::from_xyz(0.0, -0.3, 0.0),
        );
    let mut gpu = Gpu::new(&scene, voxels_only());
    // A turned volume and a second, coarser one overlapping it: several grids per frame. 64³
    // layers fill whole 32-bit words and 22³ ones do not, the two ways the interior is filled.
    let turned = spawn_volume(
        &mut gpu,
        Transform::from_xyz(0.0, 0.6, 0.0).with_rotation(Quat::from_rotation_y(0.5)),
        VoxelAoVolume {
            half_extents: Vec3::new(2.0, 1.0, 1.8),
            resolution: 64,
            ..default()
        },
    );
    let coarse = spawn_volume(
        &mut gpu,
        Transform::from_xyz(0.5, 0.5, 0.5),
        VoxelAoVolume {
            half_extents: Vec3::splat(1.5),
            resolution: 22,
            ..default()
        },
    );
    // A ball that asks to stay out of the grids; the CPU voxelization leaves it out too.
    let world = gpu.app.world_mut();
    let ball = world
        .resource_mut::<Assets<Mesh>>()
        .add(Sphere::new(0.3).mesh().ico(2).unwrap());
    world.spawn((
        Mesh3d(ball),
        Transform::from_xyz(0.8, 1.2, 0.8),
        bevy_dynamic_ao::voxels::NotVoxelOccluder,
    ));
    gpu.update(2);
    let meshes = mesh_triangles(
        &scene
            .meshes
            .iter()
            .map(|(m, t)| (m.clone(), t.compute_affine()))
            .collect::<Vec<_>>(),
    );
    for (name, (info, grid)) in ["turned 64³", "coarse 22³"]
        .into_iter()
        .zip(read_grids(&mut gpu, &[turned, coarse]))
    {
        let cpu = cpu_grid(&meshes, &info);
        let surface_only = voxelize(&meshes.concat(), info.resolution, info.grid_from_world);
        assert!(
            cpu.count() > surface_only.count(),
            "{name}: closed meshes should be filled"
        );
        assert!(info.triangles > 0);
        assert_grids_agree(name, &grid, &cpu);
    }
}

#[test]
fn a_skinned_mesh_is_voxelized_in_its_pose() {
    let mut gpu = Gpu::new(
        &SceneSpec::new(Transform::from_xyz(0.0, 0.7, 2.2)),
        voxels_only(),
    );
    let world = gpu.app.world_mut();
    let bindposes = column_bindposes(world);
    let mesh = column();
    let handle = world.resource_mut::<Assets<Mesh>>().add(mesh.clone());
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    let bend = Quat::from_rotation_z(-0.8);
    let root = world.spawn(Transform::IDENTITY).id();
    let elbow = world
        .spawn((
            Transform::from_xyz(0.0, LENGTH / 2.0, 0.0).with_rotation(bend),
            ChildOf(root),
        ))
        .id();
    world.spawn((
        Mesh3d(handle),
        MeshMaterial3d(material),
        SkinnedMesh {
            inverse_bindposes: bindposes,
            joints: vec![root, elbow],
        },
        NoFrustumCulling,
        Transform::IDENTITY,
    ));
    let volume = spawn_volume(
        &mut gpu,
        Transform::from_xyz(0.3, 0.7, 0.0),
        VoxelAoVolume {
            half_extents: Vec3::new(0.8, 0.8, 0.4),
            resolution: 48,
            ..default()
        },
    );
    gpu.update(3);
    let (info, grid) = read_grids(&mut gpu, &[volume]).remove(0);
    // The pose, worked out by hand: the upper half turns about the elbow.
    let elbow_pose = Affine3A::from_translation(Vec3::Y * (LENGTH / 2.0))
        * Affine3A::from_quat(bend)
        * Affine3A::from_translation(-Vec3::Y * (LENGTH / 2.0));
    let mut posed = mesh.clone();
    if let Some(bevy::mesh::VertexAttributeValues::Float32x3(positions)) =
        posed.attribute_mut(Mesh::ATTRIBUTE_POSITION)
    {
        for p in positions.iter_mut() {
            if p[1] > LENGTH / 2.0 + 1e-4 {
                *p = elbow_pose.transform_point3(Vec3::from(*p)).to_array();
            }
        }
    }
    let cpu = cpu_grid(&mesh_triangles(&[(posed, Affine3A::IDENTITY)]), &info);
    let unbent = cpu_grid(&mesh_triangles(&[(mesh, Affine3A::IDENTITY)]), &info);
    assert_grids_agree("bent column", &grid, &cpu);
    let (differ_rest, ..) = compare_grids(&grid, &unbent);
    assert!(
        differ_rest > 100,
        "the grid should follow the bend, not the rest pose ({differ_rest} cells differ)"
    );
}

//! CPU cost of voxel volumes per frame: gathering the triangles that reach into a volume (skinning
//! and morphing included) and moving them into its grid space, before the GPU voxelizes them.
//! Measured as whole updates of a minimal app (transform propagation plus the gather system)
//! around one 128³ volume, for rigid meshes of 10k and 100k triangles and a skinned mesh of 10k;
//! the `no meshes` row is the update alone.
//!
//! `cargo bench --bench voxels`

use bevy::asset::AssetPlugin;
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::mesh::{Mesh, VertexAttributeValues};
use bevy::prelude::*;
use bevy::shader::Shader;
use bevy_dynamic_ao::voxels::{VoxelAoPlugin, VoxelGridInfo};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

/// UV spheres of 960 triangles each, scattered in the volume, `count` of them.
fn app(balls: u32, skinned: bool) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TransformPlugin))
        .init_asset::<Mesh>()
        .init_asset::<Shader>()
        .init_asset::<SkinnedMeshInverseBindposes>()
        .add_plugins(VoxelAoPlugin);
    let world = app.world_mut();
    let mut mesh: Mesh = Sphere::new(0.15).mesh().uv(32, 16);
    let bindposes = world
        .resource_mut::<Assets<SkinnedMeshInverseBindposes>>()
        .add(vec![Mat4::IDENTITY, Mat4::IDENTITY]);
    if skinned {
        let count = mesh.count_vertices();
        let Some(VertexAttributeValues::Float32x3(positions)) =
            mesh.attribute(Mesh::ATTRIBUTE_POSITION)
        else {
            unreachable!("a UV sphere has positions");
        };
        let weights: Vec<[f32; 4]> = positions
            .iter()
            .map(|p| {
                let w = (p[1] / 0.15 * 0.5 + 0.5).clamp(0.0, 1.0);
                [1.0 - w, w, 0.0, 0.0]
            })
            .collect();
        mesh.insert_attribute(
            Mesh::ATTRIBUTE_JOINT_INDEX,
            VertexAttributeValues::Uint16x4(vec![[0, 1, 0, 0]; count]),
        );
        mesh.insert_attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT, weights);
    }
    let handle = world.resource_mut::<Assets<Mesh>>().add(mesh);
    let hash = |i: u32| (i.wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32;
    for i in 0..balls {
        let transform = Transform::from_xyz(
            -3.5 + 7.0 * hash(3 * i),
            0.15 + 2.0 * hash(3 * i + 1),
            -1.4 + 3.4 * hash(3 * i + 2),
        );
        let entity = world.spawn((Mesh3d(handle.clone()), transform));
        if skinned {
            let root = entity.id();
            let joints = vec![
                world.spawn((Transform::IDENTITY, ChildOf(root))).id(),
                world
                    .spawn((
                        Transform::from_rotation(Quat::from_rotation_z(0.3)),
                        ChildOf(root),
                    ))
                    .id(),
            ];
            world.entity_mut(root).insert(SkinnedMesh {
                inverse_bindposes: bindposes.clone(),
                joints,
            });
        }
    }
    world.spawn((
        Transform::from_xyz(0.0, 1.3, 0.3),
        bevy_dynamic_ao::voxels::VoxelAoVolume {
            half_extents: Vec3::new(4.0, 1.5, 2.5),
            resolution: 128,
            ..default()
        },
    ));
    app.update();
    app
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("voxel_gather_per_frame");
    for (name, balls, skinned) in [
        ("no meshes", 0u32, false),
        ("rigid", 10, false),
        ("rigid", 104, false),
        ("skinned", 10, true),
    ] {
        let mut app = app(balls, skinned);
        let world = app.world_mut();
        let triangles = world
            .query::<&VoxelGridInfo>()
            .single(world)
            .expect("the volume is in use")
            .triangles;
        group.bench_function(
            BenchmarkId::new(name, format!("{triangles} triangles")),
            |b| b.iter(|| app.update()),
        );
    }
    group.finish();
}

criterion_group!(voxel_benches, benches);
criterion_main!(voxel_benches);

//! CPU costs of sphere occluders: the per-frame refit of a skinned 10k-vertex mesh (the goal is
//! under 0.1 ms per 10k vertices on one core in a release build), the refit of a rigid mesh and
//! of the boxes of a morphed one, and the one-off Lloyd clustering.
//!
//! `cargo bench --bench spheres`

use bevy::math::{Affine3A, Quat, Vec3};
use bevy::prelude::*;
use bevy_dynamic_ao::geometry::{
    deform::Pose,
    rest_mesh::{RestMesh, VertexSkin},
};
use bevy_dynamic_ao::spheres::{
    fit::fit_boxes,
    lloyd::{ClusteredMesh, cluster},
    refit::refit,
};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

const JOINTS: usize = 8;

/// A UV sphere of about 10k vertices, skinned to eight joints stacked along y; every vertex
/// blends the two joints nearest its height (and two more with small weights), as a limb would.
fn skinned_mesh() -> RestMesh {
    let mesh: Mesh = Sphere::new(1.0).mesh().uv(140, 70);
    let mut rest = RestMesh::from_mesh(&mesh).expect("a triangle mesh");
    let skin = rest
        .positions
        .iter()
        .map(|p| {
            let band = ((p.y + 1.0) * 0.5 * (JOINTS - 1) as f32).clamp(0.0, (JOINTS - 1) as f32);
            let j = (band as usize).min(JOINTS - 2);
            let f = band - j as f32;
            let k = (j + 2).min(JOINTS - 1);
            let l = j.saturating_sub(1);
            VertexSkin {
                joints: [j as u16, j as u16 + 1, k as u16, l as u16],
                weights: [0.9 * (1.0 - f), 0.9 * f, 0.05, 0.05],
            }
        })
        .collect();
    rest.skin = Some(skin);
    rest
}

fn joints(t: f32) -> Vec<Affine3A> {
    (0..JOINTS)
        .map(|j| {
            let pivot = Vec3::Y * (j as f32 / (JOINTS - 1) as f32 * 2.0 - 1.0);
            Affine3A::from_translation(Vec3::new(5.0, 0.0, -3.0) + pivot)
                * Affine3A::from_quat(Quat::from_rotation_z(0.2 * (t + j as f32).sin()))
                * Affine3A::from_translation(-pivot)
        })
        .collect()
}

fn benches(c: &mut Criterion) {
    let mesh = skinned_mesh();
    let vertices = mesh.positions.len();
    let joints = joints(0.7);
    let mut group = c.benchmark_group(format!("sphere_refit_skinned_{vertices}_vertices"));
    for count in [16u32, 64] {
        let clustered: ClusteredMesh = cluster(&mesh, count);
        let mut out = Vec::new();
        group.bench_with_input(BenchmarkId::from_parameter(count), &count, |b, _| {
            b.iter(|| {
                let pose = Pose {
                    world_from_mesh: Affine3A::IDENTITY,
                    joints: &joints,
                    morph_weights: &[],
                };
                refit(&mesh, &clustered, &pose, &mut out)
            })
        });
    }
    group.finish();

    let clustered = cluster(&mesh, 16);
    let mut out = Vec::new();
    c.bench_function("sphere_refit_rigid_16_spheres", |b| {
        b.iter(|| {
            let pose = Pose {
                world_from_mesh: Affine3A::from_translation(Vec3::X),
                joints: &[],
                morph_weights: &[],
            };
            refit(&mesh, &clustered, &pose, &mut out)
        })
    });
    // The same sphere, unskinned, with one morph target that flattens it along y: its boxes take
    // the morphed vertices' spread along each of their axes every frame.
    let mut morphed = mesh.clone();
    morphed.skin = None;
    morphed.morph_positions = morphed
        .positions
        .iter()
        .map(|p| Vec3::Y * -0.3 * p.y)
        .collect();
    morphed.morph_targets = 1;
    let clustered = fit_boxes(&morphed, 16);
    c.bench_function(
        &format!(
            "box_refit_morphed_{vertices}_vertices_{}_boxes",
            clustered.spheres.len()
        ),
        |b| {
            b.iter(|| {
                let pose = Pose {
                    world_from_mesh: Affine3A::from_translation(Vec3::X),
                    joints: &[],
                    morph_weights: &[0.5],
                };
                refit(&morphed, &clustered, &pose, &mut out)
            })
        },
    );
    c.bench_function(
        &format!("lloyd_cluster_{vertices}_vertices_16_spheres"),
        |b| b.iter(|| cluster(&mesh, 16)),
    );
}

criterion_group! {
    name = spheres;
    config = Criterion::default().sample_size(10);
    targets = benches
}
criterion_main!(spheres);

//! The one-time CPU cost of a coarse back-face copy (`DynamicAo::coarse_back_faces`): a mesh's
//! rest-pose data copied out, then clustered to a quarter of its triangles, as the plugin does
//! when a camera first needs the copy.

use bevy::prelude::*;
use bevy_dynamic_ao::geometry::{rest_mesh::RestMesh, simplify::simplify};
use criterion::{Criterion, criterion_group, criterion_main};

fn benches(c: &mut Criterion) {
    // 65,536 triangles, as the GPU test `meshes_of_many_triangles_draw_their_back_faces_from_coarse_copies`.
    let torus: Mesh = Torus::new(0.2, 0.45)
        .mesh()
        .minor_resolution(128)
        .major_resolution(256)
        .build();
    c.bench_function("coarse_copy_torus_65k_triangles", |b| {
        b.iter(|| {
            let rest = RestMesh::from_mesh(&torus).unwrap();
            simplify(&rest.positions, &rest.triangles, rest.triangles.len() / 4)
        })
    });
}

criterion_group! {
    name = coarse_back_faces;
    config = Criterion::default().sample_size(10);
    targets = benches
}
criterion_main!(coarse_back_faces);

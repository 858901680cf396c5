//! Baking cost of an ambient occlusion field: a 32³ grid of 256 rays per point around a mesh of
//! about 10k triangles (the paper's default grid), on every core of the machine.
//!
//! `cargo bench --bench fields`

use bevy::math::Affine3A;
use bevy::prelude::*;
use bevy_dynamic_ao::fields::{BakeSettings, bake};
use bevy_dynamic_ao::geometry::triangles::TriangleScene;
use criterion::{Criterion, criterion_group, criterion_main};

fn benches(c: &mut Criterion) {
    let mut scene = TriangleScene::default();
    // A torus of 100 × 50 quads: 10,000 triangles, with a hole that makes the field interesting.
    scene.add_mesh(
        &Torus::new(0.3, 0.6)
            .mesh()
            .major_resolution(100)
            .minor_resolution(50)
            .build(),
        Affine3A::IDENTITY,
    );
    let triangles = scene.triangles;
    let name = format!("bake_32cubed_256_rays_{}_triangles", triangles.len());
    c.bench_function(&name, |b| {
        b.iter(|| bake(triangles.clone(), &BakeSettings::default(), &|_, _| {}).unwrap())
    });
}

criterion_group! {
    name = fields;
    config = Criterion::default().sample_size(10);
    targets = benches
}
criterion_main!(fields);

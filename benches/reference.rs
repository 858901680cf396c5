//! CPU reference costs: the near-field formula over a whole ND-buffer and ground-truth ray
//! tracing, on a synthetic 160×120 view of a box on a floor.

use bevy::math::{Affine3A, Mat4, Vec3};
use bevy::prelude::*;
use bevy_dynamic_ao::geometry::{bvh::Bvh, triangles::TriangleScene};
use bevy_dynamic_ao::reference::{
    ground_truth::{GroundTruthSettings, camera_ray, ground_truth_visibility},
    nd_buffer::{NdBuffer, NdTexel, ViewMatrices},
    near_field::{NearFieldInputs, near_field_occlusion},
};
use criterion::{Criterion, criterion_group, criterion_main};

const W: u32 = 160;
const H: u32 = 120;

fn scene() -> (Bvh, ViewMatrices) {
    let mut triangles = TriangleScene::default();
    triangles.add_mesh(
        &Plane3d::default().mesh().size(10.0, 10.0).build(),
        Affine3A::IDENTITY,
    );
    triangles.add_mesh(
        &Cuboid::new(1.0, 1.0, 1.0).into(),
        Affine3A::from_translation(Vec3::Y * 0.5),
    );
    triangles.add_mesh(
        &Sphere::new(0.4).mesh().uv(48, 24),
        Affine3A::from_translation(Vec3::new(1.2, 0.4, 0.3)),
    );
    let camera = Transform::from_xyz(2.0, 1.8, 2.8).looking_at(Vec3::new(0.0, 0.35, 0.0), Vec3::Y);
    let projection = Mat4::perspective_infinite_reverse_rh(
        std::f32::consts::FRAC_PI_4,
        W as f32 / H as f32,
        0.1,
    );
    (
        Bvh::new(triangles.triangles),
        ViewMatrices::new(camera.to_matrix(), projection),
    )
}

/// An ND-buffer traced on the CPU (front layer only), as the GPU would see the scene.
fn nd_buffer(bvh: &Bvh, view: &ViewMatrices) -> NdBuffer {
    let mut front = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let (origin, dir) = camera_ray(view, x, y, W, H);
            front.push(match bvh.closest_hit(origin, dir, 0.0, f32::INFINITY) {
                Some(hit) => {
                    let p = origin + dir * hit.t;
                    let clip = view.clip_from_view * view.view_from_world * p.extend(1.0);
                    let mut n = bvh.triangles()[hit.triangle].face_normal().normalize();
                    if n.dot(dir) > 0.0 {
                        n = -n;
                    }
                    NdTexel {
                        normal: n,
                        depth: clip.z / clip.w,
                    }
                }
                None => NdTexel::default(),
            });
        }
    }
    NdBuffer {
        width: W,
        height: H,
        back: vec![NdTexel::default(); front.len()],
        front,
    }
}

fn benches(c: &mut Criterion) {
    let (bvh, view) = scene();
    let nd = nd_buffer(&bvh, &view);
    let inputs = NearFieldInputs {
        radius: 0.75,
        intensity: 1.0,
        max_samples: 32,
        min_samples: 4,
        back_layer: false,
    };
    c.bench_function("near_field_cpu_160x120_32spp", |b| {
        b.iter(|| near_field_occlusion(&nd, &view, &inputs))
    });
    c.bench_function("bvh_build_box_ball_floor", |b| {
        b.iter(|| {
            let mut t = TriangleScene::default();
            t.add_mesh(&Sphere::new(0.4).mesh().uv(48, 24), Affine3A::IDENTITY);
            Bvh::new(t.triangles)
        })
    });
    let settings = GroundTruthSettings {
        width: W,
        height: H,
        radius: 0.75,
        rays_per_pixel: 16,
    };
    c.bench_function("ground_truth_160x120_16spp", |b| {
        b.iter(|| ground_truth_visibility(&bvh, &view, &settings))
    });
}

criterion_group! {
    name = reference;
    config = Criterion::default().sample_size(10);
    targets = benches
}
criterion_main!(reference);

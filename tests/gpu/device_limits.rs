//! Buffers past the device's storage binding limit (set low on lavapipe): one warning naming the
//! limit, what fits is kept, and the frame renders (binding more fails wgpu validation and ends
//! the app).

use bevy::prelude::*;
use bevy_dynamic_ao::fields::{AoFieldCache, BakeSettings};
use bevy_dynamic_ao::prelude::*;

use crate::harness::{Gpu, largest_difference, plain_ao};
use crate::log_capture::assert_logged_once;
use crate::scenes;

/// The storage binding limit the tests set: 256 KiB (Bevy's own passes need more than 128 KiB),
/// 2048 sphere proxies or 5461 triangles.
const LIMIT: u64 = 256 << 10;

/// A ball of 1152 triangles.
fn ball() -> Mesh {
    Sphere::new(0.3).mesh().uv(32, 18)
}

/// Forty balls around the cube on a 0.8 m grid, sharing one mesh (clustered once), each asking
/// for 128 proxies: 5120 in all.
fn spawn_balls(gpu: &mut Gpu) {
    let world = gpu.app.world_mut();
    let mesh = world.resource_mut::<Assets<Mesh>>().add(ball());
    let occluder = SphereOccluder {
        count: 128,
        shape: ProxyShape::Spheres,
        ..default()
    };
    for i in -3..=3 {
        for k in -3..=3 {
            let (x, z) = (i as f32 * 0.8, k as f32 * 0.8);
            if x.abs() < 0.9 && z.abs() < 0.9 {
                continue;
            }
            world.spawn((
                Mesh3d(mesh.clone()),
                Transform::from_xyz(x, 0.3, z),
                occluder,
            ));
        }
    }
}

/// Sphere proxies alone, reaching 0.2 m: thousands of proxies are thousands of billboards, each
/// as large as its reach, and lavapipe shades them slowly.
fn spheres_only() -> DynamicAo {
    DynamicAo {
        technique: AoTechnique::Off,
        fields: false,
        voxels: false,
        radius: 0.2,
        ..plain_ao()
    }
}

#[test]
fn sphere_proxies_past_the_binding_limit_are_left_out_with_a_warning() {
    let scene = scenes::cube_on_plane();
    let render = |mut gpu: Gpu| {
        spawn_balls(&mut gpu);
        gpu.frame(4).visibility
    };
    let all = render(Gpu::new(&scene, spheres_only()));
    let none = render(Gpu::new(
        &scene,
        DynamicAo {
            spheres: false,
            ..spheres_only()
        },
    ));
    let limited = render(Gpu::with_storage_binding_limit(
        &scene,
        spheres_only(),
        LIMIT,
    ));
    assert_logged_once(&[
        "SphereOccluder proxies: 5120 of 128 bytes each",
        "max_storage_buffer_binding_size (262144 bytes)",
        "the last 3072 are left out while it lasts",
    ]);
    assert!(
        limited
            .iter()
            .all(|v| v.is_finite() && (0.0..=1.0).contains(v))
    );
    // Fewer proxies occlude less, nowhere more; those kept still cast.
    let darker = limited
        .iter()
        .zip(&all)
        .map(|(l, a)| a - l)
        .fold(f32::MIN, f32::max);
    assert!(darker < 1e-3, "darker than all proxies by {darker}");
    let cast = limited
        .iter()
        .zip(&none)
        .map(|(l, n)| n - l)
        .fold(f32::MIN, f32::max);
    let missing = limited
        .iter()
        .zip(&all)
        .map(|(l, a)| l - a)
        .fold(f32::MIN, f32::max);
    assert!(cast > 0.05, "the proxies that fit cast {cast}");
    assert!(missing > 0.01, "nothing was left out ({missing})");
}

#[test]
fn voxel_triangles_past_the_binding_limit_are_left_out_with_a_warning() {
    // Two balls of 4608 triangles.
    let fine_ball = || Sphere::new(0.3).mesh().uv(64, 36);
    let scene = scenes::cube_on_plane()
        .with(fine_ball(), Transform::from_xyz(-1.0, 0.3, 0.9))
        .with(fine_ball(), Transform::from_xyz(1.0, 0.3, -0.9));
    let voxels_only = DynamicAo {
        technique: AoTechnique::Off,
        spheres: false,
        fields: false,
        ..plain_ao()
    };
    let volume = VoxelAoVolume {
        half_extents: Vec3::new(2.0, 1.0, 2.0),
        resolution: 32,
        ..default()
    };
    let mut gpu = Gpu::with_storage_binding_limit(&scene, voxels_only, LIMIT);
    gpu.app
        .world_mut()
        .spawn((Transform::from_xyz(0.0, 1.0, 0.0), volume));
    let limited = gpu.frame(4).visibility;
    assert_logged_once(&[
        "VoxelAoVolume triangles",
        "48 bytes each",
        "max_storage_buffer_binding_size (262144 bytes)",
    ]);
    assert!(
        limited
            .iter()
            .all(|v| v.is_finite() && (0.0..=1.0).contains(v))
    );
    assert!(
        limited.iter().any(|v| *v < 0.9),
        "the triangles that fit cast nothing"
    );
}

/// A field bakes at `resolution`³ cells of 112 bytes: 8³ take 57,344 bytes, 32³ 3,670,016 (the
/// limit is 262,144).
fn field(resolution: u32) -> AoField {
    AoField::Bake(BakeSettings {
        resolution,
        rays: 64,
        ..default()
    })
}

/// `gpu` once its fields are baked (without touching the disk).
fn baked(mut gpu: Gpu, fields: usize) -> Gpu {
    gpu.app
        .world_mut()
        .insert_resource(AoFieldCache::disabled());
    for _ in 0..400 {
        gpu.update(1);
        if gpu.app.world().resource::<Assets<AoFieldData>>().len() >= fields {
            return gpu;
        }
    }
    panic!("the fields were not baked in 400 frames");
}

#[test]
fn a_field_past_the_binding_limit_casts_nothing_with_a_warning() {
    let fields_only = DynamicAo {
        technique: AoTechnique::Off,
        spheres: false,
        voxels: false,
        ..plain_ao()
    };
    let boxes = scenes::cube_on_plane()
        .with(
            Cuboid::new(0.6, 0.6, 0.6),
            Transform::from_xyz(-1.2, 0.3, 0.8),
        )
        .with(
            Cuboid::new(0.6, 0.6, 0.6),
            Transform::from_xyz(1.2, 0.3, -0.6),
        );
    let mut both = boxes.clone();
    both.fields = vec![(2, field(8)), (3, field(32))];
    let mut small_only = boxes;
    small_only.fields = vec![(2, field(8))];

    let limited = baked(
        Gpu::with_storage_binding_limit(&both, fields_only.clone(), LIMIT),
        2,
    )
    .frame(4)
    .visibility;
    assert_logged_once(&[
        "AoField: a field of 32768 cells (3670016 bytes) does not fit",
        "max_storage_buffer_binding_size is 262144",
    ]);
    let expected = baked(Gpu::new(&small_only, fields_only), 1)
        .frame(4)
        .visibility;
    let largest = largest_difference(&limited, &expected);
    assert!(
        limited.iter().any(|v| *v < 0.9),
        "the field that fits casts nothing"
    );
    assert!(largest < 1e-4, "off the small field alone by {largest}");
}

//! Temporal stability with a still camera, ours against Bevy's SSAO in the same run: the flicker,
//! mean |AO_t − AO_{t−1}| over the pixels that show geometry, over consecutive frames once every
//! configuration has converged. Prints a Markdown table.
//!
//! `cargo bench --profile dev --bench temporal` (`-- --frames N` consecutive frames, default 16).
//! The scene is a floor, a box and a ball at 160×120. Bevy's temporal anti-aliasing is not in
//! this table: the crate's development build does not switch on Bevy's `bevy_anti_alias`. The
//! trail a moving occluder leaves is checked by `cargo test --test gpu temporal`.

#[path = "../examples/common/mod.rs"]
mod common;

use std::sync::{Arc, Mutex};

use bevy::app::PluginsState;
use bevy::camera::RenderTarget;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::TextureFormat;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::nd_buffer::NdTexel;

const SIZE: UVec2 = UVec2::new(160, 120);
/// Frames before measuring: longer than any history.
const CONVERGE_FRAMES: u32 = 40;

fn configurations() -> Vec<(&'static str, DynamicAo)> {
    let accumulated = |ao: DynamicAo| DynamicAo {
        temporal: AoTemporal::ON,
        ..ao
    };
    let near_field = DynamicAo {
        technique: AoTechnique::NearField,
        half_resolution: false,
        temporal: AoTemporal::OFF,
        ..default()
    };
    vec![
        ("ours, default (accumulated)", DynamicAo::default()),
        (
            "ours, default with accumulation off",
            DynamicAo {
                temporal: AoTemporal::OFF,
                ..default()
            },
        ),
        ("ours, near field 32 samples", near_field.clone()),
        (
            "ours, near field 8 samples, accumulated",
            accumulated(DynamicAo {
                near_field: AoPreset::Low.near_field(),
                ..near_field
            }),
        ),
        ("ours, preset low", DynamicAo::from_preset(AoPreset::Low)),
        (
            "ours, preset low, accumulated",
            accumulated(DynamicAo::from_preset(AoPreset::Low)),
        ),
        (
            "Bevy SSAO High",
            DynamicAo::default().with_technique(AoTechnique::BevySsao),
        ),
    ]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let frames = args
        .iter()
        .position(|a| a == "--frames")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(16u32)
        .max(2);
    let rows: Vec<(&str, (f64, usize))> = configurations()
        .into_iter()
        .map(|(name, ao)| (name, flicker(ao, frames)))
        .collect();
    println!(
        "\n{}×{}, still camera, mean |AO_t − AO_t−1| over geometry pixels, {frames} frames after {CONVERGE_FRAMES}:\n",
        SIZE.x, SIZE.y
    );
    println!("| configuration | flicker | frame pairs |");
    println!("|---|---:|---:|");
    for (name, (value, pairs)) in rows {
        println!("| {name} | {value:.5} | {pairs} |");
    }
}

/// Mean absolute change between consecutive frames, over the pixels that show geometry, and the
/// number of frame pairs it is over.
fn flicker(ao: DynamicAo, frames: u32) -> (f64, usize) {
    let mut app = App::new();
    app.add_plugins((common::headless_plugins(), DynamicAoPlugin));
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    let readback = spawn_scene(app.world_mut(), ao);
    for _ in 0..CONVERGE_FRAMES {
        app.update();
    }
    let mask = geometry_mask(&mut app, &readback);
    // One read-back per frame, in order, while the entity lives.
    let images: Arc<Mutex<Vec<Vec<f32>>>> = Arc::default();
    let sink = images.clone();
    let entity = app
        .world_mut()
        .spawn(Readback::texture(readback.visibility.clone()))
        .observe(move |done: On<ReadbackComplete>| {
            let data = common::unpad_f32(&done.data, SIZE.x as usize, SIZE.y as usize, 1);
            sink.lock().unwrap().push(data);
        })
        .id();
    for _ in 0..frames * 4 {
        app.update();
        if images.lock().unwrap().len() >= frames as usize {
            break;
        }
    }
    app.world_mut().despawn(entity);
    let images = images.lock().unwrap();
    let (mut sum, mut count) = (0.0f64, 0usize);
    for pair in images.windows(2) {
        for ((a, b), m) in pair[0].iter().zip(&pair[1]).zip(&mask) {
            if *m {
                sum += (a - b).abs() as f64;
                count += 1;
            }
        }
    }
    (sum / count.max(1) as f64, images.len().saturating_sub(1))
}

fn geometry_mask(app: &mut App, readback: &AoReadback) -> Vec<bool> {
    let slot: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
    let sink = slot.clone();
    let entity = app
        .world_mut()
        .spawn(Readback::texture(readback.front.clone()))
        .observe(move |done: On<ReadbackComplete>| {
            sink.lock()
                .unwrap()
                .get_or_insert_with(|| done.data.clone());
        })
        .id();
    for _ in 0..60 {
        app.update();
        if slot.lock().unwrap().is_some() {
            break;
        }
    }
    app.world_mut().despawn(entity);
    let data = slot
        .lock()
        .unwrap()
        .take()
        .expect("the ND-buffer read-back completes");
    common::unpad_f32(&data, SIZE.x as usize, SIZE.y as usize, 4)
        .chunks_exact(4)
        .map(|c| NdTexel::from_rgba([c[0], c[1], c[2], c[3]]).depth > 0.0)
        .collect()
}

fn spawn_scene(world: &mut World, ao: DynamicAo) -> AoReadback {
    let target = world
        .resource_mut::<Assets<Image>>()
        .add(Image::new_target_texture(
            SIZE.x,
            SIZE.y,
            TextureFormat::Rgba8UnormSrgb,
            None,
        ));
    let readback = AoReadback::new(&mut world.resource_mut::<Assets<Image>>(), SIZE);
    let bevy_ssao = ao.technique == AoTechnique::BevySsao;
    let mut camera = world.spawn((
        Camera3d::default(),
        RenderTarget::Image(target.into()),
        Transform::from_xyz(2.0, 1.8, 2.8).looking_at(Vec3::new(0.0, 0.35, 0.0), Vec3::Y),
        Msaa::Off,
        ao,
        readback.clone(),
    ));
    if bevy_ssao {
        camera.insert(ScreenSpaceAmbientOcclusion::default());
    }
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let floor = meshes.add(Plane3d::default().mesh().size(10.0, 10.0));
    let cube = meshes.add(Cuboid::new(1.0, 1.0, 1.0));
    let ball = meshes.add(Sphere::new(0.3).mesh().uv(32, 16));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    for (mesh, transform) in [
        (floor, Transform::IDENTITY),
        (cube, Transform::from_xyz(0.0, 0.5, 0.0)),
        (ball, Transform::from_xyz(0.9, 0.3, 0.7)),
    ] {
        world.spawn((Mesh3d(mesh), MeshMaterial3d(material.clone()), transform));
    }
    readback
}

//! Flicker with a still camera.

use std::sync::{Arc, Mutex};

use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};

use crate::Configuration;
use crate::scene::{self, SIZE};

/// Frames before measuring: longer than any history.
const CONVERGE_FRAMES: u32 = 40;

pub fn run(configurations: &[Configuration], frames: u32) {
    let rows: Vec<_> = configurations
        .iter()
        .map(|c| {
            eprintln!("still camera: {}", c.name);
            (c.name, flicker(c, frames))
        })
        .collect();
    println!(
        "\n{}×{}, still camera, mean |x_t − x_t−1| over geometry pixels, {frames} frames after \
         {CONVERGE_FRAMES}; x = AO (visibility) and the lit image's luminance:\n",
        SIZE.x, SIZE.y
    );
    println!("| configuration | AO flicker | lit-image flicker | frame pairs |");
    println!("|---|---:|---:|---:|");
    for (name, (ao, lit, pairs)) in rows {
        println!("| {name} | {ao:.5} | {lit:.5} | {pairs} |");
    }
}

/// Mean absolute change between consecutive frames of the AO and of the lit image's luminance,
/// over the pixels that show geometry, and the number of frame pairs.
fn flicker(configuration: &Configuration, frames: u32) -> (f64, f64, usize) {
    let mut app = scene::new_app();
    let world = app.world_mut();
    scene::spawn_floor_box_and_ball(world);
    let view = scene::spawn_camera(
        world,
        configuration,
        Transform::from_xyz(2.0, 1.8, 2.8).looking_at(Vec3::new(0.0, 0.35, 0.0), Vec3::Y),
    );
    scene::wait_until_written(&mut app, &view);
    for _ in 0..CONVERGE_FRAMES {
        app.update();
    }
    let mask = scene::geometry_mask(
        &scene::read_next(&mut app, std::slice::from_ref(&view.readback.front))[0],
    );
    // One read-back per frame and image, in order, while the entities live.
    type Frames = Arc<Mutex<Vec<Vec<f32>>>>;
    let (ao, lit): (Frames, Frames) = (Arc::default(), Arc::default());
    let mut entities = Vec::new();
    for (image, sink, decode) in [
        (
            view.readback.visibility.clone(),
            ao.clone(),
            scene::visibility as fn(&[u8]) -> Vec<f32>,
        ),
        (view.target.clone(), lit.clone(), scene::luminance),
    ] {
        let entity = app
            .world_mut()
            .spawn(Readback::texture(image))
            .observe(move |done: On<ReadbackComplete>| {
                sink.lock().unwrap().push(decode(&done.data));
            })
            .id();
        entities.push(entity);
    }
    for _ in 0..frames * 4 {
        app.update();
        if ao.lock().unwrap().len() >= frames as usize
            && lit.lock().unwrap().len() >= frames as usize
        {
            break;
        }
    }
    for entity in entities {
        app.world_mut().despawn(entity);
    }
    let mean_change = |images: &[Vec<f32>]| {
        let (mut sum, mut count) = (0.0f64, 0usize);
        for pair in images.windows(2) {
            for ((a, b), m) in pair[0].iter().zip(&pair[1]).zip(&mask) {
                if *m {
                    sum += (a - b).abs() as f64;
                    count += 1;
                }
            }
        }
        sum / count.max(1) as f64
    };
    let (ao, lit) = (ao.lock().unwrap(), lit.lock().unwrap());
    let pairs = ao.len().min(lit.len()).saturating_sub(1);
    (
        mean_change(&ao[..pairs + 1]),
        mean_change(&lit[..pairs + 1]),
        pairs,
    )
}

//! Temporal accumulation: with a still camera the occlusion converges toward the CPU evaluation
//! of the same formula at a full budget, and an occluder that moves away leaves no trail.

use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    metrics::rmse,
    near_field::{NearFieldInputs, near_field_occlusion},
};

use crate::harness::{Frame, Gpu, difference_stats};
use crate::scenes;

/// The near field with few samples and no blur: the noise accumulation has to remove.
fn noisy(temporal: bool) -> DynamicAo {
    DynamicAo {
        near_field: NearFieldParams {
            max_samples: 4,
            min_samples: 4,
            back_layer: true,
        },
        blur: AoBlur::OFF,
        temporal: AoTemporal {
            enabled: temporal,
            ..AoTemporal::ON
        },
        ..default()
    }
}

/// The CPU formula on the frame's own ND-buffer with 256 samples per pixel: what averaging many
/// rotated 4-sample patterns estimates.
fn full_budget(frame: &Frame, ao: &DynamicAo) -> Vec<f32> {
    let inputs = NearFieldInputs {
        radius: ao.radius,
        intensity: ao.intensity,
        max_samples: 256,
        min_samples: 256,
        back_layer: true,
    };
    near_field_occlusion(&frame.nd, &frame.view, &inputs)
        .into_iter()
        .map(|o| 1.0 - o)
        .collect()
}

#[test]
fn a_still_camera_converges_toward_the_full_budget() {
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::new(&scene, noisy(false));
    let single = gpu.frame(4);
    let mask = single.geometry_mask();
    let reference = full_budget(&single, &noisy(false));
    let error_single = rmse(&single.visibility, &reference, Some(&mask));

    gpu.set_ao(|ao| *ao = noisy(true));
    let mut errors = Vec::new();
    for frames in [1, 7, 24] {
        let frame = gpu.frame(frames);
        errors.push(rmse(&frame.visibility, &reference, Some(&mask)));
    }
    println!(
        "RMSE against the 256-sample formula: one frame {error_single:.4}, accumulated {errors:?}"
    );
    // Measured: one frame 0.081, then 0.052, 0.031, 0.031.
    assert!(errors[1] < 0.75 * errors[0], "the error falls: {errors:?}");
    let converged = *errors.last().unwrap();
    assert!(
        converged < 1.05 * errors[1],
        "the error stays down once converged: {errors:?}"
    );
    assert!(
        converged < 0.45 * error_single,
        "accumulated {converged:.4} vs one frame {error_single:.4}"
    );
}

#[test]
fn an_occluder_that_moves_away_leaves_no_trail() {
    let scene = scenes::cube_on_plane();
    let moved = Vec3::new(-1.6, 0.5, -1.2);
    // Ground truth of the moved scene: the same settings accumulated with the cube already there.
    let mut after = scenes::cube_on_plane();
    after.meshes[1].1.translation = moved;
    let ao = DynamicAo {
        temporal: AoTemporal::ON,
        ..default()
    };
    let settled = Gpu::new(&after, ao.clone()).frame(24);

    let mut gpu = Gpu::new(&scene, ao);
    let before = gpu.frame(24);
    let world = gpu.app.world_mut();
    let mut cubes = world.query::<(&mut Transform, &Mesh3d)>();
    for (mut transform, _) in cubes.iter_mut(world) {
        if transform.translation == Vec3::new(0.0, 0.5, 0.0) {
            transform.translation = moved;
        }
    }
    // Two frames, plus the few the read-back takes.
    let moved_frame = gpu.frame(2);
    let mask = settled.geometry_mask();
    let trail = |frame: &Frame| {
        frame
            .visibility
            .iter()
            .zip(&settled.visibility)
            .zip(&mask)
            .filter(|((a, b), m)| **m && (*a - *b).abs() > 0.1)
            .count()
    };
    let (was, left) = (trail(&before), trail(&moved_frame));
    println!("pixels off by > 0.1 from the settled image: before the move {was}, after {left}");
    assert!(was > 500, "the move must change the image ({was} pixels)");
    assert!(
        left * 50 < was,
        "a trail of {left} pixels is left (of {was} that changed)"
    );
}

#[test]
fn switching_accumulation_off_leaves_no_state_behind() {
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::new(&scene, noisy(false));
    // Four frames, as every test here: Bevy's SSAO may stand in for the first ones.
    let plain = gpu.frame(4);
    gpu.set_ao(|ao| *ao = noisy(true));
    let accumulated = gpu.frame(12);
    gpu.set_ao(|ao| *ao = noisy(false));
    let again = gpu.frame(4);
    let mask = plain.geometry_mask();
    assert!(
        rmse(&accumulated.visibility, &plain.visibility, Some(&mask)) > 0.01,
        "accumulation changes the image"
    );
    // The hand-off texture may round differently by a step between runs; nothing more.
    let (mean, p99) = difference_stats(&again.visibility, &plain.visibility, &mask);
    assert!(
        mean < 0.001 && p99 < 0.01,
        "off again, the image is the plain one: mean |diff| {mean}, 99th percentile {p99}"
    );
}

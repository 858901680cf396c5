//! Horizon-based AO against the CPU evaluation of the same steps, and against ground truth.

use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    horizon::{HorizonInputs, horizon_occlusion},
    metrics::{mean_bias, rmse},
};

use crate::harness::{Gpu, difference_stats, plain_ao};
use crate::scenes;

fn inputs(ao: &DynamicAo) -> HorizonInputs {
    let h = ao.horizon.sanitized();
    HorizonInputs {
        radius: ao.radius,
        intensity: ao.intensity,
        directions: h.directions,
        steps: h.steps,
        angle_bias: h.angle_bias,
        attenuation: h.attenuation,
        contrast: h.contrast,
        mode: h.mode.shader_index(),
    }
}

#[test]
fn horizon_matches_the_cpu_evaluation_and_tracks_ground_truth() {
    let radius = 0.73;
    for ((name, scene), mode) in scenes::all()
        .into_iter()
        .flat_map(|s| HorizonMode::ALL.map(|m| (s.clone(), m)))
    {
        let mut ao = plain_ao()
            .with_technique(AoTechnique::Horizon)
            .with_radius(radius)
            .with_blur(AoBlur::OFF);
        ao.horizon.mode = mode;
        let mut gpu = Gpu::new(&scene, ao.clone());
        let frame = gpu.frame(4);
        let mask = frame.geometry_mask();
        let cpu: Vec<f32> = horizon_occlusion(&frame.nd, &frame.view, &inputs(&ao))
            .into_iter()
            .map(|o| 1.0 - o)
            .collect();
        let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
        let truth = frame.ground_truth(&scene.bvh(), radius);
        let raw = rmse(&frame.visibility, &truth, Some(&mask));
        gpu.set_ao(|ao| ao.blur = AoBlur::default());
        let blurred = gpu.frame(3);
        let filtered = rmse(&blurred.visibility, &truth, Some(&mask));
        let bias = mean_bias(&blurred.visibility, &truth, Some(&mask));
        println!(
            "{name}, {mode:?} mode: horizon GPU vs CPU mean |diff| {mean:.5}, 99th percentile {p99:.5}; \
             RMSE vs ground truth {raw:.4} unfiltered, {filtered:.4} blurred (bias {bias:+.4})"
        );
        assert!(mean < 0.004, "{name}: mean |GPU − CPU| = {mean}");
        assert!(p99 < 0.03, "{name}: 99th percentile |GPU − CPU| = {p99}");
        assert!(
            frame
                .visibility
                .iter()
                .zip(&mask)
                .any(|(v, m)| *m && *v < 0.8),
            "{name}: horizon AO found no crease"
        );
        // Single-layer horizon AO misses what hides behind silhouettes; bounded like Bevy's SSAO.
        assert!(
            filtered < 0.16,
            "{name}, {mode:?} mode: horizon RMSE {filtered}"
        );
    }
}

//! Half-resolution AO with joint bilateral upsampling: the GPU against the CPU evaluation of the
//! same steps, and against full resolution.

use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    filter::{cross_bilateral_blur, joint_bilateral_upsample},
    metrics::rmse,
    near_field::{NearFieldInputs, pixel_occlusion},
};

use crate::harness::{Gpu, HEIGHT, WIDTH, difference_stats, plain_ao};
use crate::scenes;

#[test]
fn half_resolution_matches_the_cpu_and_stays_close_to_full_resolution() {
    let radius = 0.73;
    for (name, scene) in scenes::all() {
        let full_ao = plain_ao().with_radius(radius);
        let half_ao = DynamicAo {
            half_resolution: true,
            ..full_ao.clone()
        };
        let mut gpu = Gpu::new(&scene, full_ao);
        let full = gpu.frame(4);
        gpu.set_ao(|ao| *ao = half_ao.clone());
        let half = gpu.frame(4);
        let mask = half.geometry_mask();

        // The same steps on the CPU: the formula at every other pixel, the upsampling, the blur.
        let params = half_ao.near_field.sanitized();
        let inputs = NearFieldInputs {
            radius,
            intensity: 1.0,
            max_samples: params.max_samples,
            min_samples: params.min_samples,
            back_layer: params.back_layer,
        };
        let (lw, lh) = (WIDTH.div_ceil(2), HEIGHT.div_ceil(2));
        let low: Vec<f32> = (0..lw * lh)
            .map(|i| {
                pixel_occlusion(
                    &half.nd,
                    &half.view,
                    &inputs,
                    (2 * (i % lw)) as i32,
                    (2 * (i / lw)) as i32,
                )
            })
            .collect();
        let up = joint_bilateral_upsample(&low, &half.nd, &half.view, radius);
        let cpu: Vec<f32> = cross_bilateral_blur(
            &up,
            &half.nd,
            &half.view,
            half_ao.blur.radius,
            half_ao.blur.sharpness,
        )
        .into_iter()
        .map(|o| 1.0 - o)
        .collect();
        let (mean, p99) = difference_stats(&half.visibility, &cpu, &mask);
        let against_full = rmse(&half.visibility, &full.visibility, Some(&mask));
        let truth = half.ground_truth(&scene.bvh(), radius);
        println!(
            "{name}: half resolution GPU vs CPU mean |diff| {mean:.5}, 99th percentile {p99:.5}; \
             RMSE against full resolution {against_full:.4}; against ground truth {:.4} (full \
             resolution {:.4})",
            rmse(&half.visibility, &truth, Some(&mask)),
            rmse(&full.visibility, &truth, Some(&mask)),
        );
        assert!(mean < 0.004, "{name}: mean |GPU − CPU| = {mean}");
        assert!(p99 < 0.03, "{name}: 99th percentile |GPU − CPU| = {p99}");
        // A quarter of the samples, smoothed back: close to, not equal to, full resolution.
        assert!(
            against_full < 0.05,
            "{name}: half resolution drifts {against_full} from full"
        );
    }
}

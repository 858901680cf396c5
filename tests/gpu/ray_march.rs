//! The ray-marched reference against its CPU twin, and its error against ground truth as the
//! ray count grows, through perspective and orthographic cameras.

use bevy::camera::ScalingMode;
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    metrics::rmse,
    ray_march::{RayMarchInputs, ray_march_occlusion},
};

use crate::harness::{Gpu, difference_stats, plain_ao};
use crate::scenes;

#[test]
fn ray_march_matches_the_cpu_and_converges_with_more_rays() {
    let radius = 0.73;
    let scene = scenes::ball_near_wall();
    let with = |directions, elevations| {
        plain_ao()
            .with_technique(AoTechnique::RayMarch)
            .with_radius(radius)
            .with_blur(AoBlur::OFF)
            .with_ray_march(RayMarchParams {
                directions,
                elevations,
                steps: 8,
            })
    };
    let mut gpu = Gpu::new(&scene, with(2, 1));
    let first = gpu.frame(4);
    let truth = first.ground_truth(&scene.bvh(), radius);
    let mask = first.geometry_mask();

    // The same rays on the CPU, from the read-back ND-buffer.
    let inputs = RayMarchInputs {
        radius,
        intensity: 1.0,
        directions: 2,
        elevations: 1,
        steps: 8,
    };
    let cpu: Vec<f32> = ray_march_occlusion(&first.nd, &first.view, &inputs)
        .into_iter()
        .map(|o| 1.0 - o)
        .collect();
    let (mean, p99) = difference_stats(&first.visibility, &cpu, &mask);
    println!("ray march GPU vs CPU: mean |diff| {mean:.5}, 99th percentile {p99:.5}");
    // A ray whose step lands on a pixel edge can flip on one side only: one ray of two is 0.5.
    assert!(mean < 0.01, "mean |GPU − CPU| = {mean}");
    assert!(p99 <= 0.5 + 1e-3, "99th percentile |GPU − CPU| = {p99}");

    let mut errors = vec![rmse(&first.visibility, &truth, Some(&mask))];
    for (directions, rays) in [(4, 2), (8, 4)] {
        gpu.set_ao(|ao| *ao = with(directions, rays));
        let frame = gpu.frame(3);
        errors.push(rmse(&frame.visibility, &truth, Some(&mask)));
    }
    println!("ray march RMSE vs ground truth at 2, 8, 32 rays per pixel: {errors:?}");
    assert!(
        errors.windows(2).all(|w| w[1] < w[0]),
        "error should shrink with more rays: {errors:?}"
    );
    assert!(errors[2] < 0.15, "32 rays per pixel: RMSE {}", errors[2]);
}

#[test]
fn ray_march_error_on_every_scene() {
    let radius = 0.73;
    for (name, scene) in scenes::all() {
        let ao = plain_ao()
            .with_technique(AoTechnique::RayMarch)
            .with_radius(radius);
        let mut gpu = Gpu::new(&scene, ao);
        let frame = gpu.frame(4);
        let truth = frame.ground_truth(&scene.bvh(), radius);
        let error = rmse(&frame.visibility, &truth, Some(&frame.geometry_mask()));
        println!("{name}: ray march (8 × 4 rays × 8 steps, blurred) RMSE {error:.4}");
        assert!(error < 0.12, "{name}: ray-march RMSE {error}");
    }
}

/// An orthographic camera over the same view (3.5 m tall): the ray march matches its CPU twin as
/// through a perspective camera, and the default, accumulated, is as close to the truth.
#[test]
fn the_ray_march_works_on_an_orthographic_camera() {
    let radius = 0.73;
    let orthographic = Projection::Orthographic(OrthographicProjection {
        scaling_mode: ScalingMode::FixedVertical {
            viewport_height: 3.5,
        },
        ..OrthographicProjection::default_3d()
    });
    let inputs = RayMarchInputs {
        radius,
        intensity: 1.0,
        directions: 8,
        elevations: 4,
        steps: 8,
    };
    for (name, scene) in scenes::all() {
        let ao = plain_ao()
            .with_technique(AoTechnique::RayMarch)
            .with_radius(radius)
            .with_blur(AoBlur::OFF);
        let mut gpu = Gpu::new(&scene, ao);
        let camera = gpu.camera;
        gpu.app
            .world_mut()
            .entity_mut(camera)
            .insert(orthographic.clone());
        let frame = gpu.frame(4);
        let cpu: Vec<f32> = ray_march_occlusion(&frame.nd, &frame.view, &inputs)
            .into_iter()
            .map(|o| 1.0 - o)
            .collect();
        let (mean, p99) = difference_stats(&frame.visibility, &cpu, &frame.geometry_mask());
        // Measured: 0 on all three scenes.
        assert!(mean < 0.01, "{name}: mean |GPU − CPU| = {mean}");
        assert!(
            p99 <= 0.5 + 1e-3,
            "{name}: 99th percentile |GPU − CPU| = {p99}"
        );
        drop(gpu);

        let mut gpu = Gpu::new(&scene, DynamicAo::default().with_radius(radius));
        let mut errors = Vec::new();
        for projection in [None, Some(orthographic.clone())] {
            if let Some(projection) = projection {
                let camera = gpu.camera;
                gpu.app.world_mut().entity_mut(camera).insert(projection);
            }
            let frame = gpu.frame(24);
            let truth = frame.ground_truth(&scene.bvh(), radius);
            errors.push(rmse(
                &frame.visibility,
                &truth,
                Some(&frame.geometry_mask()),
            ));
        }
        println!(
            "{name}: the default converged, RMSE perspective {:.4}, orthographic {:.4}",
            errors[0], errors[1]
        );
        // Measured: 0.0143 / 0.0107, 0.0308 / 0.0289, 0.0274 / 0.0247.
        assert!(
            errors[1] <= errors[0] + 0.002,
            "{name}: orthographic RMSE {} against perspective {}",
            errors[1],
            errors[0]
        );
    }
}

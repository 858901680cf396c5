//! What limits the default on a finely detailed model: DamagedHelmet (from `../shared/assets`) on
//! a floor, against the CPU ray tracer, split into the helmet's pixels (those above the floor) and
//! the rest. Skipped, with a message, where the folder is absent.

use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::metrics::{high_frequency_error, rmse};

use crate::far_scenes::{self, FarRun};
use crate::harness::{HEIGHT, WIDTH};
use crate::near_field::BEVY_SSAO_RADIUS;

/// One frame of many rays at full resolution without blur: the ray march's own answer for
/// `steps` steps per ray, free of noise, resolution and filtering.
fn many_rays(steps: u32) -> DynamicAo {
    DynamicAo {
        ray_march: RayMarchParams {
            directions: 16,
            elevations: 8,
            steps,
        },
        half_resolution: false,
        blur: AoBlur::OFF,
        temporal: AoTemporal::OFF,
        ..DynamicAo::default()
    }
}

/// The steps per ray, not the accumulation or the blur, are what the default's error on
/// DamagedHelmet's panel lines and small parts comes from: more steps bring the ray march closer
/// to the truth there. Prints the table of BENCHMARKS.md ("What limits it").
#[test]
fn steps_limit_the_default_on_fine_detail() {
    let Some(shared) = crate::models::shared_assets() else {
        return;
    };
    let scene = far_scenes::third_party()
        .into_iter()
        .find(|s| s.name == "DamagedHelmet on floor")
        .expect("the third-party scenes include DamagedHelmet on a floor");
    let mut run = FarRun::new(&scene, shared.to_str());
    let bvh = run.bvh();
    let configurations = [
        ("the default", DynamicAo::default()),
        (
            "Bevy's SSAO High",
            DynamicAo::default().with_technique(AoTechnique::BevySsao),
        ),
        (
            "the default without the blur",
            DynamicAo::default().with_blur(AoBlur::OFF),
        ),
        (
            "the default with 2 rays × 16 steps per frame",
            DynamicAo::default().with_ray_march(RayMarchParams {
                steps: 16,
                ..RayMarchParams::default()
            }),
        ),
        ("one frame of 16 × 8 rays, 8 steps", many_rays(8)),
        ("one frame of 16 × 8 rays, 16 steps", many_rays(16)),
        ("one frame of 16 × 8 rays, 32 steps", many_rays(32)),
        ("one frame of 16 × 8 rays, 64 steps", many_rays(64)),
        (
            "the default at full resolution",
            DynamicAo {
                half_resolution: false,
                ..DynamicAo::default()
            },
        ),
    ];
    let mut truth = None;
    let mut errors = Vec::new();
    println!("| configuration | RMSE | helmet pixels | mean over truth, helmet | high-frequency |");
    for (name, ao) in configurations {
        run.image_space = ao;
        let frame = run.render(true, None, FarFieldBlend::CountOnce, BEVY_SSAO_RADIUS);
        let truth = truth.get_or_insert_with(|| frame.ground_truth(&bvh, BEVY_SSAO_RADIUS));
        let mask = frame.geometry_mask();
        let helmet: Vec<bool> = (0..mask.len())
            .map(|i| frame.position(i).is_some_and(|p| p.y > 0.01))
            .collect();
        let (over, count) = (0..helmet.len())
            .filter(|&i| helmet[i])
            .fold((0.0, 0.0), |(sum, n), i| {
                (sum + frame.visibility[i] - truth[i], n + 1.0)
            });
        let error = rmse(&frame.visibility, truth, Some(&mask));
        let helmet_error = rmse(&frame.visibility, truth, Some(&helmet));
        let detail = high_frequency_error(&frame.visibility, truth, WIDTH, HEIGHT, Some(&mask));
        println!(
            "| {name} | {error:.3} | {helmet_error:.3} | {:+.3} | {detail:.3} |",
            over / count
        );
        errors.push(error);
    }
    let steps = &errors[4..8];
    // Measured: 0.047 / 0.039 / 0.035 / 0.033 at 8 / 16 / 32 / 64 steps.
    assert!(
        steps[1] < 0.92 * steps[0] && steps[2] < steps[1] && steps[3] < steps[2] + 0.002,
        "more steps per ray should bring the ray march closer to the truth: {steps:?}"
    );
    // Measured: 2 × 16 steps 0.053 against the default's 2 × 6 steps 0.063.
    assert!(
        errors[3] < 0.95 * errors[0],
        "16 steps per ray should lower the default's error: {:.4} against {:.4}",
        errors[3],
        errors[0]
    );
}

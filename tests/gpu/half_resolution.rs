//! Half-resolution AO with joint bilateral upsampling: the GPU against the CPU evaluation of the
//! same steps, and against full resolution.

use bevy::math::UVec2;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    filter::{cross_bilateral_blur, joint_bilateral_upsample},
    metrics::rmse,
    near_field::{NearFieldInputs, pixel_occlusion},
};

use crate::harness::{Frame, Gpu, HEIGHT, WIDTH, difference_stats, largest_difference, plain_ao};
use crate::scenes;

/// The same steps on the CPU as the GPU takes them for `frame`: the near-field formula at every
/// other pixel, the joint bilateral upsampling, the blur; visibility.
fn cpu_half_resolution(frame: &Frame, ao: &DynamicAo, radius: f32) -> Vec<f32> {
    let params = ao.near_field.sanitized();
    let inputs = NearFieldInputs {
        radius,
        intensity: 1.0,
        max_samples: params.max_samples,
        min_samples: params.min_samples,
        back_layer: params.back_layer,
    };
    let (lw, lh) = (frame.nd.width.div_ceil(2), frame.nd.height.div_ceil(2));
    let low: Vec<f32> = (0..lw * lh)
        .map(|i| {
            pixel_occlusion(
                &frame.nd,
                &frame.view,
                &inputs,
                (2 * (i % lw)) as i32,
                (2 * (i / lw)) as i32,
            )
        })
        .collect();
    let up = joint_bilateral_upsample(&low, &frame.nd, &frame.view);
    cross_bilateral_blur(&up, &frame.nd, &frame.view, &ao.blur)
        .into_iter()
        .map(|o| 1.0 - o)
        .collect()
}

#[test]
fn half_resolution_matches_the_cpu_and_stays_close_to_full_resolution() {
    let radius = 0.73;
    for (name, scene) in scenes::all() {
        let full_ao = plain_ao().with_radius(radius);
        let half_ao = DynamicAo {
            half_resolution: true,
            small_viewport_pixels: 0,
            ..full_ao.clone()
        };
        let mut gpu = Gpu::new(&scene, full_ao);
        let full = gpu.frame(4);
        gpu.set_ao(|ao| *ao = half_ao.clone());
        let half = gpu.frame(4);
        let mask = half.geometry_mask();

        let cpu = cpu_half_resolution(&half, &half_ao, radius);
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
        // Measured 0.00012–0.00013 and 0.00048–0.00049 (float rounding of the same steps).
        assert!(mean < 0.0003, "{name}: mean |GPU − CPU| = {mean}");
        assert!(p99 < 0.001, "{name}: 99th percentile |GPU − CPU| = {p99}");
        // A quarter of the samples, smoothed back: close to, not equal to, full resolution.
        assert!(
            against_full < 0.05,
            "{name}: half resolution drifts {against_full} from full"
        );
    }
}

#[test]
fn half_resolution_matches_the_cpu_on_an_odd_sized_view() {
    // 159 × 119: the last column and row of full-resolution pixels have no right or lower
    // neighbour in their 2 × 2 quad, and the half-resolution buffer is 80 × 60.
    let radius = 0.73;
    let size = UVec2::new(WIDTH - 1, HEIGHT - 1);
    let ao = DynamicAo {
        half_resolution: true,
        small_viewport_pixels: 0,
        ..plain_ao().with_radius(radius)
    };
    for (name, scene) in scenes::all() {
        let mut gpu = Gpu::new(&scene, plain_ao());
        let (camera, readback) = gpu.add_camera_of_size(scene.camera, ao.clone(), size);
        let mut frame = gpu.frame_of(camera, &readback, 4);
        // On a busy machine the added camera's first frames can come before its meshes are
        // drawn: wait for them rather than compare nothing.
        for _ in 0..10 {
            if frame.geometry_mask().iter().any(|shown| *shown) {
                break;
            }
            frame = gpu.frame_of(camera, &readback, 4);
        }
        assert_eq!((frame.nd.width, frame.nd.height), (size.x, size.y));
        let mask = frame.geometry_mask();
        let cpu = cpu_half_resolution(&frame, &ao, radius);
        let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
        let last_column: Vec<usize> = (0..size.y as usize)
            .map(|y| y * size.x as usize + size.x as usize - 1)
            .filter(|i| mask[*i])
            .collect();
        let edge = last_column
            .iter()
            .map(|i| (frame.visibility[*i] - cpu[*i]).abs())
            .fold(0.0f32, f32::max);
        println!(
            "{name}, {}×{}: GPU vs CPU mean |diff| {mean:.5}, 99th percentile {p99:.5}, largest \
             on the last column {edge:.5}",
            size.x, size.y
        );
        assert!(
            !last_column.is_empty(),
            "{name}: the last column shows no geometry"
        );
        assert!(mean < 0.0003, "{name}: mean |GPU − CPU| = {mean}");
        assert!(p99 < 0.001, "{name}: 99th percentile |GPU − CPU| = {p99}");
        // Measured 0 to 0.00049.
        assert!(edge < 0.002, "{name}: last column |GPU − CPU| up to {edge}");
    }
}

/// Set up as a user sets it up (third-party models on a floor, every mesh an occluder, two radii),
/// with no far-field term selected, the last filter pass writes the visibility Bevy's PBR reads
/// itself: the upsampling where the blur is off, the blur's Y pass where it is on. Both against
/// the CPU evaluation of the same steps. Skipped, with a message, where `../shared/assets` is
/// absent.
#[test]
fn the_last_filter_pass_writes_the_cpu_visibility_on_third_party_models() {
    let Some(shared) = crate::models::shared_assets() else {
        return;
    };
    let wanted = ["DamagedHelmet on floor", "CesiumMan on floor"];
    for scene in crate::far_scenes::third_party() {
        if !wanted.contains(&scene.name) {
            continue;
        }
        let mut run = crate::far_scenes::FarRun::new(&scene, shared.to_str());
        for (radius, blur) in [(0.75, 0), (0.75, 4), (2.0, 0), (2.0, 4)] {
            let ao = DynamicAo {
                half_resolution: true,
                small_viewport_pixels: 0,
                blur: AoBlur {
                    radius: blur,
                    ..AoBlur::default()
                },
                ..plain_ao().with_radius(radius)
            };
            run.image_space = ao.clone();
            let frame = run.render(true, None, FarFieldBlend::CountOnce, radius);
            let mask = frame.geometry_mask();
            let cpu = cpu_half_resolution(&frame, &ao, radius);
            let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
            println!(
                "{}, R = {radius} m, blur {blur}: GPU vs CPU mean |diff| {mean:.5}, 99th \
                 percentile {p99:.5}",
                scene.name
            );
            // Measured: mean 0.00003–0.00020, 99th percentile 0.00045–0.00049 (one step of
            // Bevy's half-float texture near 1 is 0.00049).
            assert!(
                mean < 0.0003,
                "{}, R = {radius}, blur {blur}: mean |GPU − CPU| = {mean}",
                scene.name
            );
            assert!(
                p99 < 0.0006,
                "{}, R = {radius}, blur {blur}: 99th percentile |GPU − CPU| = {p99}",
                scene.name
            );
        }
    }
}

/// Whether each of the plugin's pass spans named in `passes` reported over the last 8 frames.
fn passes_running(gpu: &mut Gpu, passes: &[&str]) -> Vec<bool> {
    gpu.update(8);
    crate::harness::pass_spans(gpu, true);
    gpu.update(8);
    let spans = crate::harness::pass_spans(gpu, false);
    passes
        .iter()
        .map(|pass| {
            spans
                .iter()
                .any(|(path, n)| path.contains(&format!("dynamic_ao_{pass}")) && *n > 0)
        })
        .collect()
}

/// At the harness's 160 × 120, under `DynamicAo::small_viewport_pixels`, the default runs at full
/// resolution with the blur of `SMALL_VIEWPORT_BLUR_RADIUS` under accumulation and no upsampling;
/// with the rule off (0) at half resolution, upsampled and not blurred; asked for full resolution
/// outright, without the blur (the user's `AoBlur::accumulated_radius` of 0 stands). The limit
/// counts the view's own pixels: a view of exactly that many runs at full resolution, one pixel
/// more at half. Told by which passes report GPU time spans.
#[test]
fn a_small_viewport_runs_at_full_resolution_with_a_blur_of_one_pixel() {
    use bevy_dynamic_ao::settings::DEFAULT_SMALL_VIEWPORT_PIXELS;
    const { assert!(WIDTH * HEIGHT <= DEFAULT_SMALL_VIEWPORT_PIXELS) };
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::with_render_diagnostics(&scene, DynamicAo::default());
    let passes = ["ray_march", "upsample", "blur", "temporal"];
    let cases = [
        (
            "the default",
            DynamicAo::default(),
            [true, false, true, true],
        ),
        (
            "half resolution at every size",
            DynamicAo {
                small_viewport_pixels: 0,
                ..DynamicAo::default()
            },
            [true, true, false, true],
        ),
        (
            "a limit of exactly this view's pixels",
            DynamicAo {
                small_viewport_pixels: WIDTH * HEIGHT,
                ..DynamicAo::default()
            },
            [true, false, true, true],
        ),
        (
            "a limit one pixel under this view's",
            DynamicAo {
                small_viewport_pixels: WIDTH * HEIGHT - 1,
                ..DynamicAo::default()
            },
            [true, true, false, true],
        ),
        (
            "full resolution asked for",
            DynamicAo {
                half_resolution: false,
                ..DynamicAo::default()
            },
            [true, false, false, true],
        ),
    ];
    for (name, ao, expected) in cases {
        gpu.set_ao(|current| *current = ao);
        let running = passes_running(&mut gpu, &passes);
        assert_eq!(
            running,
            expected.to_vec(),
            "{name}: which of {passes:?} run"
        );
    }
}

/// A view that switches between full and half resolution at runtime (here by
/// `DynamicAo::small_viewport_pixels`; a window resized across it does the same) renders what a
/// fresh app with the new settings renders, with nothing of the other resolution left: one
/// fixed pattern of rays (accumulation off), so the frames must agree to the last bits.
#[test]
fn switching_resolution_at_runtime_leaves_nothing_stale() {
    let scene = scenes::cube_on_plane();
    let full = DynamicAo {
        temporal: AoTemporal::OFF,
        ..DynamicAo::default()
    };
    let half = DynamicAo {
        small_viewport_pixels: 0,
        ..full.clone()
    };
    let fresh = |ao: &DynamicAo| Gpu::new(&scene, ao.clone()).frame(4).visibility;
    let (full_image, half_image) = (fresh(&full), fresh(&half));
    let apart = largest_difference(&full_image, &half_image);
    assert!(
        apart > 0.05,
        "the two resolutions differ by {apart} at most"
    );
    let mut gpu = Gpu::new(&scene, full.clone());
    for (name, ao, expected) in [
        ("to half", &half, &half_image),
        ("back to full", &full, &full_image),
        ("to half again", &half, &half_image),
    ] {
        gpu.set_ao(|current| *current = ao.clone());
        let difference = largest_difference(&gpu.frame(4).visibility, expected);
        assert!(
            difference < 1e-4,
            "{name}: {difference} from a fresh app's frame"
        );
    }
}

//! Every preset on the ground-truth scenes, as the README's preset table gives it: the error
//! once converged with a still camera, its high-frequency part, and the frames it takes to get
//! there, next to Bevy's SSAO High. The default must stay within the bounds the README states:
//! at most a third of Bevy's RMSE (a quarter is asserted), and no more high-frequency error;
//! on third-party models, no more high-frequency error either.

use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::metrics::{high_frequency_error, rmse};

use crate::far_scenes::{self, FarRun};
use crate::far_terms::FarTerm;
use crate::harness::{self, Frame, Gpu, HEIGHT, WIDTH};
use crate::near_field::BEVY_SSAO_RADIUS;
use crate::scenes;

/// Frames a capture counts as converged: twice the frames the default history spans.
fn converged_frames() -> u32 {
    harness::converged_frames(&DynamicAo::default())
}
/// A preset has converged once its RMSE is within this share of the converged one.
const WITHIN: f32 = 1.1;
/// After 16 frames (8 samples a texel under the ray march's checkerboard) the default's RMSE is
/// within this share of its converged one: measured 1.11–1.31 at full resolution, which the
/// default runs at the tests' size (cube on plane the highest); at half resolution 1.19–1.47
/// since the rays' last step lies at R, which lowered the converged error more than the early
/// one (before the checkerboard, after 8 frames of 8 samples: 1.11–1.32; the clamp keeps
/// improving the history past that on a still camera).
const DEFAULT_AFTER_16: f32 = 1.4;

/// The frame `frames` frames after the history was dropped. The read-back copies the frame
/// rendered after it is asked for, so `frames - 1` are rendered before.
fn after_reset(gpu: &mut Gpu, preset: AoPreset, frames: u32) -> Frame {
    gpu.set_ao(|ao| {
        *ao = DynamicAo::from_preset(preset).with_radius(BEVY_SSAO_RADIUS);
        ao.temporal.reset = true;
    });
    gpu.frame(frames - 1)
}

#[test]
fn presets_converge_and_the_default_beats_bevy_ssao() {
    let mut table = Vec::new();
    for (name, scene) in scenes::all() {
        let bvh = scene.bvh();
        let mut gpu = Gpu::new(&scene, DynamicAo::default().with_radius(BEVY_SSAO_RADIUS));
        let first = gpu.frame(4);
        let truth = first.ground_truth(&bvh, BEVY_SSAO_RADIUS);
        let mask = first.geometry_mask();
        let (w, h) = (first.nd.width, first.nd.height);
        let errors = |frame: &Frame| {
            (
                rmse(&frame.visibility, &truth, Some(&mask)),
                high_frequency_error(&frame.visibility, &truth, w, h, Some(&mask)),
            )
        };
        gpu.set_ao(|ao| ao.technique = AoTechnique::BevySsao);
        let bevy = errors(&gpu.frame(4));
        println!(
            "{name}: Bevy SSAO High RMSE {:.4}, high-frequency {:.4}",
            bevy.0, bevy.1
        );
        for preset in AoPreset::ALL {
            let converged_frame = after_reset(&mut gpu, preset, converged_frames());
            let converged = errors(&converged_frame);
            let mut curve = Vec::new();
            let mut to_converge = None;
            let mut after_16 = f32::NAN;
            for frames in [1, 2, 4, 8, 16, 32, 48] {
                let frame = after_reset(&mut gpu, preset, frames);
                let error = errors(&frame).0;
                // What is left of the noise: the distance to the converged image.
                let residual = rmse(&frame.visibility, &converged_frame.visibility, Some(&mask));
                curve.push((frames, error, residual));
                if frames == 16 {
                    after_16 = error;
                }
                if to_converge.is_none() && error <= WITHIN * converged.0 {
                    to_converge = Some(frames);
                }
            }
            println!(
                "{name}: preset {}: converged RMSE {:.4}, high-frequency {:.4}; (frames, RMSE, \
                 distance to converged) {curve:?}",
                preset.name(),
                converged.0,
                converged.1
            );
            table.push((name, preset, converged, to_converge, after_16, bevy));
        }
    }
    println!(
        "| scene | preset | converged RMSE | × Bevy High | high-frequency (Bevy High) | frames to converge |"
    );
    println!("|---|---|---:|---:|---:|---:|");
    for (name, preset, (error, hf), frames, _, (bevy, bevy_hf)) in &table {
        let frames = frames.map_or(format!("> {}", converged_frames()), |f| f.to_string());
        println!(
            "| {name} | {} | {error:.3} | {:.2} | {hf:.3} ({bevy_hf:.3}) | {frames} |",
            preset.name(),
            error / bevy
        );
    }
    for (name, preset, (error, hf), frames, after_16, (bevy, bevy_hf)) in table {
        assert!(
            error < bevy,
            "{name}: preset {preset:?} converged RMSE {error} not below Bevy's High {bevy}"
        );
        if preset == AoPreset::default() {
            // Measured at full resolution, which the default runs at this size
            // (`DynamicAo::small_viewport_pixels`): 0.06–0.11 × Bevy's RMSE (0.0096 / 0.0141 /
            // 0.0160); high-frequency error 0.0063 / 0.0089 / 0.0097 against Bevy's 0.0230 /
            // 0.0119 / 0.0182 (room corner the closest, 0.75×). At half resolution: 0.07–0.13 ×
            // Bevy's RMSE (0.08–0.15 before the rays' last step lay at R); high-frequency error
            // 0.0068 / 0.0116 / 0.0119 (room corner the closest: the upsampling's nine texels
            // took it from 0.0128 once the blur stopped running).
            assert!(
                error <= 0.12 * bevy,
                "{name}: the default's RMSE {error:.4} is over 0.12 × Bevy's {bevy:.4}"
            );
            assert!(
                hf <= 0.8 * bevy_hf,
                "{name}: the default's high-frequency error {hf:.4} is over Bevy's {bevy_hf:.4}"
            );
            assert!(
                after_16 <= DEFAULT_AFTER_16 * error,
                "{name}: after 16 frames the default's RMSE is {after_16:.4}, converged {error:.4} \
                 ({frames:?} frames to within 10%)"
            );
        }
    }
}

/// Third-party models from `../shared/assets` on a floor (a detailed static model, two skinned
/// characters), converged: the default against Bevy's SSAO High, in error and in detail. Skipped,
/// with a message, where the folder is absent.
#[test]
fn the_default_keeps_detail_on_third_party_models() {
    let Some(shared) = crate::models::shared_assets() else {
        return;
    };
    for scene in far_scenes::third_party() {
        if ![
            "DamagedHelmet on floor",
            "CesiumMan on floor",
            "Fox on floor",
        ]
        .contains(&scene.name)
        {
            continue;
        }
        let mut run = FarRun::new(&scene, shared.to_str());
        run.image_space = DynamicAo::default();
        let bvh = run.bvh();
        let ours = run.render(true, None, FarFieldBlend::CountOnce, BEVY_SSAO_RADIUS);
        let truth = ours.ground_truth(&bvh, BEVY_SSAO_RADIUS);
        let mask = ours.geometry_mask();
        let errors = |visibility: &[f32]| {
            (
                rmse(visibility, &truth, Some(&mask)),
                high_frequency_error(visibility, &truth, WIDTH, HEIGHT, Some(&mask)),
            )
        };
        let (error, hf) = errors(&ours.visibility);
        run.gpu.set_ao(|ao| ao.technique = AoTechnique::BevySsao);
        let (bevy, bevy_hf) = errors(&run.gpu.frame(4).visibility);
        println!(
            "{}: default RMSE {error:.4} ({:.2} × Bevy's {bevy:.4}), high-frequency {hf:.4} \
             (Bevy {bevy_hf:.4})",
            scene.name,
            error / bevy
        );
        // Measured at full resolution, which the default runs at this size
        // (`DynamicAo::small_viewport_pixels`): 0.07–0.22 × Bevy's RMSE (DamagedHelmet 0.22×,
        // CesiumMan 0.08×, the Fox 0.07×), high-frequency error 0.008–0.027 against Bevy's
        // 0.032–0.044. The README quotes this bound. At half resolution: 0.09–0.26 × Bevy's RMSE
        // (DamagedHelmet 0.26×, CesiumMan 0.11×, the Fox
        // 0.09×; DamagedHelmet 0.27× before the rays' last step lay at R, 0.30× before the
        // upsampling weighed the distance from the pixel's plane; 0.34× before steps just behind
        // the back-face layer counted as blocked, 0.31× while the blur added the fine-detail term
        // at full resolution, 0.39× before the term); high-frequency error 0.012–0.033 against
        // Bevy's 0.032–0.044.
        assert!(
            error <= 0.24 * bevy,
            "{}: RMSE {error:.4} against Bevy's {bevy:.4}",
            scene.name
        );
        assert!(
            hf <= bevy_hf,
            "{}: high-frequency error {hf:.4} against Bevy's {bevy_hf:.4}",
            scene.name
        );
    }
}

/// The default joined to the far field, set up as a user sets it up: third-party models on a
/// floor (a detailed static model, a skinned character, a room of thin walls, a character just
/// outside the view), every mesh a sphere occluder, at two radii. Against the same far field
/// joined to the near field (one frame at full resolution, about four times the default's cost),
/// it must not be worse by more than 0.004. Skipped, with a message, where `../shared/assets` is
/// absent.
#[test]
fn the_default_joined_to_the_far_field_holds_on_third_party_models() {
    let Some(shared) = crate::models::shared_assets() else {
        return;
    };
    let wanted = [
        "DamagedHelmet on floor",
        "CesiumMan on floor",
        "CornellBox on floor",
        "CesiumMan beside view",
    ];
    let mut worse = Vec::new();
    for scene in far_scenes::third_party() {
        if !wanted.contains(&scene.name) {
            continue;
        }
        let mut run = FarRun::new(&scene, shared.to_str());
        let bvh = run.bvh();
        for radius in [0.75, 2.0] {
            run.image_space = crate::harness::plain_ao();
            let near = run.render(
                true,
                Some(FarTerm::Spheres),
                FarFieldBlend::CountOnce,
                radius,
            );
            let truth = near.ground_truth(&bvh, radius);
            let mask = near.geometry_mask();
            let near_error = rmse(&near.visibility, &truth, Some(&mask));
            run.image_space = DynamicAo::default();
            let ours = run.render(
                true,
                Some(FarTerm::Spheres),
                FarFieldBlend::CountOnce,
                radius,
            );
            let error = rmse(&ours.visibility, &truth, Some(&mask));
            println!(
                "{}, R = {radius} m, with sphere occluders: default {error:.4}, near field \
                 {near_error:.4}",
                scene.name
            );
            // Measured: better on DamagedHelmet (0.0505 / 0.0459 against 0.0705 / 0.0661) and on
            // CornellBox at 2 m, equal beside the view; worse on CesiumMan on a floor (0.0238 /
            // 0.0233 against 0.0203 / 0.0199), whose limbs' shading the near field's full
            // resolution keeps, and on CornellBox at 0.75 m (+0.0009).
            if error > near_error + 0.004 {
                worse.push(format!(
                    "{}, R = {radius} m: default {error:.4} against the near field \
                     {near_error:.4}",
                    scene.name
                ));
            }
        }
    }
    assert!(worse.is_empty(), "{worse:?}");
}

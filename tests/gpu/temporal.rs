//! Temporal accumulation: with a still camera the occlusion converges toward the CPU evaluation
//! of the same formula at a full budget, and an occluder that moves away leaves no trail.

use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    metrics::rmse,
    near_field::{NearFieldInputs, near_field_occlusion},
};

use crate::harness::{
    Frame, Gpu, converged_frames, difference_stats, largest_difference, plain_ao,
};
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
        ..plain_ao()
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
    // Measured (2026-11-27): one frame 0.0808, then 0.0468, 0.0316, 0.0331 on lavapipe (the same in
    // five runs: 1.05× from the second checkpoint to the last); 0.0828, then 0.0493, 0.0329,
    // 0.0353 on an NVIDIA H200 (1.07×): once converged, the error moves by several per cent from
    // one checkpoint to the next, so the bound is 10%, above both.
    assert!(errors[1] < 0.75 * errors[0], "the error falls: {errors:?}");
    let converged = *errors.last().unwrap();
    assert!(
        converged < 1.1 * errors[1],
        "the error stays down once converged: {errors:?}"
    );
    assert!(
        converged < 0.45 * error_single,
        "accumulated {converged:.4} vs one frame {error_single:.4}"
    );
    // A reset (a camera cut) drops the history: the next frame is a single frame's estimate.
    gpu.set_ao(|ao| ao.temporal.reset = true);
    let cut = rmse(&gpu.frame(0).visibility, &reference, Some(&mask));
    println!("RMSE on the frame after a reset: {cut:.4}");
    assert!(
        cut > 0.8 * error_single,
        "after a reset {cut:.4}, one frame {error_single:.4}, accumulated {converged:.4}"
    );
    assert!(
        !gpu.app
            .world()
            .get::<DynamicAo>(gpu.camera)
            .unwrap()
            .temporal
            .reset,
        "the plugin clears the reset once it is used"
    );
}

/// Pixels off by more than 0.1 from the settled image of the moved scene, with `ao`: converged
/// (`settle` frames) before the cube on the plane moves away, and 2, 4, 6 and 8 frames after.
fn trail_left(ao: DynamicAo, settle: u32) -> (usize, [usize; 4]) {
    let scene = scenes::cube_on_plane();
    let moved = Vec3::new(-1.6, 0.5, -1.2);
    // Ground truth of the moved scene: the same settings accumulated with the cube already there.
    let mut after = scenes::cube_on_plane();
    after.meshes[1].1.translation = moved;
    let settled = Gpu::new(&after, ao.clone()).frame(settle);

    let mut gpu = Gpu::new(&scene, ao);
    let before = gpu.frame(settle);
    let world = gpu.app.world_mut();
    let mut cubes = world.query::<(&mut Transform, &Mesh3d)>();
    for (mut transform, _) in cubes.iter_mut(world) {
        if transform.translation == Vec3::new(0.0, 0.5, 0.0) {
            transform.translation = moved;
        }
    }
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
    // Two frames each, plus the few the read-back takes.
    let left = [0; 4].map(|_| trail(&gpu.frame(2)));
    (trail(&before), left)
}

#[test]
fn an_occluder_that_moves_away_leaves_no_trail() {
    let near_field = DynamicAo {
        temporal: AoTemporal::ON,
        ..plain_ao()
    };
    // Scene settings, frames to converge, and the checkpoint (0: 2 frames after the move, 1: 4,
    // 2: 6, 3: 8) by which less than a fiftieth of the changed pixels may be left. The default
    // marches half the texels a frame (the checkerboard): its history spans twice the frames,
    // and its clamp window holds last frame's values beside this frame's, so the trail takes
    // longer to clear.
    for (name, ao, settle, by) in [
        ("near field, accumulated", near_field, 24, 0),
        (
            "the default",
            DynamicAo::default(),
            48,
            DEFAULT_TRAIL_CHECKPOINT,
        ),
    ] {
        let (was, left) = trail_left(ao, settle);
        println!(
            "{name}: pixels off by > 0.1 from the settled image: before the move {was}, 2, 4, 6 \
             and 8 frames after {left:?}"
        );
        assert!(
            was > 500,
            "{name}: the move must change the image ({was} pixels)"
        );
        assert!(
            left[by] * 50 < was,
            "{name}: a trail of {:?} pixels is left (of {was} that changed)",
            left
        );
    }
}

/// The checkpoint of `an_occluder_that_moves_away_leaves_no_trail` for the default: 6 frames.
/// Measured: 294, 70, 4 and 6 pixels of 3,032 after 2, 4, 6 and 8 frames (the near field: 30, 5,
/// 2, 0 of 2,654; the default before its rays' last step lay at R: 263, 55, 7 and 8 of 2,782).
const DEFAULT_TRAIL_CHECKPOINT: usize = 2;

/// The default's checkerboard (each texel marched every other frame) converges, with twice the
/// frames, to the error of marching every texel every frame, against ground truth on the test
/// scenes.
#[test]
fn the_checkerboard_converges_to_the_error_of_marching_every_texel() {
    use crate::near_field::BEVY_SSAO_RADIUS;

    for (name, scene) in scenes::all() {
        let bvh = scene.bvh();
        let every_texel = DynamicAo::default()
            .with_radius(BEVY_SSAO_RADIUS)
            .with_ray_march(RayMarchParams {
                checkerboard: false,
                ..RayMarchParams::default()
            });
        let full_frames = converged_frames(&every_texel);
        let mut gpu = Gpu::new(&scene, every_texel);
        let full = gpu.frame(full_frames);
        let truth = full.ground_truth(&bvh, BEVY_SSAO_RADIUS);
        let mask = full.geometry_mask();
        gpu.set_ao(|ao| *ao = DynamicAo::default().with_radius(BEVY_SSAO_RADIUS));
        let checkerboard = gpu.frame(converged_frames(&DynamicAo::default()));
        let errors = (
            rmse(&full.visibility, &truth, Some(&mask)),
            rmse(&checkerboard.visibility, &truth, Some(&mask)),
        );
        println!(
            "{name}: RMSE marching every texel ({full_frames} frames) {:.4}, the checkerboard \
             ({} frames) {:.4}",
            errors.0,
            converged_frames(&DynamicAo::default()),
            errors.1
        );
        // ao_capture on the project's scenes and on third-party models read within 3%.
        assert!(
            errors.1 <= 1.05 * errors.0,
            "{name}: the checkerboard's RMSE {:.4} against {:.4} marching every texel",
            errors.1,
            errors.0
        );
    }
}

/// A camera whose shaders load late (here: spawned while the compose shader is out of its assets,
/// as for a moment while a file reloads) accumulates, once its AO is shown, the same frames as a
/// camera that had been running: its history and its place in the sample sequence both start on
/// the first frame its passes all run. Before, the sequence counted from the camera's first frame
/// and the history kept what the passes wrote while Bevy's SSAO stood in: the two cameras differed
/// by 0.11. With the image-space term alone, and with a voxel volume whose term accumulates too.
#[test]
fn a_camera_whose_shaders_load_late_accumulates_what_a_running_one_does() {
    for voxels in [false, true] {
        let scene = scenes::cube_on_plane();
        let mut gpu = Gpu::new(&scene, DynamicAo::default());
        if voxels {
            gpu.app.world_mut().spawn((
                Transform::from_xyz(0.0, 1.0, 0.0),
                VoxelAoVolume {
                    half_extents: Vec3::new(3.0, 1.5, 3.0),
                    resolution: 64,
                    ..default()
                },
            ));
        }
        gpu.frame(4);
        let compose = gpu.take_shader("compose/compose.wgsl");
        gpu.update(3);
        let (_, late) = gpu.add_camera(scene.camera, DynamicAo::default());
        gpu.update(5);
        gpu.restore_shader(compose);
        let running = gpu.readback.clone();
        let mut compared = 0;
        let mut largest = 0.0f32;
        for _ in 0..40 {
            let both = gpu.visibility_of_each_now(&[&running, &late]);
            let [running, late] = [&both[0], &both[1]];
            let shown = |v: &[f32]| v.iter().all(|v| (0.0..=1.0).contains(v));
            if !shown(running) && !shown(late) {
                continue;
            }
            let difference = largest_difference(running, late);
            assert!(
                shown(running) && shown(late) && difference < 1e-6,
                "voxels {voxels}, read-back {compared} after the shader came back: the cameras \
                 differ by {difference} (each shown: {}, {})",
                shown(running),
                shown(late)
            );
            largest = largest.max(1.0 - running.iter().copied().fold(1.0, f32::min));
            compared += 1;
            if compared == 12 {
                break;
            }
        }
        assert_eq!(
            compared, 12,
            "voxels {voxels}: the AO was shown on {compared} of 40"
        );
        assert!(
            largest > 0.3,
            "voxels {voxels}: the scene should occlude: {largest}"
        );
    }
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

/// Accumulation on scenes set up as a user sets them up: every mesh a sphere occluder joined to
/// the near field, boxes, a thin wall and a large floor, a box and a wall just outside the view,
/// the project's skinned walker, at 0.75 m and 2 m. The accumulated near field with 8 samples a
/// frame (a quarter of the default's) must stay as close to ground truth as the default. Prints
/// the table of BENCHMARKS.md's temporal section.
#[test]
fn accumulation_holds_on_scenes_with_every_mesh_an_occluder() {
    use crate::far_scenes::{self, FarRun};
    use crate::far_terms::FarTerm;

    let accumulated = |ao: &mut DynamicAo, near_field: NearFieldParams| {
        ao.near_field = near_field;
        ao.temporal = AoTemporal::ON;
    };
    let mut scenes = far_scenes::procedural();
    scenes.push(far_scenes::walker_on_floor());
    for scene in scenes {
        let name = scene.name;
        let mut run = FarRun::new(&scene, None);
        let bvh = run.bvh();
        for radius in [0.75, 2.0] {
            let plain = run.render(
                true,
                Some(FarTerm::Spheres),
                FarFieldBlend::CountOnce,
                radius,
            );
            let truth = plain.ground_truth(&bvh, radius);
            let mask = plain.geometry_mask();
            let plain_error = rmse(&plain.visibility, &truth, Some(&mask));
            run.gpu
                .set_ao(|ao| accumulated(ao, AoPreset::Low.near_field()));
            let eight = run.gpu.frame(30);
            let eight_error = rmse(&eight.visibility, &truth, Some(&mask));
            run.gpu
                .set_ao(|ao| accumulated(ao, AoPreset::Medium.near_field()));
            let sixteen = run.gpu.frame(30);
            let sixteen_error = rmse(&sixteen.visibility, &truth, Some(&mask));
            // The crate's default image-space technique (the accumulated ray march, at full
            // resolution at this size: `DynamicAo::small_viewport_pixels`), joined to the same
            // far field.
            run.gpu.set_ao(|ao| {
                let default = DynamicAo::default();
                ao.technique = default.technique;
                ao.ray_march = default.ray_march;
                ao.half_resolution = default.half_resolution;
                ao.small_viewport_pixels = default.small_viewport_pixels;
                ao.near_field = default.near_field;
            });
            let default = run.gpu.frame(30);
            let default_error = rmse(&default.visibility, &truth, Some(&mask));
            run.gpu.set_ao(|ao| {
                *ao = DynamicAo {
                    radius: ao.radius,
                    far_field_blend: ao.far_field_blend,
                    spheres: ao.spheres,
                    fields: ao.fields,
                    voxels: ao.voxels,
                    ..plain_ao()
                }
            });
            println!(
                "| {name} | {radius} | {plain_error:.3} | {eight_error:.3} | {sixteen_error:.3} | \
                 {default_error:.3} |"
            );
            assert!(
                eight_error <= 1.05 * plain_error,
                "{name}, R = {radius} m: accumulated 8 samples {eight_error} vs default {plain_error}"
            );
            // Measured: as close as the near field or closer on every scene and radius but the
            // walker (0.024 against 0.023 at 0.75 m, 0.023 against 0.022 at 2 m; 0.025 against
            // 0.023 at 0.75 m before the ray march continued the surface past the screen's edge),
            // whose limbs are closed solids with air between them that the ray march's thickness
            // behind the back faces counts as solid. Before that thickness the open room at 2 m
            // read 0.113 against 0.109 (its 4 cm wall tops are under two pixels wide at half
            // resolution); it reads 0.099 now.
            assert!(
                default_error <= plain_error + 0.003,
                "{name}, R = {radius} m: the default {default_error} vs the near field {plain_error}"
            );
        }
    }
}

/// Bevy's temporal anti-aliasing on the same camera jitters the projection, and so the ND-buffer,
/// every frame. The default's accumulation still converges near the error it has without it, and
/// the lit image keeps its brightness (AO reaches the lighting through TAA's resolve). How near
/// depends on where the sample sequence starts within the jitter's cycle of 8 frames (Bevy's
/// frame count, which a late-loading shader or a reset moves against the sequence), so the
/// history is started over at each of the 8 places.
#[test]
fn accumulation_works_with_bevys_temporal_anti_aliasing() {
    use bevy::anti_alias::taa::TemporalAntiAliasing;
    use bevy::diagnostic::FrameCount;

    use crate::near_field::BEVY_SSAO_RADIUS;

    const JITTER_CYCLE: u32 = 8;
    let mut rows = Vec::new();
    for (name, scene) in crate::scenes::all() {
        let bvh = scene.bvh();
        let ao = DynamicAo::default().with_radius(BEVY_SSAO_RADIUS);
        let mut gpu = Gpu::new(&scene, ao.clone());
        let frames = converged_frames(&ao);
        let plain = gpu.frame(frames);
        let truth = plain.ground_truth(&bvh, BEVY_SSAO_RADIUS);
        let mask = plain.geometry_mask();
        let lit = |colors: &[Vec3]| colors.iter().map(|c| c.element_sum()).sum::<f32>();
        let plain_lit = lit(&gpu.color(1));
        // One app renders at a time.
        drop(gpu);

        let mut gpu = Gpu::new(&scene, ao);
        gpu.app
            .world_mut()
            .entity_mut(gpu.camera)
            .insert(TemporalAntiAliasing::default());
        gpu.frame(1);
        let errors: Vec<f32> = (0..JITTER_CYCLE)
            .map(|phase| {
                let count = gpu.app.world().resource::<FrameCount>().0;
                gpu.update((JITTER_CYCLE + phase - count % JITTER_CYCLE) % JITTER_CYCLE);
                gpu.set_ao(|ao| ao.temporal.reset = true);
                rmse(&gpu.frame(frames).visibility, &truth, Some(&mask))
            })
            .collect();
        let taa_lit = lit(&gpu.color(1));
        let plain_error = rmse(&plain.visibility, &truth, Some(&mask));
        let mean = errors.iter().sum::<f32>() / errors.len() as f32;
        let worst = errors.iter().copied().fold(0.0, f32::max);
        println!(
            "{name}: default RMSE {plain_error:.4}, with Bevy's TAA {mean:.4} on average over the \
             jitter's phases, {worst:.4} at the worst ({errors:.4?}); lit image brightness ratio \
             {:.3}",
            taa_lit / plain_lit
        );
        rows.push((name, plain_error, mean, worst, taa_lit / plain_lit));
    }
    for (name, plain, mean, worst, brightness) in rows {
        // The truth is traced without TAA's sub-pixel jitter, which costs the jittered frames a
        // little at silhouettes. Measured: on average 0.0109 / 0.0154 / 0.0195 against 0.0097 /
        // 0.0143 / 0.0161 without TAA, at the worst phase 0.0115 / 0.0161 / 0.0212; brightness
        // 1.007 / 1.010 / 1.010.
        assert!(
            mean < plain + 0.004,
            "{name}: {mean:.4} with TAA on average, {plain:.4} without"
        );
        assert!(
            worst < plain + 0.0055,
            "{name}: {worst:.4} with TAA at the worst phase, {plain:.4} without"
        );
        assert!(
            (0.99..1.02).contains(&brightness),
            "{name}: lit image with TAA at {brightness:.3} of the one without"
        );
    }
}

/// The voxel term accumulated, on scenes set up as a user sets them up: every mesh inside the
/// volume `ao_capture` places, a box and a wall just outside the view, the skinned walker and,
/// where `../shared/assets` exists, third-party models on a floor (a skinned character, a room of
/// thin walls, a character just off-screen), at 0.75 m and 2 m. Against ground truth, the voxel
/// term alone accumulated must be no worse than one frame of it (blurred by `AoBlur::radius`,
/// where accumulated it is blurred by `voxel_accumulated_radius`) and lower over the scenes
/// together, and the default joined to it no worse than the near field joined to one frame of it.
#[test]
fn the_accumulated_voxel_term_holds_on_scenes_with_every_mesh_an_occluder() {
    use crate::far_scenes::{self, FarRun};
    use crate::far_terms::FarTerm;

    let scenes = far_scenes::voxel_scenes();
    let voxels = |run: &mut FarRun, near: bool, image_space: DynamicAo, radius: f32| {
        run.image_space = image_space;
        run.render(
            near,
            Some(FarTerm::Voxels),
            FarFieldBlend::CountOnce,
            radius,
        );
        // Read once converged, the voxel term alone included.
        run.gpu.frame(30)
    };
    let accumulated = DynamicAo {
        temporal: AoTemporal::ON,
        ..plain_ao()
    };
    let mut worse = Vec::new();
    let (mut one_frame_sum, mut accumulated_sum) = (0.0, 0.0);
    for (scene, folder) in scenes {
        let name = scene.name;
        let mut run = FarRun::new(&scene, folder.as_deref());
        let bvh = run.bvh();
        for radius in [0.75, 2.0] {
            let one = voxels(&mut run, false, plain_ao(), radius);
            let truth = one.ground_truth(&bvh, radius);
            let mask = one.geometry_mask();
            let error = |frame: &Frame| rmse(&frame.visibility, &truth, Some(&mask));
            let alone = (
                error(&one),
                error(&voxels(&mut run, false, accumulated.clone(), radius)),
            );
            let joined = (
                error(&voxels(&mut run, true, plain_ao(), radius)),
                error(&voxels(&mut run, true, DynamicAo::default(), radius)),
            );
            one_frame_sum += alone.0;
            accumulated_sum += alone.1;
            println!(
                "{name}, R = {radius} m: voxels alone, one frame {:.4}, accumulated {:.4}; near \
                 field + voxels {:.4}, default + accumulated voxels {:.4}",
                alone.0, alone.1, joined.0, joined.1
            );
            // Measured: lower on every scene and radius but CesiumMan beside the view at 0.75 m
            // (0.0020 against 0.0019), by 14–35% on those in view.
            assert!(
                alone.1 <= alone.0 + 0.0005,
                "{name}, R = {radius} m: voxels accumulated {:.4} against one frame {:.4}",
                alone.1,
                alone.0
            );
            // Measured: lower on every scene and radius but the wall beside the view at 0.75 m
            // (0.0056 against 0.0056; CesiumMan on a floor 0.0131 / 0.0169 against 0.0214 /
            // 0.0242, CornellBox 0.0339 / 0.0258 against 0.0691 / 0.0489). Before the ray march's last step lay at R, CesiumMan read +0.0027 /
            // +0.0024 (the near field's full resolution keeps the limbs' shading) and CornellBox,
            // a room of one-polygon walls, +0.006 / +0.014.
            if joined.1 > joined.0 + 0.0003 {
                worse.push(format!(
                    "{name}, R = {radius} m: default + voxels {:.4} against the near field {:.4}",
                    joined.1, joined.0
                ));
            }
        }
    }
    assert!(worse.is_empty(), "{worse:?}");
    // Measured: 0.75× with `../shared/assets`, 0.78× without. With the one-frame radius (4
    // pixels) under accumulation too it read 0.96×, the characters within 0.0003 of one frame
    // (the blur smeared what the turning rays had resolved), and the default joined to the
    // voxels 0.0061 against the near field's 0.0056 beside the wall at 0.75 m.
    let ratio = accumulated_sum / one_frame_sum;
    println!("voxels alone, accumulated against one frame over every scene: {ratio:.3}×");
    assert!(ratio < 0.8, "{ratio:.3}×");
}

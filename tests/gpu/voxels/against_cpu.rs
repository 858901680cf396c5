//! The voxel term against the CPU evaluation of the same rays on the same grid, one frame and
//! accumulated.

use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    filter::{cross_bilateral_blur, joint_bilateral_upsample_pair},
    metrics::rmse,
    voxels::{VoxelCamera, VoxelGrid, voxel_ao_map},
};
use bevy_dynamic_ao::voxels::VoxelGridInfo;

use super::{read_grids, spawn_volume, voxels_only};
use crate::harness::{Frame, Gpu, difference_stats, plain_ao};
use crate::scenes;

/// The CPU twin of the whole voxel path for one frame: sampling on the GPU's own grids,
/// upsampling, blur, and visibility as compose writes it.
fn cpu_voxel_visibility(
    frame: &Frame,
    grids: &[(VoxelGridInfo, VoxelGrid)],
    ao: &DynamicAo,
) -> Vec<f32> {
    let volumes: Vec<_> = grids
        .iter()
        .map(|(info, grid)| (grid.clone(), info.rays))
        .collect();
    // The voxels alone count every hit within the camera's radius: all in the second channel.
    let camera = VoxelCamera {
        radius: ao.effective_radius(),
        count_once: None,
    };
    let low = voxel_ao_map(&frame.nd, &frame.view, &volumes, &camera);
    let full = joint_bilateral_upsample_pair(&low, &frame.nd, &frame.view);
    let rest: Vec<f32> = full.iter().map(|[_, rest]| *rest).collect();
    // The voxel term's blur weighs by depth alone, at its own radius.
    let sanitized = ao.blur.sanitized();
    let blur = AoBlur {
        radius: sanitized.voxel_radius(ao.temporal.enabled),
        normal_sharpness: 0.0,
        ..sanitized
    };
    let filtered = cross_bilateral_blur(&rest, &frame.nd, &frame.view, &blur);
    filtered.iter().map(|o| 1.0 - o.clamp(0.0, 1.0)).collect()
}

/// A volume of 96³ cells over the room corner tracing `rays` (`accumulated_rays` a frame under
/// accumulation), two frames after it was spawned.
fn corner_volume(gpu: &mut Gpu, rays: u32, accumulated_rays: u32) -> Entity {
    let volume = spawn_volume(
        gpu,
        Transform::from_xyz(-0.5, 1.0, -0.5),
        VoxelAoVolume {
            half_extents: Vec3::new(2.0, 1.3, 2.0),
            resolution: 96,
            rays,
            accumulated_rays,
            ..default()
        },
    );
    gpu.update(2);
    volume
}

/// The CPU evaluation of `volume`'s grid with 64 rays at `frame`, seen by a camera with `ao`.
fn with_many_rays(gpu: &mut Gpu, volume: Entity, frame: &Frame, ao: &DynamicAo) -> Vec<f32> {
    let mut grids = read_grids(gpu, &[volume]);
    grids[0].0.rays.rays = 64;
    cpu_voxel_visibility(frame, &grids, ao)
}

/// The walk crosses empty bricks of 8³ cells in one step where the reach spans at least four
/// (`voxel_ao.wgsl`): at 96³ over the corner a brick is about 0.3 m, so a reach of 1.5 m walks
/// by bricks and one of 0.75 m cell by cell. At 90³, whose rows of cells do not fill whole words,
/// the bricks are marked one at a time.
#[test]
fn gpu_voxel_ao_matches_the_cpu_evaluation_of_the_same_rays() {
    let scene = scenes::room_corner();
    for (blur, resolution, d_max) in [(0, 96, 1.5), (4, 96, 1.5), (0, 90, 1.5), (0, 96, 0.75)] {
        let ao = DynamicAo {
            blur: AoBlur {
                radius: blur,
                ..default()
            },
            ..voxels_only()
        };
        let mut gpu = Gpu::new(&scene, ao.clone());
        let volume = spawn_volume(
            &mut gpu,
            Transform::from_xyz(-0.5, 1.0, -0.5),
            VoxelAoVolume {
                half_extents: Vec3::new(2.0, 1.3, 2.0),
                resolution,
                rays: 16,
                d_max: Some(d_max),
                ..default()
            },
        );
        gpu.update(2);
        let frame = gpu.frame(2);
        let grids = read_grids(&mut gpu, &[volume]);
        let cpu = cpu_voxel_visibility(&frame, &grids, &ao);
        let mask = frame.geometry_mask();
        let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
        let darkest = cpu.iter().copied().fold(1.0, f32::min);
        println!(
            "voxel AO, blur {blur}, {resolution}³, reach {d_max} m: darkest {darkest:.3}; GPU vs \
             CPU mean |diff| {mean:.5}, 99th percentile {p99:.5}"
        );
        assert!(darkest < 0.7, "the corner should be occluded");
        // A ray that grazes a cell boundary can take the other cell on one side: one ray of 16
        // is about 0.06 of a texel.
        assert!(mean < 0.003 && p99 < 0.07, "{mean} {p99}");
    }
}

/// Under temporal accumulation the voxel rays turn every frame, and the accumulated term
/// approaches the CPU evaluation of the same volume with 16 times the rays (what averaging many
/// turned 4-ray patterns estimates); a reset drops the history.
#[test]
fn the_voxel_term_accumulates_toward_many_rays() {
    let scene = scenes::room_corner();
    let ao = |temporal: AoTemporal| DynamicAo {
        blur: AoBlur::OFF,
        temporal,
        ..voxels_only()
    };
    let mut gpu = Gpu::new(&scene, ao(AoTemporal::OFF));
    let volume = corner_volume(&mut gpu, 4, 4);
    let single = gpu.frame(2);
    let many = with_many_rays(&mut gpu, volume, &single, &ao(AoTemporal::OFF));
    let mask = single.geometry_mask();
    let error_single = rmse(&single.visibility, &many, Some(&mask));

    gpu.set_ao(|a| *a = ao(AoTemporal::ON));
    let errors: Vec<f32> = [1, 7, 24]
        .into_iter()
        .map(|frames| rmse(&gpu.frame(frames).visibility, &many, Some(&mask)))
        .collect();
    println!(
        "voxel term, RMSE against 64 rays on the CPU: one frame of 4 rays {error_single:.4}, \
         accumulated {errors:?}"
    );
    // Measured: one frame 0.051, then 0.034, 0.012, 0.009 (0.068, 0.043, 0.013, 0.010 on an
    // earlier build).
    let converged = errors[2];
    assert!(errors[1] < 0.4 * errors[0], "the error falls: {errors:?}");
    assert!(
        converged < 0.2 * error_single,
        "accumulated {converged:.4} vs one frame {error_single:.4}"
    );
    gpu.set_ao(|a| a.temporal.reset = true);
    let cut = rmse(&gpu.frame(0).visibility, &many, Some(&mask));
    println!("voxel term, RMSE on the frame after a reset: {cut:.4}");
    assert!(cut > 0.8 * error_single, "after a reset {cut:.4}");
}

/// A camera that accumulates the voxel term traces `accumulated_rays` a frame, not `rays`: with
/// a history of one frame (nothing averaged), each frame is as far from many rays as that budget
/// is.
#[test]
fn an_accumulating_camera_traces_the_accumulated_rays_each_frame() {
    let scene = scenes::room_corner();
    let one_frame = AoTemporal {
        max_frames: 1,
        ..AoTemporal::ON
    };
    let ao = DynamicAo {
        blur: AoBlur::OFF,
        temporal: one_frame,
        ..voxels_only()
    };
    let mut gpu = Gpu::new(&scene, ao.clone());
    let volume = corner_volume(&mut gpu, 32, 4);
    let four = gpu.frame(2);
    let still = DynamicAo {
        temporal: AoTemporal::OFF,
        ..ao
    };
    let many = with_many_rays(&mut gpu, volume, &four, &still);
    let mask = four.geometry_mask();
    let error = |frame: &Frame| rmse(&frame.visibility, &many, Some(&mask));
    let error_four = error(&four);
    gpu.app
        .world_mut()
        .get_mut::<VoxelAoVolume>(volume)
        .unwrap()
        .accumulated_rays = 32;
    let error_all = error(&gpu.frame(2));
    println!(
        "voxel term a frame, RMSE against 64 rays on the CPU: 4 rays {error_four:.4}, 32 rays \
         {error_all:.4}"
    );
    // Measured: 0.0531 and 0.0107.
    assert!(
        error_four > 4.0 * error_all,
        "{error_four:.4} vs {error_all:.4}"
    );
}

/// A camera that accumulates the voxel term blurs it by `AoBlur::voxel_accumulated_radius`, not
/// `radius`: the blurred image is the CPU blur (by depth alone) of the unblurred one, and the
/// one-frame radius changes nothing. Each run starts its history over once its AO is written,
/// so the three accumulate the same frames of the same sequence.
#[test]
fn an_accumulating_camera_blurs_the_voxel_term_by_its_accumulated_radius() {
    let scene = scenes::room_corner();
    let ao = |radius, voxel_accumulated_radius| DynamicAo {
        blur: AoBlur {
            radius,
            voxel_accumulated_radius,
            ..AoBlur::OFF
        },
        temporal: AoTemporal::ON,
        ..voxels_only()
    };
    let run = |ao: DynamicAo| {
        let mut gpu = Gpu::new(&scene, ao);
        corner_volume(&mut gpu, 4, 4);
        // Where shaders load late (other tests loading models meanwhile), the AO is first shown
        // a few frames later in one app than in another: started over once it is shown, the
        // three histories hold the same number of frames when read.
        gpu.frame(1);
        gpu.set_ao(|ao| ao.temporal.reset = true);
        gpu.frame(8)
    };
    let unblurred = run(ao(0, 0));
    let one_frame_radius = run(ao(4, 0));
    let blurred = run(ao(0, 2));
    let mask = unblurred.geometry_mask();
    let (same_mean, same_p99) =
        difference_stats(&unblurred.visibility, &one_frame_radius.visibility, &mask);
    let occlusion: Vec<f32> = unblurred.visibility.iter().map(|v| 1.0 - v).collect();
    let cpu_blur = AoBlur {
        radius: 2,
        normal_sharpness: 0.0,
        ..AoBlur::default()
    };
    let cpu: Vec<f32> = cross_bilateral_blur(&occlusion, &unblurred.nd, &unblurred.view, &cpu_blur)
        .iter()
        .map(|o| 1.0 - o)
        .collect();
    let (mean, p99) = difference_stats(&blurred.visibility, &cpu, &mask);
    let (moved, _) = difference_stats(&blurred.visibility, &unblurred.visibility, &mask);
    println!(
        "accumulated voxel term: `radius` 4 against 0, mean |diff| {same_mean:.5}; blurred by 2 \
         against the CPU blur of the unblurred image {mean:.5} (99th percentile {p99:.5}), \
         against the unblurred image {moved:.5}"
    );
    assert!(
        same_mean == 0.0 && same_p99 == 0.0,
        "{same_mean} {same_p99}"
    );
    assert!(moved > 0.002, "the blur changed nothing: {moved}");
    assert!(
        mean < 0.25 * moved && p99 < 0.01,
        "{mean} {p99} (moved {moved})"
    );
}

/// Scenes as a user sets them up (`far_scenes::voxel_scenes`), every mesh in one volume placed
/// as `ao_capture` places it (256³ over what occludes the view), at two radii. Where R spans
/// four bricks the walk crosses empty ones in one step; the CPU twin walks every cell, so the
/// two agree only if no occupied cell is skipped.
#[test]
fn the_brick_walk_matches_the_cpu_on_scenes_with_every_mesh_an_occluder() {
    use crate::far_scenes::{self, FarRun};
    use crate::far_terms::FarTerm;

    let mut bricked = 0;
    for (scene, folder) in far_scenes::voxel_scenes() {
        let name = scene.name;
        let mut run = FarRun::new(&scene, folder.as_deref());
        for radius in [0.75, 2.0] {
            let frame = run.render(
                false,
                Some(FarTerm::Voxels),
                FarFieldBlend::CountOnce,
                radius,
            );
            let volume = run.volume().expect("a volume");
            let grids = read_grids(&mut run.gpu, &[volume]);
            // `MIN_BRICKS_PER_REACH` bricks of 8³ cells of the volume's mean cell.
            let cell = grids[0].0.rays.cell;
            let bricks = radius / (8.0 * (cell.x + cell.y + cell.z) / 3.0);
            bricked += usize::from(bricks >= 4.0);
            let cpu = cpu_voxel_visibility(&frame, &grids, &plain_ao().with_radius(radius));
            let mask = frame.geometry_mask();
            let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
            // The darkest pixel: an occluder off-screen darkens only a strip (CesiumMan beside
            // the view, at 0.75 m, by 0.043 at most).
            let darkest = mask
                .iter()
                .zip(&cpu)
                .filter(|(m, _)| **m)
                .map(|(_, v)| 1.0 - v)
                .fold(0.0, f32::max);
            println!(
                "{name}, R = {radius} m: reach {bricks:.1} bricks; darkest occlusion {darkest:.3}; \
                 GPU vs CPU mean |diff| {mean:.5}, 99th percentile {p99:.5}"
            );
            assert!(darkest > 0.02, "{name}: the volume casts occlusion");
            // Measured: mean at most 0.00094 and 99th percentile 0.0106 (the room corner at
            // 2 m, whose walls meet cell boundaries along whole rows of pixels).
            assert!(
                mean < 0.0015 && p99 < 0.02,
                "{name}, R = {radius}: {mean} {p99}"
            );
        }
    }
    assert!(bricked >= 4, "the walk crossed bricks in {bricked} runs");
}

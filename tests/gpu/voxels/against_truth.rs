//! Occluders the depth buffer misses (off-screen, hidden) against ground truth, and stability
//! under a moving camera.

use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::metrics::rmse;
use bevy_dynamic_ao::voxels::{VoxelFalloff, VoxelMarch};

use super::{spawn_volume, voxels_only};
use crate::harness::{Frame, Gpu, SceneSpec, WIDTH, band, plain_ao};
use crate::scenes;

/// Occlusion a technique adds to the image columns `strip` against the columns `other`, and its
/// RMSE against ground truth.
#[derive(Clone, Copy, Debug)]
struct Measured {
    strip: f32,
    rmse: f32,
}

/// Ground truth, near field + voxels (the defaults, and the paper's Wendland falloff and
/// 8-step march), near field alone and Bevy's SSAO.
struct Comparison {
    truth: Measured,
    voxels: Measured,
    wendland: Measured,
    steps: Measured,
    near: Measured,
    bevy: Measured,
}

fn against_truth(
    scene: &SceneSpec,
    transform: Transform,
    volume: VoxelAoVolume,
    strip: std::ops::Range<u32>,
    other: std::ops::Range<u32>,
    radius: f32,
) -> Comparison {
    let mut gpu = Gpu::new(scene, plain_ao().with_radius(radius));
    let entity = spawn_volume(&mut gpu, transform, volume);
    gpu.set_ao(|ao| ao.voxels = false);
    // The first frames of an app still show Bevy's SSAO: the view's AO state is prepared from
    // the second frame on.
    let near = gpu.frame(10);
    gpu.set_ao(|ao| ao.voxels = true);
    let voxels = gpu.frame(3);
    let set = |gpu: &mut Gpu, change: fn(&mut VoxelAoVolume)| {
        change(
            &mut gpu
                .app
                .world_mut()
                .get_mut::<VoxelAoVolume>(entity)
                .unwrap(),
        );
        gpu.frame(3)
    };
    let wendland = set(&mut gpu, |v| v.falloff = VoxelFalloff::Wendland);
    let steps = set(&mut gpu, |v| {
        v.falloff = VoxelFalloff::None;
        v.march = VoxelMarch::Steps(VoxelAoVolume::PAPER_STEPS);
    });
    gpu.set_ao(|ao| ao.technique = AoTechnique::BevySsao);
    let bevy = gpu.frame(3);
    let truth = voxels.ground_truth(&scene.bvh(), radius);
    let mask = voxels.geometry_mask();
    let measure = |v: &[f32]| Measured {
        strip: band(v, strip.clone()) - band(v, other.clone()),
        rmse: rmse(v, &truth, Some(&mask)),
    };
    Comparison {
        truth: measure(&truth),
        voxels: measure(&voxels.visibility),
        wendland: measure(&wendland.visibility),
        steps: measure(&steps.visibility),
        near: measure(&near.visibility),
        bevy: measure(&bevy.visibility),
    }
}

impl Comparison {
    /// Prints the comparison and checks the defaults find the truth's occlusion within `bound`.
    fn report(&self, what: &str, bound: f32) {
        let Self {
            truth,
            voxels,
            wendland,
            steps,
            near,
            bevy,
        } = self;
        println!(
            "{what}: occlusion added to the strip: truth {:.3}, near+voxels {:.3} (Wendland \
             {:.3}, 8 steps {:.3}), near only {:.3}, Bevy SSAO {:.3}; RMSE vs truth: near+voxels \
             {:.4} (Wendland {:.4}, 8 steps {:.4}), near only {:.4}, Bevy SSAO {:.4}",
            truth.strip,
            voxels.strip,
            wendland.strip,
            steps.strip,
            near.strip,
            bevy.strip,
            voxels.rmse,
            wendland.rmse,
            steps.rmse,
            near.rmse,
            bevy.rmse
        );
        assert!(
            truth.strip > 0.05,
            "{what}: the scene should have something to find"
        );
        assert!(
            (voxels.strip - truth.strip).abs() < bound,
            "{what}: voxels {} vs truth {}",
            voxels.strip,
            truth.strip
        );
        assert!(
            voxels.rmse < near.rmse && voxels.rmse < bevy.rmse,
            "{what}: voxels should bring the image closer to the truth"
        );
        // The paper's falloff weights hits down: it finds less than ground truth counts.
        assert!(wendland.strip < voxels.strip - 0.02, "{what}: Wendland");
    }
}

/// A box just outside the view of a camera looking down at the floor.
#[test]
fn an_off_screen_occluder_darkens_the_floor_like_ground_truth() {
    let scene = scenes::box_beside_view();
    let comparison = against_truth(
        &scene,
        Transform::from_xyz(1.0, 0.8, 0.0),
        VoxelAoVolume {
            half_extents: Vec3::new(2.5, 1.0, 2.5),
            resolution: 128,
            ..default()
        },
        WIDTH * 9 / 10..WIDTH,
        0..WIDTH / 10,
        2.0,
    );
    comparison.report("off-screen box", 0.02);
    let Comparison { near, bevy, .. } = comparison;
    assert!(
        near.strip.abs() < 0.02 && bevy.strip.abs() < 0.02,
        "screen space cannot see the box"
    );
}

/// A wall under a floating plate, seen from above: the plate hides the wall from the camera, so
/// the depth buffer holds only the plate, yet the wall darkens the visible floor beside it.
#[test]
fn a_hidden_occluder_darkens_the_floor_like_ground_truth() {
    let scene = SceneSpec::new(Transform::from_xyz(0.0, 3.0, 0.0).looking_at(Vec3::ZERO, -Vec3::Z))
        .with(
            Plane3d::default().mesh().size(10.0, 10.0),
            Transform::IDENTITY,
        )
        .with(
            Cuboid::new(0.9, 0.05, 4.0),
            Transform::from_xyz(-0.6, 1.05, 0.0),
        )
        .with(
            Cuboid::new(0.5, 1.0, 4.0),
            Transform::from_xyz(-0.6, 0.5, 0.0),
        );
    let comparison = against_truth(
        &scene,
        Transform::from_xyz(-0.3, 0.8, 0.0),
        VoxelAoVolume {
            half_extents: Vec3::new(2.2, 1.0, 2.2),
            resolution: 128,
            ..default()
        },
        WIDTH * 44 / 100..WIDTH * 56 / 100,
        WIDTH * 9 / 10..WIDTH,
        1.0,
    );
    comparison.report("wall hidden under a plate", 0.03);
}

/// A slow orbit around a static scene: the jitter is tied to world positions, so frame-to-frame
/// change stays small.
#[test]
fn voxel_ao_is_stable_under_a_slow_orbit() {
    let scene = scenes::room_corner();
    let mut gpu = Gpu::new(&scene, voxels_only());
    spawn_volume(
        &mut gpu,
        Transform::from_xyz(-0.5, 1.0, -0.5),
        VoxelAoVolume {
            half_extents: Vec3::new(2.0, 1.3, 2.0),
            resolution: 128,
            ..default()
        },
    );
    gpu.update(3);
    let start = scene.camera;
    let mut previous: Option<Frame> = None;
    let mut changes = Vec::new();
    for step in 0..6 {
        let angle = step as f32 * 0.5f32.to_radians();
        let camera = Transform::from_translation(Quat::from_rotation_y(angle) * start.translation)
            .looking_at(Vec3::new(-0.5, 0.4, -0.5), Vec3::Y);
        let id = gpu.camera;
        *gpu.app.world_mut().get_mut::<Transform>(id).unwrap() = camera;
        let frame = gpu.frame(2);
        if let Some(previous) = previous {
            let (mut sum, mut n) = (0.0, 0);
            for i in 0..frame.visibility.len() {
                if frame.nd.front[i].depth > 0.0 && previous.nd.front[i].depth > 0.0 {
                    sum += (frame.visibility[i] - previous.visibility[i]).abs();
                    n += 1;
                }
            }
            changes.push(sum / n as f32);
        }
        previous = Some(frame);
    }
    let worst = changes.iter().copied().fold(0.0, f32::max);
    let occlusion = previous
        .map(|f| 1.0 - f.visibility.iter().sum::<f32>() / f.visibility.len() as f32)
        .unwrap_or(0.0);
    println!(
        "orbit 0.5° per frame: mean |Δ visibility| per frame {changes:?}, mean occlusion \
         {occlusion:.4}"
    );
    assert!(occlusion > 0.02, "the scene should be occluded somewhere");
    assert!(
        worst < 0.005 && worst < 0.2 * occlusion,
        "frame-to-frame change {worst}"
    );
}

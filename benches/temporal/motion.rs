//! Error against per-frame ground truth with an orbiting camera and walking characters, and the
//! ghost trail a moving occluder leaves.

#[path = "../../examples/common/walking.rs"]
mod walking;

use bevy::prelude::*;
use bevy::world_serialization::WorldAssetRoot;
use bevy_dynamic_ao::geometry::bvh::Bvh;
use bevy_dynamic_ao::reference::{
    ground_truth::{GroundTruthSettings, ground_truth_visibility},
    metrics::rmse,
    nd_buffer::ViewMatrices,
    posed::posed_triangles,
};

use crate::Configuration;
use crate::scene::{self, SIZE};

/// Frames the scene moves before the first checkpoint.
const WARM_UP: u32 = 20;
/// Frames it moves between checkpoints.
const BETWEEN: u32 = 15;
const CHECKPOINTS: u32 = 6;
/// Frames a checkpoint's pose is held still before its settled image is read.
const SETTLE: u32 = 40;
/// A pixel darker than the truth by more than this counts toward a trail.
const DARKER: f32 = 0.1;

pub fn run(configurations: &[Configuration]) {
    let rows: Vec<_> = configurations
        .iter()
        .map(|c| (c.name, measure(c)))
        .collect();
    println!(
        "\n{}×{}, orbiting camera, two walkers and a sliding box, R = {} m, {CHECKPOINTS} \
         checkpoints {BETWEEN} frames apart ({} s of motion each); RMSE against ground truth traced \
         for the checkpoint's pose (256 rays per pixel), moving and once the pose was held still \
         for {SETTLE} frames; trail: pixels darker than the truth by more than {DARKER} while \
         moving, minus those once settled (mean, largest):\n",
        SIZE.x,
        SIZE.y,
        crate::RADIUS,
        BETWEEN as f32 * scene::FRAME_TIME
    );
    println!(
        "| configuration | RMSE moving | RMSE settled | trail (px, mean) | trail (px, largest) |"
    );
    println!("|---|---:|---:|---:|---:|");
    for (name, m) in rows {
        println!(
            "| {name} | {:.4} | {:.4} | {:.0} | {} |",
            m.moving, m.settled, m.trail_mean, m.trail_max
        );
    }
}

struct Measured {
    moving: f32,
    settled: f32,
    trail_mean: f32,
    trail_max: i64,
}

#[derive(Component)]
struct Orbit;

#[derive(Component)]
struct Slide;

/// Poses the camera and the slab from the simulated time, as `walking::walk` poses the walkers,
/// so every configuration sees the same frames.
fn drive(
    time: Res<Time>,
    mut orbit: Query<&mut Transform, (With<Orbit>, Without<Slide>)>,
    mut slide: Query<&mut Transform, With<Slide>>,
) {
    let t = time.elapsed_secs();
    for mut transform in &mut orbit {
        let angle = 0.7 + 0.35 * t;
        let eye = Vec3::new(5.0 * angle.cos(), 2.4, 5.0 * angle.sin());
        *transform = Transform::from_translation(eye).looking_at(Vec3::new(0.0, 0.6, 0.0), Vec3::Y);
    }
    for mut transform in &mut slide {
        transform.translation.x = 1.4 * (1.1 * t).sin();
    }
}

fn spawn_scene(app: &mut App, configuration: &Configuration) -> scene::View {
    app.add_systems(Update, (drive, walking::walk));
    let world = app.world_mut();
    scene::spawn_floor_box_and_ball(world);
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let slab = meshes.add(Cuboid::new(0.8, 0.5, 0.8));
    let wall = meshes.add(Cuboid::new(6.0, 1.5, 0.15));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    world.spawn((
        Mesh3d(slab),
        MeshMaterial3d(material.clone()),
        Transform::from_xyz(0.0, 0.25, 1.6),
        Slide,
    ));
    world.spawn((
        Mesh3d(wall),
        MeshMaterial3d(material),
        Transform::from_xyz(0.0, 0.75, -2.0),
    ));
    let walker = walking::WalkAnimation::load(world);
    for (centre, speed, phase) in [
        (Vec3::new(-1.5, 0.0, 0.2), 0.9, 0.0),
        (Vec3::new(1.6, 0.0, -0.6), -0.8, 2.0),
    ] {
        world
            .spawn((
                WorldAssetRoot(walker.clone()),
                Transform::default(),
                walking::WalkPath {
                    centre,
                    radius: 0.8,
                    speed,
                    phase,
                },
            ))
            .observe(walking::start_walking);
    }
    let view = scene::spawn_camera(world, configuration, Transform::default());
    world.entity_mut(view.camera).insert(Orbit);
    view
}

fn set_paused(app: &mut App, paused: bool) {
    let mut time = app.world_mut().resource_mut::<Time<Virtual>>();
    if paused {
        time.pause();
    } else {
        time.unpause();
    }
}

/// Ground truth of the world as it stands, seen by `camera`.
fn ground_truth(world: &mut World, camera: Entity) -> Vec<f32> {
    let bvh = Bvh::new(posed_triangles(world).triangles);
    let transform = world.get::<GlobalTransform>(camera).expect("camera");
    let projection = world
        .get::<Camera>(camera)
        .expect("camera")
        .clip_from_view();
    let view = ViewMatrices::new(transform.to_matrix(), projection);
    ground_truth_visibility(
        &bvh,
        &view,
        &GroundTruthSettings {
            width: SIZE.x,
            height: SIZE.y,
            radius: crate::RADIUS,
            rays_per_pixel: 256,
        },
    )
}

fn measure(configuration: &Configuration) -> Measured {
    let mut app = scene::new_app();
    let view = spawn_scene(&mut app, configuration);
    // Nothing moves until both walkers walk.
    set_paused(&mut app, true);
    for _ in 0..600 {
        app.update();
        let world = app.world_mut();
        let walking = world
            .query_filtered::<(), (With<AnimationPlayer>, With<AnimationGraphHandle>)>()
            .iter(world)
            .count();
        if walking >= 2 {
            break;
        }
    }
    scene::wait_until_written(&mut app, &view);
    set_paused(&mut app, false);
    for _ in 0..WARM_UP {
        app.update();
    }
    let images = [
        view.readback.visibility.clone(),
        view.readback.front.clone(),
    ];
    let (mut moving, mut settled, mut trails) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..CHECKPOINTS {
        for _ in 0..BETWEEN - 1 {
            app.update();
        }
        // The frame read is the last one that moved: time stops right after it.
        let moving_frame = scene::read_next_then(&mut app, &images, |app| set_paused(app, true));
        let truth = ground_truth(app.world_mut(), view.camera);
        for _ in 0..SETTLE {
            app.update();
        }
        let settled_frame = scene::read_next(&mut app, &images);
        set_paused(&mut app, false);
        let mask = scene::geometry_mask(&moving_frame[1]);
        let (now, still) = (
            scene::visibility(&moving_frame[0]),
            scene::visibility(&settled_frame[0]),
        );
        let darker = |image: &[f32]| {
            image
                .iter()
                .zip(&truth)
                .zip(&mask)
                .filter(|((v, t), m)| **m && **v < **t - DARKER)
                .count() as i64
        };
        moving.push(rmse(&now, &truth, Some(&mask)));
        settled.push(rmse(&still, &truth, Some(&mask)));
        trails.push(darker(&now) - darker(&still));
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    Measured {
        moving: mean(&moving),
        settled: mean(&settled),
        trail_mean: trails.iter().sum::<i64>() as f32 / trails.len() as f32,
        trail_max: trails.iter().copied().max().unwrap_or(0),
    }
}

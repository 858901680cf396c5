//! GPU time per pass, from timestamp queries, for no AO, Bevy's SSAO at each level and ours at
//! each preset, on the same scene in the same run. Prints a Markdown table.
//!
//! `cargo bench --bench gpu_passes` (add `-- --width 1920 --height 1080` for another size,
//! `-- --frames 60` for longer measurements and `-- --only "Bevy SSAO High,spheres"` to run only
//! the configurations whose names contain one of the comma-separated words).
//! The `far field, N spheres` rows splat N occluder spheres (small balls with a
//! `SphereOccluder` each, scattered over the view) with the image-space term off; the
//! `AO fields, N occluders` rows draw N toaster-sized boxes with an `AoField` each (one baked
//! 32³ field shared by all). The `voxels` rows put one `VoxelAoVolume` around the room (plus
//! extra balls for the triangle-count rows) with the image-space term off, tracing the row's rays
//! every frame (its `accumulated_rays` too; the `near + voxels` rows keep the volume's defaults,
//! 8 rays a frame under the camera's accumulation): `voxelize` is the
//! per-frame grid build, `voxel AO` the sampling of the half-resolution map, `voxel temporal` its
//! accumulation over frames (where the camera accumulates), `voxel filter` its upsampling and
//! blur. On lavapipe the voxelize dispatch's timestamps do not capture its work
//! (a run that skips the dispatch is faster by the whole difference while the span reads the
//! same), so there the `frame` column against the `voxels 8³` row is the measure of it.
//! Timings are for comparison within one run on one adapter; the table names the adapter.
//!
//! `-- --plot FILE.svg` also measures the converged error of every preset and every Bevy SSAO
//! level against the CPU ray tracer (`cost_error.rs`) and draws cost against error from this
//! run's timings; with it, `-- --grid FILE.png` writes the default's and Bevy's SSAO High's AO
//! beside the ground truth on each scene of that measurement and on a floor beside an
//! off-screen wall. `cargo bench --bench gpu_passes -- --only "preset,Bevy SSAO" --plot
//! docs/cost_error.svg --grid docs/vs_ground_truth.png` writes the README's plot and grid.

#[path = "../../examples/common/mod.rs"]
mod common;
mod cost_error;
#[path = "../../tests/gpu/harness.rs"]
#[allow(dead_code)]
mod harness;
#[path = "../../tests/gpu/log_capture.rs"]
#[allow(dead_code)]
mod log_capture;
#[path = "../../tests/gpu/scenes.rs"]
#[allow(dead_code)]
mod scenes;

use std::collections::BTreeMap;
use std::time::Instant;

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::diagnostic::DiagnosticsStore;
use bevy::pbr::{ScreenSpaceAmbientOcclusion, ScreenSpaceAmbientOcclusionQualityLevel};
use bevy::prelude::*;
use bevy::render::{
    diagnostic::RenderDiagnosticsPlugin, render_resource::TextureFormat,
    renderer::RenderAdapterInfo,
};
use bevy_dynamic_ao::fields::{ActiveAoField, PendingAoField};
use bevy_dynamic_ao::prelude::*;

const WARMUP_FRAMES: u32 = 10;

#[derive(Clone)]
enum Config {
    NoAo,
    BevySsao(ScreenSpaceAmbientOcclusionQualityLevel),
    Preset(AoPreset),
    /// The far field alone, from about this many spheres.
    Spheres(u32),
    /// AO fields alone, from this many occluders.
    Fields(u32),
    /// AO fields alone, from 16 balls of the same size tessellated into about this many
    /// triangles: the cost should not depend on it.
    FieldBalls(u32),
    /// One voxel volume alone.
    Voxels(VoxelRun),
    /// The default near field at this radius (metres), joined by one far-field term with every
    /// mesh of the room its occluder (`None`: the near field alone).
    Joined(Option<Far>, f32),
}

/// A far-field term for [`Config::Joined`].
#[derive(Clone, Copy, PartialEq)]
enum Far {
    Spheres,
    Fields,
    Voxels,
}

#[derive(Clone, Copy)]
struct VoxelRun {
    resolution: u32,
    /// Triangles added to the room's few hundred, in balls of 960.
    extra_triangles: u32,
    rays: u32,
    steps: u32,
}

/// A voxel-volume row; `steps` 0 walks every cell (the default), otherwise the paper's march.
const fn voxels(resolution: u32, extra_triangles: u32, rays: u32, steps: u32) -> Config {
    Config::Voxels(VoxelRun {
        resolution,
        extra_triangles,
        rays,
        steps,
    })
}

impl Config {
    fn name(&self) -> String {
        match self {
            Config::NoAo => "no AO".into(),
            Config::BevySsao(level) => format!("Bevy SSAO {level:?}"),
            Config::Preset(preset) => format!("preset {}", preset.name()),
            Config::Spheres(count) => format!("far field, {count} spheres"),
            Config::Fields(count) => format!("AO fields, {count} occluders"),
            Config::FieldBalls(triangles) => {
                format!("AO fields, 16 balls of {triangles} triangles")
            }
            Config::Voxels(run) => format!(
                "voxels {}³, +{}k triangles, {} rays × {}",
                run.resolution,
                run.extra_triangles / 1000,
                run.rays,
                if run.steps == 0 {
                    "every cell".to_string()
                } else {
                    format!("{} steps", run.steps)
                }
            ),
            Config::Joined(far, radius) => match far {
                None => format!("near field, R = {radius} m"),
                Some(Far::Spheres) => format!("near + spheres, R = {radius} m"),
                Some(Far::Fields) => format!("near + fields, R = {radius} m"),
                Some(Far::Voxels) => format!("near + voxels, R = {radius} m"),
            },
        }
    }
}

struct Row {
    name: String,
    frame_ms: f64,
    passes: BTreeMap<String, f64>,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str, default: u32| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    let size = UVec2::new(value("--width", 640), value("--height", 480));
    let frames = value("--frames", 30).max(1);
    let configs = [
        Config::NoAo,
        Config::BevySsao(ScreenSpaceAmbientOcclusionQualityLevel::Low),
        Config::BevySsao(ScreenSpaceAmbientOcclusionQualityLevel::Medium),
        Config::BevySsao(ScreenSpaceAmbientOcclusionQualityLevel::High),
        Config::BevySsao(ScreenSpaceAmbientOcclusionQualityLevel::Ultra),
        Config::Preset(AoPreset::Low),
        Config::Preset(AoPreset::Medium),
        Config::Preset(AoPreset::High),
        Config::Preset(AoPreset::Ultra),
        Config::Spheres(1_000),
        Config::Spheres(10_000),
        Config::Spheres(100_000),
        Config::Fields(1),
        Config::Fields(16),
        Config::Fields(256),
        Config::FieldBalls(20),
        Config::FieldBalls(10_000),
        voxels(8, 0, 32, 0),
        voxels(64, 0, 32, 0),
        voxels(128, 0, 32, 0),
        voxels(256, 0, 32, 0),
        voxels(128, 10_000, 32, 0),
        voxels(128, 100_000, 32, 0),
        voxels(128, 0, 8, 0),
        voxels(128, 0, 64, 0),
        voxels(128, 0, 32, 8),
        voxels(128, 0, 32, 16),
        Config::Joined(None, 0.75),
        Config::Joined(Some(Far::Spheres), 0.75),
        Config::Joined(Some(Far::Fields), 0.75),
        Config::Joined(Some(Far::Voxels), 0.75),
        Config::Joined(None, 2.0),
        Config::Joined(Some(Far::Spheres), 2.0),
        Config::Joined(Some(Far::Fields), 2.0),
        Config::Joined(Some(Far::Voxels), 2.0),
    ];
    let only: Option<Vec<String>> = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1))
        .map(|list| list.split(',').map(str::to_string).collect());
    let configs: Vec<Config> = configs
        .into_iter()
        .filter(|c| {
            only.as_ref()
                .is_none_or(|words| words.iter().any(|w| c.name().contains(w.as_str())))
        })
        .collect();

    let mut adapter = String::new();
    let rows: Vec<Row> = configs
        .iter()
        .map(|config| run(config, size, frames, &mut adapter))
        .collect();

    let columns = [
        ("ssao", "Bevy SSAO"),
        ("dynamic_ao_back_faces", "back faces"),
        ("dynamic_ao_near_field", "near field"),
        ("dynamic_ao_horizon", "horizon"),
        ("dynamic_ao_ray_march", "ray march"),
        ("dynamic_ao_temporal", "temporal"),
        ("dynamic_ao_upsample", "upsample"),
        ("dynamic_ao_blur", "blur"),
        ("dynamic_ao_spheres", "spheres"),
        ("dynamic_ao_fields", "fields"),
        ("dynamic_ao_voxelize", "voxelize"),
        ("dynamic_ao_voxel_ao", "voxel AO"),
        ("dynamic_ao_voxel_temporal", "voxel temporal"),
        ("dynamic_ao_voxel_filter", "voxel filter"),
        ("dynamic_ao_compose", "compose"),
    ];
    println!(
        "\nAdapter: {adapter}; {}×{}; mean of {frames} frames after {WARMUP_FRAMES}.",
        size.x, size.y
    );
    println!(
        "GPU times in ms from timestamp queries; frame = wall-clock time of one app update.\n"
    );
    print!("| configuration | frame (ms) | all passes (GPU ms) |");
    for (_, title) in columns {
        print!(" {title} |");
    }
    println!();
    println!("|---|---:|---:|{}", "---:|".repeat(columns.len()));
    for row in &rows {
        let total: f64 = row.passes.values().sum();
        print!("| {} | {:.2} | {:.3} |", row.name, row.frame_ms, total);
        for (key, _) in columns {
            match row.passes.get(key) {
                Some(ms) => print!(" {ms:.3} |"),
                None => print!(" – |"),
            }
        }
        println!();
    }

    if let Some(path) = args
        .iter()
        .position(|a| a == "--plot")
        .and_then(|i| args.get(i + 1))
    {
        // The AO passes: Bevy's SSAO or ours, not the rest of the frame.
        let ao_ms = |row: &Row| -> f64 {
            columns
                .iter()
                .filter_map(|(key, _)| row.passes.get(*key))
                .sum()
        };
        let mut points = Vec::new();
        println!("\n| configuration | AO passes (GPU ms) | mean converged RMSE |");
        println!("|---|---:|---:|");
        let measured = cost_error::measure();
        for (name, ours, rmse) in measured.errors {
            let Some(row) = rows.iter().find(|row| row.name == name) else {
                eprintln!("--plot: no timing row for {name} (left out by --only?)");
                continue;
            };
            println!("| {name} | {:.2} | {rmse:.3} |", ao_ms(row));
            points.push(cost_error::Point {
                name,
                ours,
                ms: ao_ms(row),
                rmse,
            });
        }
        let caption = format!("Cost against error, {}×{}, {adapter}", size.x, size.y);
        match cost_error::plot(&points, std::path::Path::new(path), &caption) {
            Ok(()) => println!("\nplot: {path}"),
            Err(error) => {
                eprintln!("--plot {path}: {error}");
                std::process::exit(1);
            }
        }
        if let Some(grid) = args
            .iter()
            .position(|a| a == "--grid")
            .and_then(|i| args.get(i + 1))
        {
            match cost_error::write_grid(std::path::Path::new(grid), &measured.images) {
                Ok(()) => println!("grid: {grid}"),
                Err(error) => {
                    eprintln!("--grid {grid}: {error}");
                    std::process::exit(1);
                }
            }
        }
    }
}

fn run(config: &Config, size: UVec2, frames: u32, adapter: &mut String) -> Row {
    let mut app = App::new();
    app.add_plugins((
        common::headless_plugins(),
        DynamicAoPlugin,
        RenderDiagnosticsPlugin,
    ));
    common::finish_plugins(&mut app);
    let info = app.world().get_resource::<RenderAdapterInfo>().or_else(|| {
        app.get_sub_app(bevy::render::RenderApp)
            .and_then(|render| render.world().get_resource::<RenderAdapterInfo>())
    });
    if adapter.is_empty()
        && let Some(info) = info
    {
        *adapter = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
    }
    spawn_scene(app.world_mut(), config, size);
    // Fields are baked on the async pool; measure once every occluder has its field.
    for _ in 0..2000 {
        let world = app.world_mut();
        let waiting = world
            .query_filtered::<(Has<ActiveAoField>, Has<PendingAoField>), With<AoField>>()
            .iter(world)
            .filter(|(active, pending)| !active || *pending)
            .count();
        if waiting == 0 {
            break;
        }
        app.update();
    }
    for _ in 0..WARMUP_FRAMES {
        app.update();
    }
    // Only the measured frames count: during warm-up Bevy's SSAO runs until our pipelines are
    // ready, and the first frames compile pipelines.
    for diagnostic in app
        .world_mut()
        .resource_mut::<DiagnosticsStore>()
        .iter_mut()
    {
        diagnostic.clear_history();
    }
    let start = Instant::now();
    for _ in 0..frames {
        app.update();
    }
    let frame_ms = start.elapsed().as_secs_f64() * 1000.0 / frames as f64;
    let store = app.world().resource::<DiagnosticsStore>();
    let mut passes = BTreeMap::new();
    for diagnostic in store.iter() {
        let path = diagnostic.path().as_str();
        if let Some(name) = path
            .strip_prefix("render/")
            .and_then(|p| p.strip_suffix("/elapsed_gpu"))
            && let Some(mean) = diagnostic.average()
        {
            passes.insert(name.to_string(), mean);
        }
    }
    let world = app.world_mut();
    let spheres: usize = world
        .query::<&OccluderSpheres>()
        .iter(world)
        .map(|o| o.spheres.len())
        .sum();
    let name = match config {
        Config::Spheres(_) => format!("far field, {spheres} spheres"),
        Config::Joined(Some(Far::Spheres), _) => format!("{} ({spheres} proxies)", config.name()),
        _ => config.name(),
    };
    eprintln!("{name}: {passes:?}");
    Row {
        name,
        frame_ms,
        passes,
    }
}

fn spawn_scene(world: &mut World, config: &Config, size: UVec2) {
    let target = world
        .resource_mut::<Assets<Image>>()
        .add(Image::new_target_texture(
            size.x,
            size.y,
            TextureFormat::Rgba8UnormSrgb,
            None,
        ));
    let mut camera = world.spawn((
        Camera3d::default(),
        Transform::from_xyz(-3.2, 2.6, 4.6).looking_at(Vec3::new(0.3, 0.6, 0.0), Vec3::Y),
        Msaa::Off,
        Tonemapping::None,
        RenderTarget::Image(target.into()),
    ));
    match config {
        Config::NoAo => {}
        Config::BevySsao(level) => {
            camera.insert(ScreenSpaceAmbientOcclusion {
                quality_level: *level,
                ..default()
            });
        }
        Config::Preset(preset) => {
            camera.insert(DynamicAo::from_preset(*preset));
        }
        Config::Spheres(_) => {
            camera.insert(DynamicAo {
                technique: AoTechnique::Off,
                ..default()
            });
        }
        Config::Voxels(_) => {
            camera.insert(DynamicAo {
                technique: AoTechnique::Off,
                spheres: false,
                fields: false,
                ..default()
            });
        }
        Config::Fields(_) | Config::FieldBalls(_) => {
            camera.insert(DynamicAo {
                technique: AoTechnique::Off,
                spheres: false,
                ..default()
            });
        }
        Config::Joined(far, radius) => {
            camera.insert(DynamicAo {
                radius: *radius,
                spheres: *far == Some(Far::Spheres),
                fields: *far == Some(Far::Fields),
                voxels: *far == Some(Far::Voxels),
                ..default()
            });
        }
    }
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let floor = meshes.add(Plane3d::default().mesh().size(12.0, 12.0));
    let wall = meshes.add(Cuboid::new(12.0, 4.0, 0.2));
    let cube = meshes.add(Cuboid::new(1.0, 1.0, 1.0));
    let ball = meshes.add(Sphere::new(0.5).mesh().uv(48, 24));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    let mut room = Vec::new();
    let mut spawn = |mesh: &Handle<Mesh>, transform: Transform| {
        room.push(
            world
                .spawn((
                    Mesh3d(mesh.clone()),
                    MeshMaterial3d(material.clone()),
                    transform,
                ))
                .id(),
        );
    };
    spawn(&floor, Transform::IDENTITY);
    spawn(&wall, Transform::from_xyz(0.0, 2.0, -1.6));
    for i in 0..5 {
        spawn(
            &cube,
            Transform::from_xyz(-2.0 + i as f32, 0.5, -0.9 + 0.3 * (i % 2) as f32),
        );
        spawn(&ball, Transform::from_xyz(-2.0 + i as f32, 0.5, 0.8));
    }
    if let Config::Joined(Some(far), _) = config {
        // Every mesh of the room an occluder, as `ao_capture` sets a scene up.
        for &mesh in &room {
            match far {
                Far::Spheres => {
                    world.entity_mut(mesh).insert(SphereOccluder::default());
                }
                Far::Fields => {
                    world.entity_mut(mesh).insert(AoField::default());
                }
                Far::Voxels => {}
            }
        }
        if *far == Far::Voxels {
            world.spawn((
                Transform::from_xyz(0.0, 1.3, 0.3),
                VoxelAoVolume::new(Vec3::new(4.0, 1.5, 2.5)),
            ));
        }
    }
    if let Config::Spheres(count) = config {
        // Small balls of 16 spheres each, scattered with a fixed hash over the visible room.
        let pebble = world
            .resource_mut::<Assets<Mesh>>()
            .add(Sphere::new(0.08).mesh().ico(1).expect("a small icosphere"));
        let hash = |i: u32| (i.wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32;
        for i in 0..count.div_ceil(16) {
            let position = Vec3::new(
                -3.5 + 7.0 * hash(3 * i),
                0.08 + 1.6 * hash(3 * i + 1),
                -1.4 + 3.4 * hash(3 * i + 2),
            );
            world.spawn((
                Mesh3d(pebble.clone()),
                MeshMaterial3d(material.clone()),
                Transform::from_translation(position),
                SphereOccluder {
                    count: 16,
                    ..default()
                },
            ));
        }
    }
    if let Config::Voxels(run) = config {
        let hash = |i: u32| (i.wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32;
        let ball = world
            .resource_mut::<Assets<Mesh>>()
            .add(Sphere::new(0.15).mesh().uv(32, 16));
        for i in 0..run.extra_triangles / 960 {
            world.spawn((
                Mesh3d(ball.clone()),
                MeshMaterial3d(material.clone()),
                Transform::from_xyz(
                    -3.5 + 7.0 * hash(3 * i),
                    0.15 + 2.0 * hash(3 * i + 1),
                    -1.4 + 3.4 * hash(3 * i + 2),
                ),
            ));
        }
        world.spawn((
            Transform::from_xyz(0.0, 1.3, 0.3),
            VoxelAoVolume {
                half_extents: Vec3::new(4.0, 1.5, 2.5),
                resolution: run.resolution,
                // The row's rays every frame, accumulated or not.
                rays: run.rays,
                accumulated_rays: run.rays,
                march: if run.steps == 0 {
                    VoxelMarch::Cells
                } else {
                    VoxelMarch::Steps(run.steps)
                },
                ..default()
            },
        ));
    }
    let field_occluders = match config {
        // Toaster-sized boxes on a grid over the floor, one baked field shared by all.
        Config::Fields(count) => Some((*count, Mesh::from(Cuboid::new(0.3, 0.2, 0.17)))),
        // Balls with the same bounding box (so the same grid): an icosahedron, whose vertices
        // reach 0.8507 of its radius along the axes, or a fine UV sphere.
        Config::FieldBalls(triangles) if *triangles <= 20 => Some((
            16,
            Sphere::new(0.12 / 0.8507)
                .mesh()
                .ico(0)
                .expect("an icosahedron"),
        )),
        Config::FieldBalls(_) => Some((16, Sphere::new(0.12).mesh().uv(100, 50))),
        _ => None,
    };
    if let Some((count, mesh)) = field_occluders {
        let count = &count;
        let toaster = world.resource_mut::<Assets<Mesh>>().add(mesh);
        let side = (*count as f32).sqrt().ceil() as u32;
        for i in 0..*count {
            let (u, v) = ((i % side) as f32, (i / side) as f32);
            let step = 5.0 / side as f32;
            world.spawn((
                Mesh3d(toaster.clone()),
                MeshMaterial3d(material.clone()),
                Transform::from_xyz(-2.5 + (u + 0.5) * step, 0.1, -1.2 + (v + 0.5) * step * 0.6)
                    .with_rotation(Quat::from_rotation_y(i as f32)),
                AoField::default(),
            ));
        }
    }
    world.spawn((
        DirectionalLight {
            illuminance: 3_000.0,
            ..default()
        },
        Transform::from_xyz(3.0, 6.0, 2.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
}

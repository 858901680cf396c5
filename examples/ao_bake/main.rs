//! Bakes an ambient occlusion field (`.aofield`) for every mesh of a glTF file.
//!
//! ```text
//! cargo run --release --example ao_bake -- --scene FILE.glb --out-dir DIR \
//!     [--resolution N] [--radius R] [--near-radius N] [--epsilon E] [--rays N]
//! ```
//!
//! A field counts occluders within the radius R of the cameras it will be seen by (`--radius`,
//! metres, default 0.75, the crate's default), with the near field's share within
//! `--near-radius` (default 0.5, the crate's default); `--epsilon E` bakes the paper's field
//! instead: hits at any distance, the grid's extent from eq. 4, border rescale and interior fill.
//! Each mesh primitive is baked in its own mesh space (the grid follows the object wherever it is
//! placed, and the radii count mesh units: for a model shown at another scale, divide them by
//! that scale) into `DIR/<file>_<mesh>_<primitive>.aofield`, with a progress bar on stderr and one
//! summary line per object on stdout. A missing file, a bad number or a scene without meshes
//! gives a one-line error and exit code 2 (arguments) or 1 (scene).

#[path = "../common/mod.rs"]
mod common;

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use bevy::app::ScheduleRunnerPlugin;
use bevy::asset::{AssetPlugin, LoadState, RecursiveDependencyLoadState};
use bevy::gltf::{Gltf, GltfMesh};
use bevy::math::Affine3A;
use bevy::prelude::*;
use bevy_dynamic_ao::fields::{BakeSettings, FieldReach, bake};
use bevy_dynamic_ao::geometry::triangles::TriangleScene;
use bevy_dynamic_ao::settings::{DEFAULT_NEAR_FIELD_RADIUS, DEFAULT_RADIUS};

const USAGE: &str = "usage: ao_bake --scene FILE.glb --out-dir DIR [--resolution N] \
[--radius R] [--near-radius N] [--epsilon E] [--rays N]";

/// Frames the glTF file may take to load before the run gives up.
const LOAD_TIMEOUT_FRAMES: u32 = 2000;

struct Options {
    scene: PathBuf,
    out_dir: PathBuf,
    settings: BakeSettings,
}

fn parse(args: impl IntoIterator<Item = String>) -> Result<Option<Options>, String> {
    let (mut scene, mut out_dir) = (None, None);
    let mut settings = BakeSettings::default();
    let (mut radius, mut near) = (DEFAULT_RADIUS, DEFAULT_NEAR_FIELD_RADIUS);
    let mut epsilon = None;
    let distance = |flag: &str, text: String| {
        text.parse::<f32>()
            .ok()
            .filter(|d| d.is_finite() && *d > 0.0)
            .ok_or(format!(
                "{flag} takes a positive distance in metres, got '{text}'"
            ))
    };
    let mut args = args.into_iter();
    while let Some(flag) = args.next() {
        let mut value = || args.next().ok_or_else(|| format!("{flag} needs a value"));
        match flag.as_str() {
            "--scene" => scene = Some(PathBuf::from(value()?)),
            "--out-dir" => out_dir = Some(PathBuf::from(value()?)),
            "--resolution" => {
                settings.resolution = common::parse_number("--resolution", &value()?, 2u32)?;
                if settings.resolution > 256 {
                    return Err("--resolution is at most 256".into());
                }
            }
            "--rays" => settings.rays = common::parse_number("--rays", &value()?, 1u32)?,
            "--radius" => radius = distance("--radius", value()?)?,
            "--near-radius" => near = distance("--near-radius", value()?)?,
            "--epsilon" => {
                let text = value()?;
                epsilon = Some(
                    text.parse::<f32>()
                        .ok()
                        .filter(|e| *e > 0.0 && *e < 1.0)
                        .ok_or(format!("--epsilon takes a number in (0, 1), got '{text}'"))?,
                );
            }
            "--help" | "-h" => {
                println!("{USAGE}");
                return Ok(None);
            }
            other => return Err(format!("unknown argument '{other}' (see --help)")),
        }
    }
    settings = match epsilon {
        Some(epsilon) => BakeSettings {
            reach: FieldReach::Unlimited { epsilon },
            resolution: settings.resolution,
            rays: settings.rays,
            ..BakeSettings::paper()
        },
        None => settings.for_camera(radius, near),
    };
    let scene = scene.ok_or("--scene is required (see --help)")?;
    if !scene.is_file() {
        return Err(format!("scene file {} not found", scene.display()));
    }
    let scene = std::fs::canonicalize(&scene).map_err(|e| format!("{}: {e}", scene.display()))?;
    Ok(Some(Options {
        scene,
        out_dir: out_dir.ok_or("--out-dir is required (see --help)")?,
        settings,
    }))
}

fn main() {
    let options = match parse(std::env::args().skip(1)) {
        Ok(Some(options)) => options,
        Ok(None) => return,
        Err(message) => {
            eprintln!("ao_bake: {message}");
            std::process::exit(2);
        }
    };
    // Bevy's glTF loader gives the meshes exactly as the game will see them.
    let folder = options
        .scene
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let mut app = App::new();
    app.add_plugins((
        common::headless_plugins().set(AssetPlugin {
            file_path: folder.to_string_lossy().into_owned(),
            ..default()
        }),
        ScheduleRunnerPlugin::run_loop(Duration::ZERO),
    ));
    // The app is driven by hand below, so it finishes its plugins itself (as `App::run` would).
    common::finish_plugins(&mut app);
    let file = options
        .scene
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    let gltf: Handle<Gltf> = app.world().resource::<AssetServer>().load(file);
    for _ in 0..LOAD_TIMEOUT_FRAMES {
        app.update();
        let server = app.world().resource::<AssetServer>();
        if let Some(LoadState::Failed(error)) = server.get_load_state(&gltf) {
            eprintln!("ao_bake: cannot load {}: {error}", options.scene.display());
            std::process::exit(1);
        }
        if matches!(
            server.get_recursive_dependency_load_state(&gltf),
            Some(RecursiveDependencyLoadState::Loaded)
        ) {
            break;
        }
    }
    let world = app.world();
    let Some(gltf) = world.resource::<Assets<Gltf>>().get(&gltf) else {
        eprintln!("ao_bake: {} did not load in time", options.scene.display());
        std::process::exit(1);
    };
    let (gltf_meshes, meshes) = (
        world.resource::<Assets<GltfMesh>>(),
        world.resource::<Assets<Mesh>>(),
    );
    let stem = options
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    if let Err(error) = std::fs::create_dir_all(&options.out_dir) {
        eprintln!(
            "ao_bake: cannot create {}: {error}",
            options.out_dir.display()
        );
        std::process::exit(1);
    }
    let mut baked = 0;
    for (index, handle) in gltf.meshes.iter().enumerate() {
        let Some(gltf_mesh) = gltf_meshes.get(handle) else {
            continue;
        };
        for primitive in &gltf_mesh.primitives {
            let Some(mesh) = meshes.get(&primitive.mesh) else {
                continue;
            };
            let name = format!(
                "{stem}_{}_{}",
                sanitize(&gltf_mesh.name, index),
                primitive.index
            );
            let mut triangles = TriangleScene::default();
            triangles.add_mesh(mesh, Affine3A::IDENTITY);
            let count = triangles.triangles.len();
            let started = Instant::now();
            // Slices finish out of order across threads; the bar only moves forwards.
            let shown = Mutex::new(0usize);
            let progress = |done: usize, total: usize| {
                let Ok(mut shown) = shown.lock() else {
                    return;
                };
                if done <= *shown {
                    return;
                }
                *shown = done;
                let width = 30;
                let filled = done * width / total.max(1);
                eprint!(
                    "\r{name} [{}{}] {:3}%",
                    "#".repeat(filled),
                    " ".repeat(width - filled),
                    done * 100 / total.max(1)
                );
            };
            match bake(triangles.triangles, &options.settings, &progress) {
                Ok(field) => {
                    eprintln!();
                    let path = options.out_dir.join(format!("{name}.aofield"));
                    if let Err(error) = std::fs::write(&path, field.to_bytes()) {
                        eprintln!("ao_bake: cannot write {}: {error}", path.display());
                        std::process::exit(1);
                    }
                    let size = field.half_extent * 2.0;
                    println!(
                        "{name}: {count} triangles, grid {}x{}x{} over {:.2} x {:.2} x {:.2} m, \
                         baked in {:.2} s -> {}",
                        field.resolution.x,
                        field.resolution.y,
                        field.resolution.z,
                        size.x,
                        size.y,
                        size.z,
                        started.elapsed().as_secs_f32(),
                        path.display()
                    );
                    baked += 1;
                }
                Err(error) => println!("{name}: skipped, {error}"),
            }
        }
    }
    if baked == 0 {
        eprintln!("ao_bake: {} has no mesh to bake", options.scene.display());
        std::process::exit(1);
    }
}

/// A file-name-safe form of a glTF mesh name (or its index when it has none).
fn sanitize(name: &str, index: usize) -> String {
    let cleaned: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if cleaned.is_empty() {
        format!("mesh{index}")
    } else {
        cleaned
    }
}

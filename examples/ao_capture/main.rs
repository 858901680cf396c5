//! Renders a glTF scene headless through its first camera and writes the AO buffer as a 16-bit
//! grayscale PNG of linear visibility (65535 = open, and 65535 where no geometry is).
//!
//! ```text
//! cargo run --release --example ao_capture -- --scene FILE.glb --width W --height H \
//!     --radius R --technique NAME [--preset low|medium|high|ultra] [--blur PIXELS] \
//!     [--accumulated-blur PIXELS] [--voxel-accumulated-blur PIXELS] \
//!     [--blur-sharpness S] [--blur-normal-sharpness S] [--blur-detail PIXELS] \
//!     [--thickness F] [--full-back-faces] [--half-res] \
//!     [--far-blend count-once|add|max] [--near-field-radius M] \
//!     [--voxel-falloff none|wendland] [--frames N] \
//!     [--time SECONDS] [--temporal|--no-temporal] [--history-frames N] [--msaa 1|4] \
//!     [--timings] --out-ao AO.png \
//!     [--out-color COLOR.png] [--compare SIDE_BY_SIDE.png] [--out-truth TRUTH.png]
//! ```
//!
//! `--out-color` writes the lit image (ambient light as most of the light, so the AO shows);
//! `--compare` writes it beside Bevy's SSAO and no AO (`compare.rs`); `--out-truth` writes the
//! CPU ray tracer's ground truth at the same view and prints the capture's RMSE against it
//! (`truth.rs`).
//!
//! `--technique default` captures what `DynamicAo::from_preset(--preset)` runs (with the default
//! preset, `DynamicAo::default()`). Every technique gets the level's sample budgets and its
//! temporal accumulation (on above `low`; `--temporal` and `--no-temporal` override it);
//! `--history-frames N` sets how many samples a history averages (`AoTemporal::max_frames`,
//! default 16).
//! `--frames N` renders N frames with a still camera before the capture, counted from the frame
//! the scene is ready and the camera's AO shown (`DynamicAoStatus`: not while its shaders still
//! load), where an accumulated history starts over, so that captures are
//! reproducible (default: 4, or where the occlusion is accumulated twice the frames its history
//! spans, so the capture shows it converged: 64 for the ray march, 32 for the others, with the
//! default history).
//! `--timings` then prints one line,
//! `timings: ao_gpu_ms=<mean GPU ms of the AO passes> frame_gpu_ms=<all passes> frames=<n>`, over
//! the frames rendered once the scene was ready, waiting for the last ones' spans (for
//! `bevy-ssao` the AO pass is Bevy's own).
//! `--msaa 4` renders with 4 samples per pixel (default 1, off; the AO passes read a
//! single-sampled front layer that holds what a prepass without MSAA would).
//! `--full-back-faces` draws the back-face layer from every mesh as it is, without the coarse
//! copies of meshes of many triangles (`DynamicAo::coarse_back_faces` off), to measure what
//! they change.
//!
//! `--technique list` prints the technique names: the image-space ones, the far-field terms alone
//! (`spheres`: a `SphereOccluder` on the scene root so every mesh casts it; `fields`: an AO field
//! baked for every mesh; `voxels`: one `VoxelAoVolume` over what occludes the surfaces the camera
//! sees within the radius, traced on the CPU, reaching the radius: `volume.rs`) and each
//! image-space one, and `default`, with `+spheres`, `+fields` or `+voxels` added. Bevy's own SSAO
//! (`bevy-ssao`) has a radius fixed in its shader (about 0.73 m); `--radius` applies to every other
//! technique.

#[path = "../common/mod.rs"]
mod common;
mod compare;
#[path = "../common/far_terms.rs"]
mod far_terms;
mod options;
mod preflight;
mod scene;
mod timings;
mod truth;
mod undrawable;
mod volume;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::app::ScheduleRunnerPlugin;
use bevy::asset::{AssetPlugin, LoadState};
use bevy::camera::RenderTarget;
use bevy::diagnostic::DiagnosticsStore;
use bevy::gltf::Gltf;
use bevy::prelude::*;
use bevy::render::{
    diagnostic::RenderDiagnosticsPlugin,
    gpu_readback::{Readback, ReadbackComplete},
    view::screenshot::{Screenshot, ScreenshotCaptured},
};
use bevy::world_serialization::WorldAsset;
use bevy_dynamic_ao::fields::{ActiveAoField, PendingAoField};
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::nd_buffer::ViewMatrices;
use bevy_dynamic_ao::reference::png16::write_visibility_png;
use options::{FarTerm, Options};

/// Frames rendered once the scene is ready before `--timings` starts measuring (timestamps
/// come back a few frames late).
const TIMING_WARMUP_FRAMES: u32 = 8;

/// Frames after the read-back began that `--timings` waits at most for the AO passes' spans of
/// the frames `--frames` counts (an adapter without timestamp queries never sends them).
const TIMING_WAIT_FRAMES: u32 = 30;

/// Frames after the scene is ready by which the plugin has looked at every `AoField` occluder:
/// from then on one with neither an active nor a pending field casts none (its bake failed, and
/// the plugin said why), and the capture does not wait for it.
const FIELD_RESOLVE_FRAMES: u32 = 4;

/// Frames a scene may take to load before the run gives up.
const LOAD_TIMEOUT_FRAMES: u32 = 2000;
/// How long the AO fields of `--technique fields` may take to bake. A bake's time grows with the
/// mesh's triangles, not with frames: a 60k-triangle model takes seconds to minutes on a small
/// CPU, while frames run as fast as the renderer allows.
const BAKE_TIMEOUT: Duration = Duration::from_secs(900);

fn main() {
    let options = match Options::parse(std::env::args().skip(1)) {
        Ok(Some(options)) => options,
        Ok(None) => return,
        Err(message) => {
            eprintln!("ao_capture: {message}");
            std::process::exit(2);
        }
    };
    if let Err(message) = preflight::check(&options.scene) {
        eprintln!("ao_capture: {message}");
        std::process::exit(1);
    }
    let folder = options
        .scene
        .parent()
        .map(PathBuf::from)
        .unwrap_or_default();
    let file = options
        .scene
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();

    let timings = options.timings;
    let mut app = App::new();
    app.add_plugins((
        common::headless_plugins().set(AssetPlugin {
            file_path: folder.to_string_lossy().into_owned(),
            ..default()
        }),
        ScheduleRunnerPlugin::run_loop(Duration::ZERO),
        DynamicAoPlugin,
    ))
    .insert_resource(Capture {
        options,
        file,
        stage: Stage::Loading,
        frames: 0,
        gltf: Handle::default(),
        scene: Handle::default(),
        root: None,
        readback: None,
        visibility: None,
        color_done: false,
        compare: None,
        failure: None,
        volume: None,
        stage_start: 0,
        placing: None,
        started: Instant::now(),
        truth_line: None,
    })
    .add_systems(Startup, scene::load_scene)
    .add_systems(
        Update,
        (volume::place_volume, truth::write_truth, drive).chain(),
    )
    .add_systems(
        PostUpdate,
        undrawable::neutralize_unplaceable_cameras
            .after(TransformSystems::Propagate)
            .before(bevy::camera::visibility::VisibilitySystems::UpdateFrusta),
    );
    if timings {
        app.add_plugins(RenderDiagnosticsPlugin);
    }
    let exit = app.run();
    if let AppExit::Error(_) = exit {
        std::process::exit(1);
    }
}

#[derive(PartialEq, Eq, Debug, Clone, Copy)]
enum Stage {
    Loading,
    /// The scene is in the world. `until`: the frame the capture is read back, set once the
    /// scene, fields and volume are ready and the `--frames` count begins (`None` before: the
    /// frames until then show Bevy's SSAO standing in, or nothing yet).
    Rendering {
        until: Option<u32>,
    },
    /// The capture is being read back; `since`: the frame the read-back began.
    Reading {
        since: u32,
    },
}

#[derive(Resource)]
struct Capture {
    options: Options,
    file: String,
    stage: Stage,
    frames: u32,
    gltf: Handle<Gltf>,
    scene: Handle<WorldAsset>,
    root: Option<Entity>,
    readback: Option<AoReadback>,
    visibility: Option<Vec<f32>>,
    color_done: bool,
    /// `--compare`: the Bevy's-SSAO and no-AO views beside ours.
    compare: Option<compare::Compare>,
    failure: Option<String>,
    /// The voxel volume of `--technique voxels`, once the view's surfaces are known.
    volume: Option<Entity>,
    /// The frame rendering began.
    stage_start: u32,
    /// The read-back of the front ND layer the voxel volume is placed from, while it runs.
    placing: Option<Arc<Mutex<Option<Vec<u8>>>>>,
    /// When the run began.
    started: Instant,
    /// `--out-truth`: the line that says how far the capture lies from ground truth, once
    /// traced and written.
    truth_line: Option<String>,
}

/// The view and projection of the camera the capture renders through.
fn capture_view(world: &mut World) -> Option<ViewMatrices> {
    world
        .query_filtered::<(&GlobalTransform, &Camera), With<AoReadback>>()
        .iter(world)
        .next()
        .map(|(transform, camera)| {
            ViewMatrices::new(transform.to_matrix(), camera.clip_from_view())
        })
}

fn drive(
    mut commands: Commands,
    mut capture: ResMut<Capture>,
    assets: Res<AssetServer>,
    fields: Query<(Has<ActiveAoField>, Has<PendingAoField>), With<AoField>>,
    mut diagnostics: Option<ResMut<DiagnosticsStore>>,
    mut ours: Query<(&mut DynamicAo, Option<&DynamicAoStatus>), With<AoReadback>>,
    mut exit: MessageWriter<AppExit>,
) {
    capture.frames += 1;
    let resolving = capture.frames < capture.stage_start + FIELD_RESOLVE_FRAMES;
    let fields_baking = fields
        .iter()
        .any(|(active, pending)| pending || (!active && resolving));
    // Bevy's SSAO stands in while a new camera's passes start: those frames do not count.
    let shown = ours
        .iter()
        .any(|(_, status)| status.is_some_and(|s| s.shown != AoShown::Pending));
    let ready = capture.stage != Stage::Loading
        && shown
        && capture.frames >= capture.stage_start + TIMING_WARMUP_FRAMES
        && !(capture.options.far == Some(FarTerm::Voxels) && capture.volume.is_none())
        && !fields_baking;
    if !ready && let Some(store) = diagnostics.as_deref_mut() {
        timings::forget(store);
    }
    // The frames `--frames` counts begin on the first frame the scene is ready, with the AO's
    // history started over there (where it accumulates), so that every capture of a view
    // accumulates the same frames.
    if ready && capture.stage == (Stage::Rendering { until: None }) {
        capture.stage = Stage::Rendering {
            until: Some(capture.frames.saturating_add(capture.options.frames)),
        };
        for (mut ao, _) in &mut ours {
            if ao.temporal.enabled {
                ao.temporal.reset = true;
            }
        }
    }
    if let Some(failure) = capture.failure.take() {
        eprintln!("ao_capture: {failure}");
        exit.write(AppExit::error());
        return;
    }
    match capture.stage {
        Stage::Loading => {
            if let Some(LoadState::Failed(err)) = assets.get_load_state(&capture.scene) {
                eprintln!(
                    "ao_capture: cannot load {}: {err}",
                    capture.options.scene.display()
                );
                exit.write(AppExit::error());
            } else if capture.frames > LOAD_TIMEOUT_FRAMES {
                eprintln!(
                    "ao_capture: {} did not load in time",
                    capture.options.scene.display()
                );
                exit.write(AppExit::error());
            }
        }
        Stage::Rendering { .. }
            if capture.options.far == Some(FarTerm::Voxels) && capture.volume.is_none() =>
        {
            // Mesh bounds appear a frame after the scene spawns.
            if capture.frames > LOAD_TIMEOUT_FRAMES {
                eprintln!("ao_capture: the scene's bounds never became known");
                exit.write(AppExit::error());
            }
        }
        Stage::Rendering { .. } if fields_baking => {
            // Fields still baking: the capture waits for them, within the bake time limit.
            if capture.started.elapsed() > BAKE_TIMEOUT {
                eprintln!(
                    "ao_capture: the AO fields were not baked within {} s",
                    BAKE_TIMEOUT.as_secs()
                );
                exit.write(AppExit::error());
            }
        }
        Stage::Rendering { until: None }
            if !shown && capture.frames > capture.stage_start + LOAD_TIMEOUT_FRAMES =>
        {
            eprintln!("ao_capture: the AO passes never came into the image (see the errors above)");
            exit.write(AppExit::error());
        }
        Stage::Rendering { until: Some(until) } if capture.frames >= until => {
            let Some(readback) = capture.readback.clone() else {
                return;
            };
            commands
                .spawn(Readback::texture(readback.visibility.clone()))
                .observe(store_visibility);
            capture.stage = Stage::Reading {
                since: capture.frames,
            };
        }
        Stage::Rendering { .. } => {}
        Stage::Reading { since } => {
            let out_color = capture.options.out_color.as_ref();
            let compared = match capture.compare.as_ref().map(|c| c.finish(out_color)) {
                None => true,
                Some(None) => false,
                Some(Some(Ok(()))) => true,
                Some(Some(Err(failure))) => {
                    eprintln!("ao_capture: {failure}");
                    exit.write(AppExit::error());
                    return;
                }
            };
            // With `--compare` its screenshot of our target also gives `--out-color`.
            let color_ready = compared
                && (capture.options.out_color.is_none()
                    || capture.color_done
                    || capture.compare.is_some())
                && (capture.options.out_truth.is_none() || capture.truth_line.is_some());
            // A short capture's spans are still on their way when its image is back.
            let bevy_ssao = capture.options.technique == AoTechnique::BevySsao;
            let timed = !capture.options.timings
                || capture.frames >= since + TIMING_WAIT_FRAMES
                || diagnostics.as_deref().is_none_or(|store| {
                    timings::measured(store, bevy_ssao, capture.options.frames)
                });
            if let (Some(visibility), true) = (capture.visibility.as_ref(), color_ready && timed) {
                let options = &capture.options;
                if let Err(err) =
                    write_visibility_png(&options.out_ao, options.width, options.height, visibility)
                {
                    eprintln!(
                        "ao_capture: cannot write {}: {err}",
                        options.out_ao.display()
                    );
                    exit.write(AppExit::error());
                    return;
                }
                let open = visibility.iter().sum::<f32>() / visibility.len().max(1) as f32;
                println!(
                    "ao_capture: {} technique {} radius {} -> {} (mean visibility {open:.4})",
                    options.scene.display(),
                    options.technique_name(),
                    options.radius,
                    options.out_ao.display()
                );
                if let Some(line) = &capture.truth_line {
                    println!("{line}");
                }
                if let (true, Some(store)) = (options.timings, diagnostics.as_deref()) {
                    println!("{}", timings::summary(store, bevy_ssao));
                }
                exit.write(AppExit::Success);
            } else if capture.frames > LOAD_TIMEOUT_FRAMES * 2 {
                eprintln!("ao_capture: the GPU read-back never completed");
                exit.write(AppExit::error());
            }
        }
    }
}

fn store_visibility(
    readback: On<ReadbackComplete>,
    mut commands: Commands,
    mut capture: ResMut<Capture>,
    cameras: Query<&RenderTarget, With<AoReadback>>,
) {
    if capture.visibility.is_some() {
        return;
    }
    let (w, h) = (
        capture.options.width as usize,
        capture.options.height as usize,
    );
    let visibility = common::unpad_f32(&readback.data, w, h, 1);
    // −1: the camera's passes have not compiled yet; the read-back goes on every frame.
    if visibility.first().is_some_and(|v| *v < 0.0) {
        return;
    }
    capture.visibility = Some(visibility);
    commands.entity(readback.entity).despawn();
    if let Some(compare) = &capture.compare {
        // Its screenshot of our target also writes `--out-color` (one screenshot per target).
        compare.capture(&mut commands);
        return;
    }
    // The lit image is captured once the AO is, from the same frame onwards.
    if let Some(out) = capture.options.out_color.clone()
        && let Some(RenderTarget::Image(target)) = cameras.iter().next()
    {
        {
            commands
                .spawn(Screenshot::image(target.handle.clone()))
                .observe(
                    move |shot: On<ScreenshotCaptured>, mut capture: ResMut<Capture>| {
                        match shot.image.clone().try_into_dynamic() {
                            Ok(image) => {
                                if let Err(err) = image.to_rgba8().save(&out) {
                                    capture.failure =
                                        Some(format!("cannot write {}: {err}", out.display()));
                                }
                            }
                            Err(err) => {
                                capture.failure = Some(format!("cannot convert the image: {err}"))
                            }
                        }
                        capture.color_done = true;
                    },
                );
        }
    }
}

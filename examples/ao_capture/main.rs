//! Renders a glTF scene headless through its first camera and writes the AO buffer as a 16-bit
//! grayscale PNG of linear visibility (65535 = open, and 65535 where no geometry is).
//!
//! ```text
//! cargo run --release --example ao_capture -- --scene FILE.glb --width W --height H \
//!     --radius R --technique NAME [--preset low|medium|high|ultra] [--blur PIXELS] \
//!     [--half-res] [--far-blend count-once|add|max] [--voxel-falloff none|wendland] [--frames N] \
//!     [--time SECONDS] [--temporal|--no-temporal] [--msaa 1|4] [--timings] --out-ao AO.png \
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
//! temporal accumulation (on above `low`; `--temporal` and `--no-temporal` override it).
//! `--frames N` renders N frames with a still camera before the capture, counted from the frame
//! the scene is ready, where an accumulated history starts over, so that captures are
//! reproducible (default: 4, or 32 where the occlusion is accumulated, twice its history, so the
//! capture shows it converged). `--timings` then prints one line,
//! `timings: ao_gpu_ms=<mean GPU ms of the AO passes> frame_gpu_ms=<all passes> frames=<n>`, over
//! the frames rendered once the scene was ready (for `bevy-ssao` the AO pass is Bevy's own).
//! `--msaa 4` renders with 4 samples per pixel (default 1, off; the AO passes read a
//! single-sampled front layer that holds what a prepass without MSAA would).
//!
//! `--technique list` prints the technique names: the image-space ones, the far-field terms alone
//! (`spheres`: a `SphereOccluder` on the scene root so every mesh casts it; `fields`: an AO field
//! baked for every mesh; `voxels`: one `VoxelAoVolume` over what occludes the surfaces the
//! camera sees within the radius, traced on the CPU, reaching the radius) and each image-space
//! one, and `default`, with `+spheres`, `+fields` or `+voxels` added. Bevy's own SSAO (`bevy-ssao`) has a radius
//! fixed in its shader (about 0.73 m); `--radius` applies to every other technique.

#[path = "../common/mod.rs"]
mod common;
mod compare;
#[path = "../common/far_terms.rs"]
mod far_terms;
mod options;
mod preflight;
mod timings;
mod truth;
mod undrawable;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::app::ScheduleRunnerPlugin;
use bevy::asset::{AssetPlugin, LoadState};
use bevy::camera::RenderTarget;
use bevy::diagnostic::DiagnosticsStore;
use bevy::gltf::{Gltf, GltfAssetLabel};
use bevy::prelude::*;
use bevy::render::{
    diagnostic::RenderDiagnosticsPlugin,
    gpu_readback::{Readback, ReadbackComplete},
    render_resource::TextureFormat,
    view::screenshot::{Screenshot, ScreenshotCaptured},
};
use bevy::world_serialization::{WorldAsset, WorldAssetRoot, WorldInstanceReady};
use bevy_dynamic_ao::fields::{ActiveAoField, PendingAoField};
use bevy_dynamic_ao::geometry::bvh::Bvh;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::nd_buffer::{NdTexel, ViewMatrices};
use bevy_dynamic_ao::reference::png16::write_visibility_png;
use bevy_dynamic_ao::reference::posed::{descendants, posed_triangles_of};
use options::{FarTerm, Options};

/// Frames rendered once the scene is ready before `--timings` starts measuring (timestamps
/// come back a few frames late).
const TIMING_WARMUP_FRAMES: u32 = 8;

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
        counting: false,
        placing: None,
        started: Instant::now(),
        truth_line: None,
    })
    .add_systems(Startup, load_scene)
    .add_systems(Update, (place_volume, write_truth, drive).chain())
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
    Rendering { until: u32 },
    Reading,
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
    /// Whether the frames counted by `--frames` have begun: from the first frame the scene is
    /// ready, with the AO's history started over there (where it accumulates), so that every
    /// capture of a view accumulates the same frames.
    counting: bool,
    /// The read-back of the front ND layer the voxel volume is placed from, while it runs.
    placing: Option<Arc<Mutex<Option<Vec<u8>>>>>,
    /// When the run began.
    started: Instant,
    /// `--out-truth`: the line that says how far the capture lies from ground truth, once
    /// traced and written.
    truth_line: Option<String>,
}

fn load_scene(mut commands: Commands, assets: Res<AssetServer>, mut capture: ResMut<Capture>) {
    capture.gltf = assets.load(capture.file.clone());
    capture.scene = assets.load(GltfAssetLabel::Scene(0).from_asset(capture.file.clone()));
    let root = commands
        .spawn(WorldAssetRoot(capture.scene.clone()))
        .observe(scene_ready)
        .id();
    capture.root = Some(root);
}

/// Once the scene is spawned: pick its first camera, point it at our image, pose the animation.
fn scene_ready(
    ready: On<WorldInstanceReady>,
    mut commands: Commands,
    mut capture: ResMut<Capture>,
    children: Query<&Children>,
    cameras: Query<Option<&Projection>, With<Camera3d>>,
    transforms: Query<(&Transform, Option<&ChildOf>)>,
    meshes: Query<(
        &Mesh3d,
        Option<&Name>,
        Has<bevy::mesh::skinning::SkinnedMesh>,
    )>,
    mesh_assets: Res<Assets<Mesh>>,
    players: Query<Entity, With<AnimationPlayer>>,
    gltfs: Res<Assets<Gltf>>,
    mut graphs: ResMut<Assets<AnimationGraph>>,
    mut images: ResMut<Assets<Image>>,
) {
    // Depth-first in node order: the first camera of the glTF file.
    let mut stack = vec![ready.entity];
    let mut found = Vec::new();
    while let Some(entity) = stack.pop() {
        if cameras.contains(entity) {
            found.push(entity);
        }
        if let Ok(kids) = children.get(entity) {
            stack.extend(kids.iter().rev());
        }
    }
    let Some((&camera, others)) = found.split_first() else {
        capture.failure = Some(format!("{} has no camera", capture.options.scene.display()));
        return;
    };
    if undrawable::unplaceable(camera, &transforms) {
        capture.failure = Some(format!(
            "{}: the first camera's node has a zero scale or a value that is not finite in its \
             transform (or in an ancestor's), so it has no view direction",
            capture.options.scene.display()
        ));
        return;
    }
    undrawable::leave_out_undrawable(
        &mut commands,
        ready.entity,
        &children,
        &meshes,
        &mesh_assets,
    );
    for &other in others {
        commands.entity(other).insert(Camera {
            is_active: false,
            ..default()
        });
    }
    let options = &capture.options;
    let size = UVec2::new(options.width, options.height);
    let target = images.add(Image::new_target_texture(
        size.x,
        size.y,
        TextureFormat::Rgba8UnormSrgb,
        None,
    ));
    let readback = AoReadback::new(&mut images, size);
    if let Some(out) = options.compare.clone() {
        let projection = cameras
            .get(camera)
            .ok()
            .flatten()
            .cloned()
            .unwrap_or_default();
        capture.compare = Some(compare::Compare::spawn_peers(
            &mut commands,
            &mut images,
            camera,
            projection,
            target.clone(),
            size,
            compare::lit(),
            out,
        ));
    }
    let options = &capture.options;
    commands.entity(camera).insert((
        compare::lit(),
        RenderTarget::Image(target.into()),
        Msaa::from_samples(options.msaa),
        DynamicAo {
            technique: options.technique,
            radius: options.radius,
            blur: AoBlur {
                radius: options.blur,
                ..default()
            },
            half_resolution: options.half_resolution
                || (options.default_technique && options.preset.half_resolution()),
            spheres: options.far == Some(FarTerm::Spheres),
            fields: options.far == Some(FarTerm::Fields),
            voxels: options.far == Some(FarTerm::Voxels),
            far_field_blend: options.far_blend,
            temporal: options.temporal,
            // Every technique's budget at the chosen level.
            ..DynamicAo::from_preset(options.preset)
        },
        readback.clone(),
    ));
    if let Some(term @ (FarTerm::Fields | FarTerm::Spheres)) = options.far {
        // Every mesh of the scene an occluder (fields are baked on load, or read from the disk
        // cache, each in its mesh's own space).
        let scene_meshes: Vec<Entity> = children
            .iter_descendants(ready.entity)
            .filter(|e| {
                meshes.get(*e).is_ok_and(|(mesh, _, _)| {
                    mesh_assets
                        .get(&mesh.0)
                        .is_none_or(|m| undrawable::why_undrawable(m).is_none())
                })
            })
            .collect();
        term.attach(&mut commands, &scene_meshes, (Vec3::ZERO, Vec3::ZERO), 0.0);
    }
    capture.readback = Some(readback);

    if let Some(clip) = gltfs
        .get(&capture.gltf)
        .and_then(|gltf| gltf.animations.first().cloned())
    {
        let (graph, node) = AnimationGraph::from_clip(clip);
        let graph = graphs.add(graph);
        let time = capture.options.time;
        for player in &players {
            commands
                .entity(player)
                .insert(AnimationGraphHandle(graph.clone()));
            commands.queue(move |world: &mut World| {
                if let Some(mut player) = world.get_mut::<AnimationPlayer>(player) {
                    player.play(node).seek_to(time).pause();
                }
            });
        }
    }
    let until = capture.frames + capture.options.frames;
    capture.stage = Stage::Rendering { until };
    capture.stage_start = capture.frames;
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

/// `--out-truth`: once the capture is read, traces the posed scene through its camera on the CPU
/// and writes the result beside it (`truth.rs`).
fn write_truth(world: &mut World) {
    let capture = world.resource::<Capture>();
    let (Some(out), Some(captured), None, Some(root)) = (
        capture.options.out_truth.clone(),
        capture.visibility.clone(),
        capture.truth_line.as_ref(),
        capture.root,
    ) else {
        return;
    };
    let (width, height) = (capture.options.width, capture.options.height);
    let radius = capture.options.radius;
    let below = descendants(world, root);
    let scene = posed_triangles_of(world, |e| below.contains(&e));
    let Some(view) = capture_view(world) else {
        return;
    };
    let bvh = Bvh::new(scene.triangles);
    let truth = truth::trace(&bvh, &view, (width, height), radius, &captured);
    let mut capture = world.resource_mut::<Capture>();
    if let Err(err) = write_visibility_png(&out, width, height, &truth.visibility) {
        capture.failure = Some(format!("cannot write {}: {err}", out.display()));
        return;
    }
    capture.truth_line = Some(format!(
        "ground truth: {} (CPU ray tracer, {} rays per pixel, R = {radius}); RMSE of the capture \
         {:.4} over the {} pixels that show geometry",
        out.display(),
        truth::RAYS_PER_PIXEL,
        truth.rmse,
        truth.pixels
    ));
}

/// Frames rendered before the view's surfaces are read to place the voxel volume.
const FRAMES_BEFORE_PLACING: u32 = 3;

/// `--technique voxels`: one volume over what occludes the surfaces the camera sees within the
/// radius (`far_terms::occluder_bounds`, traced on the CPU against the posed scene), so its
/// cells are as fine as the occlusion allows; its rays reach as far as the radius. The view's
/// surfaces come from the front layer of the ND-buffer after a few frames. Where nothing
/// occludes them, the volume covers the whole scene.
fn place_volume(world: &mut World) {
    let capture = world.resource::<Capture>();
    let (Stage::Rendering { .. }, Some(FarTerm::Voxels), None, Some(root), Some(readback)) = (
        capture.stage,
        capture.options.far,
        capture.volume,
        capture.root,
        capture.readback.clone(),
    ) else {
        return;
    };
    let Some(placing) = capture.placing.clone() else {
        if capture.frames >= capture.stage_start + FRAMES_BEFORE_PLACING {
            let front: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
            let store = front.clone();
            world
                .spawn(Readback::texture(readback.front.clone()))
                .observe(move |done: On<ReadbackComplete>, mut commands: Commands| {
                    *store.lock().unwrap() = Some(done.data.clone());
                    commands.entity(done.entity).despawn();
                });
            world.resource_mut::<Capture>().placing = Some(front);
        }
        return;
    };
    let Some(bytes) = placing.lock().unwrap().take() else {
        return;
    };
    let (width, height) = (capture.options.width, capture.options.height);
    let radius = capture.options.radius;
    let falloff = capture.options.voxel_falloff;
    let texels: Vec<NdTexel> = common::unpad_f32(&bytes, width as usize, height as usize, 4)
        .chunks_exact(4)
        .map(|c| NdTexel::from_rgba([c[0], c[1], c[2], c[3]]))
        .collect();
    let below = descendants(world, root);
    let scene = posed_triangles_of(world, |e| below.contains(&e));
    let (lo, hi) = scene.bounds();
    if !lo.is_finite() || !hi.is_finite() {
        world.resource_mut::<Capture>().failure = Some("the scene has no triangles".into());
        return;
    }
    let view = capture_view(world);
    let bvh = Bvh::new(scene.triangles);
    let region = view
        .and_then(|view| far_terms::occluder_bounds(&bvh, &texels, width, height, &view, radius))
        .unwrap_or((lo, hi));
    let meshes: Vec<Entity> = below
        .iter()
        .copied()
        .filter(|e| world.get::<Mesh3d>(*e).is_some())
        .collect();
    let mut commands = world.commands();
    let volume = FarTerm::Voxels.attach(
        &mut commands,
        &meshes,
        region,
        far_terms::VOXEL_MARGIN * radius,
    );
    world.flush();
    if let Some(volume) = volume
        && let Some(mut settings) = world.get_mut::<VoxelAoVolume>(volume)
    {
        settings.falloff = falloff;
    }
    let mut capture = world.resource_mut::<Capture>();
    capture.volume = volume;
    // The frames to render start now that the volume exists.
    capture.stage = Stage::Rendering {
        until: capture.frames + capture.options.frames,
    };
}

fn drive(
    mut commands: Commands,
    mut capture: ResMut<Capture>,
    assets: Res<AssetServer>,
    fields: Query<(Has<ActiveAoField>, Has<PendingAoField>), With<AoField>>,
    mut diagnostics: Option<ResMut<DiagnosticsStore>>,
    mut ours: Query<&mut DynamicAo, With<AoReadback>>,
    mut exit: MessageWriter<AppExit>,
) {
    capture.frames += 1;
    let resolving = capture.frames < capture.stage_start + FIELD_RESOLVE_FRAMES;
    let fields_baking = fields
        .iter()
        .any(|(active, pending)| pending || (!active && resolving));
    // Bevy's SSAO stands in while a new camera's passes start: those frames do not count.
    let ready = capture.stage != Stage::Loading
        && capture.frames >= capture.stage_start + TIMING_WARMUP_FRAMES
        && !(capture.options.far == Some(FarTerm::Voxels) && capture.volume.is_none())
        && !fields_baking;
    if !ready && let Some(store) = diagnostics.as_deref_mut() {
        timings::forget(store);
    }
    if ready && !capture.counting && matches!(capture.stage, Stage::Rendering { .. }) {
        capture.counting = true;
        capture.stage = Stage::Rendering {
            until: capture.frames + capture.options.frames,
        };
        for mut ao in &mut ours {
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
        Stage::Rendering { until } if capture.frames >= until => {
            let Some(readback) = capture.readback.clone() else {
                return;
            };
            commands
                .spawn(Readback::texture(readback.visibility.clone()))
                .observe(store_visibility);
            capture.stage = Stage::Reading;
        }
        Stage::Rendering { .. } => {}
        Stage::Reading => {
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
            if let (Some(visibility), true) = (capture.visibility.as_ref(), color_ready) {
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
                    let bevy_ssao = options.technique == AoTechnique::BevySsao;
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
    capture.visibility = Some(common::unpad_f32(&readback.data, w, h, 1));
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

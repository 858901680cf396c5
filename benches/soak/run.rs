//! The soak run itself, shared by the benchmark binary (`main.rs`, 10,000 frames) and the GPU
//! test that CI runs (1,000 frames).
//!
//! One camera renders a floor and a box into a small image while, on a fixed schedule, occluders
//! of every kind spawn and despawn (each with a mesh of its own, so every per-mesh cache must
//! let go of it), a voxel volume comes and goes, the target image is replaced by one of another
//! size, the preset and the techniques change, MSAA toggles and `DynamicAo` is taken off the
//! camera and put back. Process memory (RSS, which on lavapipe holds the GPU's memory as well)
//! and the plugin's GPU bytes ([`DynamicAoGpuMemory`]) are sampled at checkpoints.

use std::time::Duration;

use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::time::TimeUpdateStrategy;
use bevy_dynamic_ao::DynamicAoGpuMemory;
use bevy_dynamic_ao::fields::{AoFieldCache, BakeSettings};
use bevy_dynamic_ao::prelude::*;

/// Sizes the target cycles through, pixels, one every 400 frames: 64×48 first.
const SIZES: [UVec2; 4] = [
    UVec2::new(64, 48),
    UVec2::new(80, 60),
    UVec2::new(64, 48),
    UVec2::new(48, 36),
];
/// Frames after which the schedule of the 10,000-frame benchmark repeats.
pub const CYCLE: u32 = 1600;
/// Occluders alive at once; the oldest goes when one more comes.
const MAX_OCCLUDERS: usize = 6;

/// Memory at one frame.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    pub frame: u32,
    /// Resident set size of the process, bytes (0 where `/proc` does not exist).
    pub rss: u64,
    /// What [`DynamicAoGpuMemory`] reports, bytes.
    pub gpu: u64,
    /// Entities in the main world.
    pub entities: u32,
    /// Mesh assets in the main world.
    pub meshes: usize,
}

/// The environment a run is measured in: glibc's allocator limited to one arena. With one arena
/// per thread (its default), which threads come to allocate depends on the machine's load, and
/// each that does first adds its own pages: on a busy two-core machine, RSS rose in steps of 4 to
/// 15 MiB in the last 400 frames of a run that leaked nothing (14.4 MiB in all), and stayed flat
/// from frame 400 to 1,000 in the same run with one arena. Growth is then what the process
/// keeps, not which threads kept it.
pub const ONE_ARENA: (&str, &str) = ("MALLOC_ARENA_MAX", "1");

/// The Khronos validation layer kept off in a measured run. Debug builds ask wgpu for validation,
/// and wgpu then loads the layer wherever it is installed (`vulkan-validationlayers`): its
/// records of every object and command grew RSS by 13 MiB over the last 500 frames of a run
/// whose growth is 0.1 MiB without it, on the same lavapipe, in one arena. The soak measures
/// what this crate and the driver keep, not a debugging layer's bookkeeping.
pub const NO_VALIDATION_LAYER: (&str, &str) = ("WGPU_VALIDATION", "0");

/// The environment a run is measured in: [`ONE_ARENA`] and [`NO_VALIDATION_LAYER`].
const MEASURED: [(&str, &str); 2] = [ONE_ARENA, NO_VALIDATION_LAYER];

/// Whether this process runs in the environment a run is measured in; if not, the caller runs
/// itself again in it ([`again_measured`]).
pub fn is_measured() -> bool {
    MEASURED
        .iter()
        .all(|(name, value)| std::env::var_os(name).is_some_and(|set| set == *value))
}

/// This executable with `args`, in the environment a run is measured in ([`ONE_ARENA`],
/// [`NO_VALIDATION_LAYER`]).
pub fn again_measured<I, S>(args: I) -> std::process::Command
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    let mut command = std::process::Command::new(std::env::current_exe().expect("own path"));
    command.args(args).envs(MEASURED);
    command
}

/// The frame of the warm checkpoint of a schedule that repeats every `cycle` frames: a quarter
/// cycle after the first whole one ([`Report::warm`] says why). Growth is measured from there.
pub fn warm_frame(cycle: u32) -> u32 {
    cycle + cycle / 4
}

/// Most the RSS may grow from the warm checkpoint to the end, bytes.
pub const RSS_GROWTH_BOUND: u64 = 8 << 20;
/// Growth past which the run stops rather than exhaust the machine's memory, bytes.
const RSS_STOP: u64 = 4 << 30;
/// Most GPU bytes the plugin may hold at any checkpoint: the run's largest state (a 32³ voxel
/// grid, six small fields of 112 bytes per cell, the temporal histories of an 80×60 view) took
/// 407,216 bytes in CI's 1,000 frames since views of at most 240×180 run at full resolution
/// (`DynamicAo::small_viewport_pixels`: the histories and the blur's textures are 80×60, not
/// 40×30); at half resolution 292,016 bytes in the 10,000-frame run and 264,368 in CI's.
pub const GPU_BYTES_BOUND: u64 = 448 << 10;

/// What a run's memory did.
pub struct Verdict {
    /// The run stopped early, its memory running away.
    pub stopped: bool,
    /// RSS at the end less RSS at the warm checkpoint, bytes.
    pub rss_growth: u64,
    /// The largest GPU bytes at any checkpoint.
    pub gpu_peak: u64,
}

impl Verdict {
    pub fn bounded(&self) -> bool {
        !self.stopped && self.rss_growth <= RSS_GROWTH_BOUND && self.gpu_peak <= GPU_BYTES_BOUND
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.stopped {
            write!(f, "stopped early, ")?;
        }
        write!(
            f,
            "rss_growth_mib={:.1} (bound {}) gpu_peak_bytes={} (bound {GPU_BYTES_BOUND})",
            self.rss_growth as f64 / (1 << 20) as f64,
            RSS_GROWTH_BOUND >> 20,
            self.gpu_peak
        )
    }
}

/// Every checkpoint of a run.
pub struct Report {
    /// Frames after which the schedule repeats: every change's period divides it, so each
    /// combination of settings, MSAA, size, volume and occluders that ever occurs has occurred
    /// once this many frames in, and what a later repetition adds to memory is a leak, not a
    /// first use (a pipeline compiled, a pool grown).
    pub cycle: u32,
    /// Whether the run stopped early because the process grew past 4 GiB.
    pub stopped: bool,
    pub samples: Vec<Sample>,
}

impl Report {
    /// The first checkpoint a quarter cycle after the first whole cycle (the last one in a
    /// shorter run): growth is measured from here. The margin is there because the passes of the
    /// first frames' settings run only once their pipelines are ready, so a few combinations are
    /// first drawn early in the second cycle (10 MiB at frames 400–450 of the CI run).
    pub fn warm(&self) -> Sample {
        *self
            .samples
            .iter()
            .find(|s| s.frame >= warm_frame(self.cycle))
            .unwrap_or(&self.end())
    }

    pub fn end(&self) -> Sample {
        *self.samples.last().expect("a run has checkpoints")
    }

    pub fn verdict(&self) -> Verdict {
        Verdict {
            stopped: self.stopped,
            rss_growth: self.end().rss.saturating_sub(self.warm().rss),
            gpu_peak: self.samples.iter().map(|s| s.gpu).max().unwrap_or(0),
        }
    }

    /// Markdown table of the checkpoints.
    pub fn table(&self) -> String {
        let mut out = String::from(
            "| frame | RSS (MiB) | plugin GPU bytes | entities | meshes |\n|---|---|---|---|---|\n",
        );
        for s in &self.samples {
            out += &format!(
                "| {} | {:.1} | {} | {} | {} |\n",
                s.frame,
                s.rss as f64 / (1 << 20) as f64,
                s.gpu,
                s.entities,
                s.meshes
            );
        }
        out
    }
}

/// Resident set size of this process, bytes; 0 where `/proc/self/status` does not exist.
pub fn rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib * 1024)
        })
        .unwrap_or(0)
}

fn new_app() -> App {
    let mut app = App::new();
    app.add_plugins((crate::common::headless_plugins(), DynamicAoPlugin))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
            1.0 / 30.0,
        )))
        // Fields bake in memory only: the run must not grow a cache folder.
        .insert_resource(AoFieldCache::disabled());
    crate::common::finish_plugins(&mut app);
    app
}

fn target(world: &mut World, size: UVec2) -> RenderTarget {
    let image = Image::new_target_texture(size.x, size.y, TextureFormat::Rgba8UnormSrgb, None);
    RenderTarget::Image(world.resource_mut::<Assets<Image>>().add(image).into())
}

/// The camera's settings at step `step` (of 16, then again) of the settings schedule: every
/// preset, with and without each far-field term, and two image-space techniques on their own;
/// the sphere term only where `spheres` allows it.
fn settings(step: u32, spheres: bool) -> DynamicAo {
    let step = step % 16;
    let preset = AoPreset::ALL[step as usize % AoPreset::ALL.len()];
    let mut ao = DynamicAo::from_preset(preset);
    match (step / 4) % 4 {
        0 => {}
        1 => ao.spheres = false,
        2 => {
            ao.fields = false;
            ao.voxels = false;
        }
        _ => {
            ao.technique = [AoTechnique::NearField, AoTechnique::Off][step as usize % 2];
            ao.temporal = AoTemporal::OFF;
        }
    }
    ao.spheres &= spheres;
    ao
}

/// An occluder of kind `i % 4` with a mesh of its own: a box with sphere proxies, a box with an
/// AO field baked on the spot, a ball the voxels find, a wall with both proxies and a field.
fn spawn_occluder(world: &mut World, i: u32, material: &Handle<StandardMaterial>) -> Entity {
    let angle = i as f32 * 2.4;
    let place = Transform::from_xyz(1.6 * angle.cos(), 0.3, 1.6 * angle.sin());
    let field = || {
        AoField::Bake(BakeSettings {
            resolution: 8,
            rays: 32,
            ..default()
        })
    };
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let (mesh, kind) = match i % 4 {
        0 => (meshes.add(Cuboid::new(0.5, 0.6, 0.5)), 0),
        1 => (meshes.add(Cuboid::new(0.6, 0.5, 0.4)), 1),
        2 => (meshes.add(Sphere::new(0.3).mesh().uv(16, 9)), 2),
        _ => (meshes.add(Cuboid::new(1.2, 0.8, 0.08)), 3),
    };
    let mut entity = world.spawn((Mesh3d(mesh), MeshMaterial3d(material.clone()), place));
    match kind {
        0 => {
            entity.insert(SphereOccluder::default());
        }
        1 => {
            entity.insert(field());
        }
        2 => {}
        _ => {
            entity.insert((SphereOccluder::default(), field()));
        }
    }
    entity.id()
}

/// Runs `frames` frames of a schedule that repeats every `cycle` frames (a multiple of 80) and
/// samples memory `checkpoints` times, evenly (the first at frame 0); the camera draws sphere
/// proxies only if `spheres`.
///
/// In steps of a sixteenth of the cycle: the settings change every step (16 settings per
/// cycle); an occluder spawns every 2/5 step (kinds in turn) and the oldest of seven despawns;
/// the voxel volume comes or goes and the target changes size every 4 steps (4 sizes); MSAA
/// toggles and `DynamicAo` goes for a tenth of a step every 8 steps.
pub fn soak(frames: u32, checkpoints: u32, spheres: bool, cycle: u32) -> Report {
    let step = cycle / 16;
    let mut app = new_app();
    let world = app.world_mut();
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            base_color: Color::srgb(0.8, 0.8, 0.8),
            perceptual_roughness: 1.0,
            ..default()
        });
    let floor = world
        .resource_mut::<Assets<Mesh>>()
        .add(Plane3d::default().mesh().size(8.0, 8.0));
    world.spawn((
        Mesh3d(floor),
        MeshMaterial3d(material.clone()),
        Transform::IDENTITY,
    ));
    let cube = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(1.0, 1.0, 1.0));
    world.spawn((
        Mesh3d(cube),
        MeshMaterial3d(material.clone()),
        Transform::from_xyz(0.0, 0.5, 0.0),
        SphereOccluder::default(),
    ));
    let target = target(world, SIZES[0]);
    let camera = world
        .spawn((
            Camera3d::default(),
            target,
            Transform::from_xyz(2.5, 2.2, 3.2).looking_at(Vec3::new(0.0, 0.3, 0.0), Vec3::Y),
            Msaa::Off,
            AmbientLight {
                brightness: 2000.0,
                ..default()
            },
            settings(0, spheres),
        ))
        .id();

    let every = (frames / checkpoints.max(1)).max(1);
    let mut samples = Vec::new();
    let mut occluders: Vec<Entity> = Vec::new();
    let mut volume: Option<Entity> = None;
    let mut spawned = 0;
    let mut stopped = false;
    for frame in 0..=frames {
        if frame % every == 0 || frame == frames {
            let world = app.world_mut();
            samples.push(Sample {
                frame,
                rss: rss_bytes(),
                gpu: world.resource::<DynamicAoGpuMemory>().bytes(),
                entities: world.entities().count_spawned(),
                meshes: world.resource::<Assets<Mesh>>().len(),
            });
        }
        if frame == frames {
            break;
        }
        if rss_bytes() > samples[0].rss + RSS_STOP {
            println!(
                "soak: stopped at frame {frame}: the process grew by more than {} GiB",
                RSS_STOP >> 30
            );
            samples.push(Sample {
                frame,
                ..*samples.last().expect("frame 0 was sampled")
            });
            samples.last_mut().expect("just pushed").rss = rss_bytes();
            stopped = true;
            break;
        }
        let world = app.world_mut();
        let phase = frame % cycle;
        if frame % (step * 2 / 5) == 0 {
            occluders.push(spawn_occluder(world, spawned, &material));
            spawned += 1;
            if occluders.len() > MAX_OCCLUDERS {
                world.despawn(occluders.remove(0));
            }
        }
        if phase % (4 * step) == step {
            match volume.take() {
                Some(entity) => {
                    world.despawn(entity);
                }
                None => {
                    volume = Some(
                        world
                            .spawn((
                                Transform::from_xyz(0.0, 1.0, 0.0),
                                VoxelAoVolume {
                                    half_extents: Vec3::new(2.5, 1.0, 2.5),
                                    resolution: 32,
                                    rays: 8,
                                    ..default()
                                },
                            ))
                            .id(),
                    );
                }
            }
        }
        if phase % (4 * step) == 2 * step {
            let size = SIZES[(phase / (4 * step) + 1) as usize % SIZES.len()];
            let target = self::target(world, size);
            world.entity_mut(camera).insert(target);
        }
        if phase % step == step / 2 {
            world
                .entity_mut(camera)
                .insert(settings(phase / step + 1, spheres));
        }
        if phase % (8 * step) == 3 * step + step * 7 / 10 {
            let mut msaa = world.get_mut::<Msaa>(camera).expect("the camera has Msaa");
            *msaa = if *msaa == Msaa::Off {
                Msaa::Sample4
            } else {
                Msaa::Off
            };
        }
        if phase % (8 * step) == 6 * step + step / 5 {
            world.entity_mut(camera).remove::<DynamicAo>();
        }
        if phase % (8 * step) == 6 * step + step * 3 / 10 {
            world
                .entity_mut(camera)
                .insert(settings(phase / step, spheres));
        }
        app.update();
    }
    Report {
        cycle,
        stopped,
        samples,
    }
}

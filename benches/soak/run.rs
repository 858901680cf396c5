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

use bevy::app::PluginsState;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::time::TimeUpdateStrategy;
use bevy_dynamic_ao::DynamicAoGpuMemory;
use bevy_dynamic_ao::fields::{AoFieldCache, BakeSettings};
use bevy_dynamic_ao::prelude::*;

/// Sizes the target cycles through, pixels: 64×48 first.
const SIZES: [UVec2; 3] = [UVec2::new(64, 48), UVec2::new(80, 60), UVec2::new(48, 36)];
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

/// Most the RSS may grow from the warm checkpoint to the end, bytes.
pub const RSS_GROWTH_BOUND: u64 = 48 << 20;
/// Most GPU bytes the plugin may hold at any checkpoint: the run's largest state (a 32³ voxel
/// grid, six small fields, the temporal histories of an 80×60 view) takes about 0.2 MB.
pub const GPU_BYTES_BOUND: u64 = 1 << 20;

/// What a run's memory did.
pub struct Verdict {
    /// RSS at the end less RSS at the warm checkpoint, bytes.
    pub rss_growth: u64,
    /// The largest GPU bytes at any checkpoint.
    pub gpu_peak: u64,
}

impl Verdict {
    pub fn bounded(&self) -> bool {
        self.rss_growth <= RSS_GROWTH_BOUND && self.gpu_peak <= GPU_BYTES_BOUND
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
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
    pub samples: Vec<Sample>,
}

impl Report {
    /// The checkpoint after the first fifth of the run, when every schedule has turned at least
    /// once and caches and pools are warm: growth is measured from here.
    pub fn warm(&self) -> Sample {
        self.samples[self.samples.len() / 5]
    }

    pub fn end(&self) -> Sample {
        *self.samples.last().expect("a run has checkpoints")
    }

    pub fn verdict(&self) -> Verdict {
        Verdict {
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
        .insert_resource(AoFieldCache { folder: None });
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    app
}

fn target(world: &mut World, size: UVec2) -> RenderTarget {
    let image = Image::new_target_texture(size.x, size.y, TextureFormat::Rgba8UnormSrgb, None);
    RenderTarget::Image(world.resource_mut::<Assets<Image>>().add(image).into())
}

/// The camera's settings at step `step` of the settings schedule: every preset, with and without
/// each far-field term, and two image-space techniques on their own; the sphere term only where
/// `spheres` allows it.
fn settings(step: u32, spheres: bool) -> DynamicAo {
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

/// Runs `frames` frames and samples memory `checkpoints` times, evenly (the first at frame 0);
/// the camera draws sphere proxies only if `spheres`.
pub fn soak(frames: u32, checkpoints: u32, spheres: bool) -> Report {
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
        let world = app.world_mut();
        if frame % 40 == 0 {
            occluders.push(spawn_occluder(world, spawned, &material));
            spawned += 1;
            if occluders.len() > MAX_OCCLUDERS {
                world.despawn(occluders.remove(0));
            }
        }
        if frame % 300 == 100 {
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
        if frame % 250 == 200 {
            let size = SIZES[(frame / 250 + 1) as usize % SIZES.len()];
            let target = self::target(world, size);
            world.entity_mut(camera).insert(target);
        }
        if frame % 100 == 50 {
            world
                .entity_mut(camera)
                .insert(settings(frame / 100 + 1, spheres));
        }
        if frame % 350 == 170 {
            let mut msaa = world.get_mut::<Msaa>(camera).expect("the camera has Msaa");
            *msaa = if *msaa == Msaa::Off {
                Msaa::Sample4
            } else {
                Msaa::Off
            };
        }
        if frame % 500 == 420 {
            world.entity_mut(camera).remove::<DynamicAo>();
        }
        if frame % 500 == 430 {
            world
                .entity_mut(camera)
                .insert(settings(frame / 100, spheres));
        }
        app.update();
    }
    Report { samples }
}

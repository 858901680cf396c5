//! Temporal stability, ours against Bevy's SSAO with and without Bevy's temporal anti-aliasing,
//! all in the same run. Prints Markdown tables.
//!
//! `cargo bench --profile dev --bench temporal` (`-- --frames N`: consecutive frames of the
//! still-camera table, default 16; `-- --only still` or `-- --only motion` for one table;
//! `-- --config TEXT` for the configurations whose name holds TEXT). Each configuration's frames
//! count from the first frame its AO is written (`scene::wait_until_written`): until its shaders
//! have loaded and compiled, `AoReadback` reads −1, which no table counts.
//!
//! - **Still camera** (`still.rs`): a floor, a box and a ball. Flicker: mean |AO_t − AO_{t−1}|
//!   over the pixels that show geometry, once every configuration has converged, and the same for
//!   the lit image's luminance (what a player sees, after TAA's resolve where it is on).
//! - **Orbiting camera, walking characters** (`motion.rs`): the project's skinned walker twice,
//!   walking on circles, a box sliding to and fro, a wall, seen from an orbiting camera. At
//!   checkpoints, error against ground truth traced for that frame's pose, and the ghost trail:
//!   pixels darker than the truth by more than 0.1 while moving, minus those left once the same
//!   pose has been held still until converged.

mod motion;
mod scene;
mod still;

use bevy::anti_alias::taa::TemporalAntiAliasing;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::prelude::default;
use bevy_dynamic_ao::prelude::*;

/// One configuration of a camera.
#[derive(Clone)]
pub struct Configuration {
    pub name: &'static str,
    pub ao: DynamicAo,
    /// Bevy's temporal anti-aliasing on the same camera.
    pub taa: bool,
}

impl Configuration {
    /// The components the camera gets besides its transform and target.
    pub fn insert(&self, camera: &mut bevy::ecs::world::EntityWorldMut) {
        camera.insert(self.ao.clone());
        if self.ao.technique == AoTechnique::BevySsao {
            camera.insert(ScreenSpaceAmbientOcclusion::default());
        }
        if self.taa {
            camera.insert(TemporalAntiAliasing::default());
        }
    }
}

/// The radius of every configuration, metres: the one Bevy's SSAO shader fixes.
pub const RADIUS: f32 = 0.73;

fn configurations() -> Vec<Configuration> {
    // Ours at half resolution, as every view over 240 × 180 runs it: at this bench's 160 × 120
    // `DynamicAo::small_viewport_pixels` would run it at full resolution, and the trail and
    // flicker this bench measures are the half-resolution path's (README, "Temporal stability"),
    // with one row of the default as it runs at this size.
    let ours = |name, ao: DynamicAo| Configuration {
        name,
        ao: DynamicAo {
            small_viewport_pixels: 0,
            ..ao.with_radius(RADIUS)
        },
        taa: false,
    };
    let bevy = DynamicAo::default().with_technique(AoTechnique::BevySsao);
    vec![
        ours("ours, default (accumulated)", DynamicAo::default()),
        // What the default runs at this size itself.
        Configuration {
            name: "ours, default at 160×120 (full resolution, blur of 1 px)",
            ao: DynamicAo::default().with_radius(RADIUS),
            taa: false,
        },
        Configuration {
            taa: true,
            ..ours("ours, default, with Bevy's TAA", DynamicAo::default())
        },
        ours(
            "ours, default marching every texel every frame",
            DynamicAo {
                ray_march: RayMarchParams {
                    checkerboard: false,
                    ..default()
                },
                ..default()
            },
        ),
        ours(
            "ours, default with accumulation off",
            DynamicAo {
                temporal: AoTemporal::OFF,
                ..default()
            },
        ),
        // The longer history the README offers where the camera mostly holds still: less grain,
        // a longer trail (BENCHMARKS.md, "How many samples a history averages").
        ours(
            "ours, default with a 32-sample history",
            DynamicAo {
                temporal: AoTemporal {
                    max_frames: 32,
                    ..default()
                },
                ..default()
            },
        ),
        ours("ours, preset low", DynamicAo::from_preset(AoPreset::Low)),
        ours(
            "ours, preset medium",
            DynamicAo::from_preset(AoPreset::Medium),
        ),
        ours("Bevy SSAO High", bevy.clone()),
        Configuration {
            taa: true,
            ..ours("Bevy SSAO High, with Bevy's TAA", bevy)
        },
    ]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let frames = value("--frames")
        .and_then(|v| v.parse().ok())
        .unwrap_or(16u32)
        .max(2);
    let only = value("--only");
    let mut configurations = configurations();
    if let Some(text) = value("--config") {
        configurations.retain(|c| c.name.contains(text.as_str()));
    }
    if only.as_deref() != Some("motion") {
        still::run(&configurations, frames);
    }
    if only.as_deref() != Some("still") {
        motion::run(&configurations);
    }
}

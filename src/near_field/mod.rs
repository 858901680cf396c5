//! Image-space near-field occlusion, Shanmugam & Arikan 2007, §4.
//!
//! Every pixel of both ND-buffer layers stands for a sphere pushed back along −n (so a flat
//! surface does not occlude itself). For a receiver P with normal n, the pass gathers
//! neighbouring pixels inside the projected r_far on a per-pixel rotated Vogel spiral, keeps the
//! occluders Q with |P − Q| < r_far and sums their sphere occlusion A_ψ (eq. 2–4). The number of
//! samples follows the projected r_far: one per covered pixel at most, between the preset's
//! minimum and maximum. Each sample sphere stands for the pixels the sampling skips: its
//! cross-section equals the surface area of the (disk area / sample count) pixels around it at
//! its depth, which keeps the sum independent of the sample count.

mod node;
mod pipeline;

use bevy::app::{App, Plugin};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::schedule::IntoScheduleConfigs;
use bevy::render::{GpuResourceAppExt, Render, RenderApp, RenderSystems};

use crate::schedule::DynamicAoSystems;

/// Registers the near-field pipeline and pass.
pub struct NearFieldPlugin;

impl Plugin for NearFieldPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "near_field.wgsl");
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::NearFieldPipeline>()
            .add_systems(
                Render,
                pipeline::prepare_near_field_bind_groups.in_set(RenderSystems::PrepareBindGroups),
            )
            .add_systems(Core3d, node::near_field_pass.in_set(DynamicAoSystems::NearField));
    }
}

pub(crate) use pipeline::NearFieldPipeline;

//! Filtering of the occlusion buffer.
//!
//! A separable cross-bilateral blur (Bavoil & Sainz 2008, "Cross Bilateral Filter"): one pass
//! along X into a scratch texture, one along Y back into the occlusion buffer. Each tap is
//! weighted by a Gaussian of its pixel distance and by exp(−(sharpness · Δz / z)²), where Δz is
//! its view-depth difference from the centre pixel, so occlusion does not bleed across
//! silhouettes. Sharpness 0 gives a plain Gaussian. Pixels that show no geometry take no part.
//! `reference::filter` is the CPU twin.

mod node;
mod pipeline;

use bevy::app::{App, Plugin};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::schedule::IntoScheduleConfigs;
use bevy::render::{GpuResourceAppExt, Render, RenderApp, RenderSystems};

use crate::schedule::DynamicAoSystems;

pub(crate) use pipeline::BlurPipelines;

/// Registers the blur pipelines and passes.
pub struct FilterPlugin;

impl Plugin for FilterPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "blur.wgsl");
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::BlurPipelines>()
            .add_systems(
                Render,
                pipeline::prepare_blur_bind_groups.in_set(RenderSystems::PrepareBindGroups),
            )
            .add_systems(Core3d, node::blur_pass.in_set(DynamicAoSystems::Filter));
    }
}

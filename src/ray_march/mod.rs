//! Ray-marched ambient occlusion through both ND-buffer layers: the in-engine reference
//! (Bavoil & Sainz 2008, "Ray-Marched Ambient Occlusion").
//!
//! From each pixel, `directions × rays_per_direction` rays leave over the hemisphere around the
//! normal, stratified so that they follow the cosine weighting of the AO integral; each is
//! marched in `steps` equal steps over the radius R. A step is blocked where it lies behind the
//! front layer and in front of the back-face layer at the pixel it projects to (inside a solid),
//! or, where no back face was drawn there, less than R behind the front layer. The occlusion is
//! the fraction of blocked rays. Costly, but its error against ray-traced ground truth shrinks as
//! the ray count grows. `reference::ray_march` is the CPU twin.

mod node;
mod pipeline;

use bevy::app::{App, Plugin};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::schedule::IntoScheduleConfigs;
use bevy::render::{GpuResourceAppExt, Render, RenderApp, RenderSystems};

use crate::schedule::DynamicAoSystems;

pub(crate) use pipeline::RayMarchPipeline;

/// Registers the ray-marched pipeline and pass.
pub struct RayMarchPlugin;

impl Plugin for RayMarchPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "ray_march.wgsl");
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::RayMarchPipeline>()
            .add_systems(
                Render,
                pipeline::prepare_ray_march_bind_groups.in_set(RenderSystems::PrepareBindGroups),
            )
            // Writes the same occlusion buffer the near-field pass writes; one of them runs.
            .add_systems(
                Core3d,
                node::ray_march_pass.in_set(DynamicAoSystems::NearField),
            );
    }
}

//! Horizon-based ambient occlusion, Bavoil & Sainz 2008 ("Horizon-Based Ambient Occlusion").
//!
//! The front layer of the ND-buffer is read as a heightfield seen from the camera. For each of
//! a few image-space directions around a pixel (randomly rotated per pixel), the pass steps
//! outwards up to the radius R projected on screen (fewer steps where it covers fewer pixels),
//! tracks the highest elevation angle h seen so far, measured from the view plane, and adds
//! W0 · W(r/R) · (sin h_new − sin h_old) whenever the horizon rises, starting from the elevation
//! t of the tangent plane (raised by the angle bias). W(x) = 1 − x². The mean over directions,
//! times the contrast, is the occlusion. `reference::horizon` is the CPU twin.
//!
//! The whitepaper's low and high modes are named there but not spelled out; what they do here is
//! documented on [`HorizonMode`](crate::settings::HorizonMode).

mod node;
mod pipeline;

use bevy::app::{App, Plugin};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::schedule::IntoScheduleConfigs;
use bevy::render::{GpuResourceAppExt, Render, RenderApp, RenderSystems};

use crate::schedule::DynamicAoSystems;

pub(crate) use pipeline::HorizonPipeline;

/// Registers the horizon-based pipeline and pass.
pub struct HorizonPlugin;

impl Plugin for HorizonPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "horizon.wgsl");
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::HorizonPipeline>()
            .add_systems(
                Render,
                pipeline::prepare_horizon_bind_groups.in_set(RenderSystems::PrepareBindGroups),
            )
            // Writes the same occlusion buffer the near-field pass writes; one of them runs.
            .add_systems(
                Core3d,
                node::horizon_pass.in_set(DynamicAoSystems::NearField),
            );
    }
}

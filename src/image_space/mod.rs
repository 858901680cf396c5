//! The pass that runs the image-space technique of each view: [`near_field`](crate::near_field),
//! [`horizon`](crate::horizon) or [`ray_march`](crate::ray_march). All three read the same
//! bindings (view, settings, both ND-buffer layers) and write the same occlusion buffer, so they
//! share one layout, one bind group per view and one pass; only the shader differs, compiled for
//! the resolution of the view's occlusion buffer.

use bevy::app::{App, Plugin};
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::render::{GpuResourceAppExt, Render, render_resource::*};

mod node;
mod pipeline;

use crate::capabilities;
use crate::schedule::{DynamicAoPrepare, DynamicAoSystems};
use crate::settings::AoTechnique;
use crate::view::{DynamicAoView, PendingPasses, drop_without_ao};

/// Registers the shared pipelines, bind groups and pass of the image-space techniques.
pub(crate) struct ImageSpacePlugin;

impl Plugin for ImageSpacePlugin {
    fn build(&self, _app: &mut App) {}

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::ImageSpacePipelines>()
            .add_systems(
                Render,
                (
                    pipeline::prepare_image_space_bind_groups.in_set(DynamicAoPrepare::BindGroups),
                    drop_without_ao::<pipeline::ImageSpaceBindGroup>
                        .in_set(DynamicAoPrepare::BindGroups),
                    wait_for_image_space.in_set(DynamicAoPrepare::Readiness),
                ),
            )
            .add_systems(
                Core3d,
                node::image_space_pass.in_set(DynamicAoSystems::NearField),
            );
    }
}

/// The view's image-space technique counts until its pipeline has compiled. `Off` has none to
/// wait for; under Bevy's SSAO ours never take over.
fn wait_for_image_space(
    pipeline_cache: Res<PipelineCache>,
    pipelines: Res<pipeline::ImageSpacePipelines>,
    mut views: Query<(&DynamicAoView, &mut PendingPasses)>,
) {
    for (view, mut pending) in &mut views {
        let ready = match view.technique() {
            AoTechnique::Off => true,
            AoTechnique::BevySsao => false,
            technique => pipelines
                .pipeline(technique, view.half_resolution)
                .is_some_and(|id| pipeline_cache.get_compute_pipeline(id).is_some()),
        };
        pending.wait_for(ready);
    }
}

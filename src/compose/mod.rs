//! Combining the occlusion terms and handing the result to Bevy's PBR lighting.
//!
//! Near and far terms combine as [`FarFieldBlend`](crate::FarFieldBlend) says (by default each
//! occluder counted once: within the near field's reach the larger of the near field and what
//! the far field adds that the ND-buffer misses, beyond it the far field as an independent
//! occluder; `compose.wgsl` says why); this pass writes the result as **visibility** (1 = open) into the texture Bevy binds for its own SSAO
//! (`ScreenSpaceAmbientOcclusionResources::screen_space_ambient_occlusion_texture`, mesh view
//! binding 17). Bevy's PBR shader applies that texture to ambient/indirect diffuse light and
//! environment specular only, so direct lights are never darkened. Bevy's own SSAO pass is
//! skipped on views where ours runs, by removing its pipeline id once our pipelines are ready
//! (and runs again if one of them stops compiling, see `failed`). The sphere and field splats may
//! arrive at half resolution; a second variant of the pass upsamples them on the way. On a view
//! with no far-field term there is nothing to combine: the filter's last pass writes the
//! visibility itself and this pass does not run.
//!
//! The debug view draws the same visibility over the lit image, full screen.

mod debug_view;
mod failed;
mod node;
mod pipeline;
mod ssao_slot;
mod status;

pub(crate) use failed::FailedPipelines;
pub(crate) use pipeline::bevy_ssao_format;
pub(crate) use ssao_slot::{ParkedSsao, bevy_ssao_runs, visibility_texture};
pub(crate) use status::shown;
pub use status::{AoShown, DynamicAoStatus};

use bevy::app::{App, Plugin};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::pbr::{SsaoPipelineId, prepare_mesh_view_bind_groups};
use bevy::render::{
    ExtractSchedule, GpuResourceAppExt, Render, RenderSystems,
    render_resource::{PipelineCache, SpecializedRenderPipelines},
};

use crate::capabilities;
use crate::schedule::{DynamicAoExtract, DynamicAoPrepare, DynamicAoSystems};
use crate::view::{AoPassesReady, PendingPasses, drop_without_ao};

/// Registers the compose pass, the hand-off to PBR and the debug view.
pub struct ComposePlugin;

impl Plugin for ComposePlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "compose.wgsl");
        embedded_asset!(app, "debug_view.wgsl");
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_resource::<FailedPipelines>()
            .init_resource::<status::RenderedStatuses>()
            .init_gpu_resource::<pipeline::ComposePipeline>()
            .init_gpu_resource::<debug_view::DebugViewPipeline>()
            .init_gpu_resource::<SpecializedRenderPipelines<debug_view::DebugViewPipeline>>()
            .add_systems(
                ExtractSchedule,
                (
                    ssao_slot::extract_msaa_slots.in_set(DynamicAoExtract::Views),
                    status::publish_statuses.in_set(DynamicAoExtract::Consumed),
                ),
            )
            .add_systems(
                Render,
                (
                    (
                        ssao_slot::place_split_screen_textures,
                        ssao_slot::stand_in_open_textures,
                        ssao_slot::park_msaa_resources,
                    )
                        .chain()
                        .in_set(DynamicAoPrepare::SsaoSlot),
                    (
                        ssao_slot::restore_msaa_resources,
                        // A second run, now with the texture: the first one, during
                        // `PrepareBindGroups`, saw the views without it.
                        prepare_mesh_view_bind_groups.run_if(ssao_slot::any_msaa_slot),
                    )
                        .chain()
                        .in_set(DynamicAoPrepare::RestoreSsao),
                    debug_view::prepare_debug_view_pipelines.in_set(RenderSystems::Prepare),
                    hand_over_from_bevy_ssao.in_set(DynamicAoPrepare::HandOver),
                    status::record_statuses.in_set(DynamicAoPrepare::Status),
                    failed::report_failed_pipelines.in_set(DynamicAoPrepare::HandOver),
                    (
                        pipeline::prepare_compose_bind_groups,
                        debug_view::prepare_debug_view_bind_groups,
                        drop_without_ao::<(
                            pipeline::ComposeBindGroup,
                            debug_view::DebugViewPipelineId,
                            debug_view::DebugViewBindGroup,
                        )>,
                    )
                        .in_set(DynamicAoPrepare::BindGroups),
                ),
            )
            .add_systems(
                Core3d,
                (
                    node::compose_pass.in_set(DynamicAoSystems::Compose),
                    node::debug_view_pass.in_set(DynamicAoSystems::Debug),
                ),
            );
    }
}

/// Bevy's SSAO pass only runs on views that carry its pipeline id; taking it away hands the
/// texture to us. Until every pass the view needs has compiled (pipelines compile in the
/// background over several frames; each technique counts its own in [`PendingPasses`]), Bevy's
/// pass keeps running and ours stays off, so the image never shows an unwritten texture.
pub(crate) fn hand_over_from_bevy_ssao(
    mut commands: Commands,
    pipeline_cache: Res<PipelineCache>,
    compose: Res<pipeline::ComposePipeline>,
    views: Query<(Entity, &PendingPasses, Has<SsaoPipelineId>)>,
    // Views that stopped running the plugin.
    stale: Query<Entity, (With<AoPassesReady>, Without<PendingPasses>)>,
) {
    for entity in &stale {
        commands.entity(entity).remove::<AoPassesReady>();
    }
    let compose_ready = compose.ready(&pipeline_cache);
    for (entity, pending, bevy_ssao) in &views {
        if compose_ready && pending.all_ready() {
            commands.entity(entity).insert(AoPassesReady);
            if bevy_ssao {
                commands.entity(entity).remove::<SsaoPipelineId>();
            }
        } else {
            commands.entity(entity).remove::<AoPassesReady>();
        }
    }
}

//! Combining the occlusion terms and handing the result to Bevy's PBR lighting.
//!
//! Near and far terms combine as [`FarFieldBlend`](crate::FarFieldBlend) says (by default each
//! occluder counted once: within the near field's reach the larger of the near field and what
//! the far field adds that the ND-buffer misses, beyond it the far field as an independent
//! occluder; `compose.wgsl` says why); this pass writes the result as **visibility** (1 = open) into the texture Bevy binds for its own SSAO
//! (`ScreenSpaceAmbientOcclusionResources::screen_space_ambient_occlusion_texture`, mesh view
//! binding 17). Bevy's PBR shader applies that texture to ambient/indirect diffuse light and
//! environment specular only, so direct lights are never darkened. Bevy's own SSAO pass is
//! skipped on views where ours runs, by removing its pipeline id once our pipelines are ready.
//!
//! The debug view draws the same visibility over the lit image, full screen.

mod debug_view;
pub(crate) mod node;
mod pipeline;

use bevy::app::{App, Plugin};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::pbr::SsaoPipelineId;
use bevy::render::{
    GpuResourceAppExt, Render, RenderApp, RenderSystems,
    render_resource::{PipelineCache, SpecializedRenderPipelines},
};

use crate::fields::FieldPipelines;
use crate::filter::BlurPipelines;
use crate::image_space::ImageSpacePipelines;
use crate::schedule::DynamicAoSystems;
use crate::settings::{AoTechnique, FieldShading};
use crate::spheres::SplatPipeline;
use crate::view::DynamicAoView;
use crate::voxels::VoxelPipelines;

/// Registers the compose pass, the hand-off to PBR and the debug view.
pub struct ComposePlugin;

impl Plugin for ComposePlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "compose.wgsl");
        embedded_asset!(app, "debug_view.wgsl");
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::ComposePipeline>()
            .init_gpu_resource::<debug_view::DebugViewPipeline>()
            .init_gpu_resource::<SpecializedRenderPipelines<debug_view::DebugViewPipeline>>()
            .add_systems(
                Render,
                (
                    debug_view::prepare_debug_view_pipelines.in_set(RenderSystems::Prepare),
                    // Bevy inserts `SsaoPipelineId` during `Prepare`; its pass needs it.
                    hand_over_from_bevy_ssao
                        .after(RenderSystems::Prepare)
                        .before(RenderSystems::Render),
                    (
                        pipeline::prepare_compose_bind_groups,
                        debug_view::prepare_debug_view_bind_groups,
                    )
                        .in_set(RenderSystems::PrepareBindGroups),
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

/// Marks a view whose passes have all compiled: from then on ours write the AO texture, not
/// Bevy's SSAO.
#[derive(Component)]
pub(crate) struct AoPassesReady;

/// Bevy's SSAO pass only runs on views that carry its pipeline id; taking it away hands the
/// texture to us. Until every pass the view needs has compiled (pipelines compile in the
/// background over several frames), Bevy's pass keeps running and ours stays off, so the image
/// never shows an unwritten texture.
fn hand_over_from_bevy_ssao(
    mut commands: Commands,
    pipeline_cache: Res<PipelineCache>,
    image_space: Res<ImageSpacePipelines>,
    blur: Res<BlurPipelines>,
    compose: Res<pipeline::ComposePipeline>,
    splat: Res<SplatPipeline>,
    fields: Res<FieldPipelines>,
    voxels: Res<VoxelPipelines>,
    views: Query<(Entity, &DynamicAoView, Has<SsaoPipelineId>)>,
) {
    let ready = |id| pipeline_cache.get_compute_pipeline(id).is_some();
    for (entity, view, bevy_ssao) in &views {
        let technique = match view.technique {
            AoTechnique::Off => true,
            AoTechnique::BevySsao => false,
            technique => image_space.pipeline(technique).is_some_and(ready),
        };
        let filter = (view.blur_radius == 0 || (ready(blur.one.x) && ready(blur.one.y)))
            && (!view.half_resolution || ready(blur.one.upsample));
        let far_field =
            !view.far_field || pipeline_cache.get_render_pipeline(splat.pipeline).is_some();
        let field_pipeline = match view.field_shading {
            FieldShading::Cone => fields.cone,
            FieldShading::OcclusionOnly => fields.occlusion_only,
        };
        let fields_ready =
            !view.fields || pipeline_cache.get_render_pipeline(field_pipeline).is_some();
        let voxels_ready = !view.voxels
            || (ready(voxels.voxelize) && ready(voxels.sample) && blur.two.ready(&pipeline_cache));
        if technique
            && filter
            && far_field
            && fields_ready
            && voxels_ready
            && ready(compose.pipeline)
        {
            commands.entity(entity).insert(AoPassesReady);
            if bevy_ssao {
                commands.entity(entity).remove::<SsaoPipelineId>();
            }
        } else {
            commands.entity(entity).remove::<AoPassesReady>();
        }
    }
}

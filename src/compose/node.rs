//! The compose pass and the debug view pass.

use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    diagnostic::RecordDiagnostics,
    extract_component::DynamicUniformIndex,
    render_resource::{PipelineCache, RenderPassDescriptor},
    renderer::{RenderContext, ViewQuery},
    view::{ViewTarget, ViewUniformOffset},
};

use super::debug_view::{DebugViewBindGroup, DebugViewPipelineId};
use super::pipeline::{ComposeBindGroup, ComposePipeline};
use crate::dispatch::{ComputeStep, SpanStart, Workgroup, record_passes};
use crate::view::{AoPassesReady, DynamicAoUniform, DynamicAoView, FilterWritesVisibility};

pub(crate) fn compose_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &DynamicAoView,
        &ComposeBindGroup,
        &DynamicUniformIndex<DynamicAoUniform>,
        &ViewUniformOffset,
        Has<AoPassesReady>,
        Has<FilterWritesVisibility>,
    )>,
    pipeline: Res<ComposePipeline>,
    pipeline_cache: Res<PipelineCache>,
    span_start: Res<SpanStart>,
    mut ctx: RenderContext,
) {
    let (camera, ao_view, bind_group, settings_index, view_offset, ready, filter_wrote) =
        view.into_inner();
    // Until every pass of the view has compiled, Bevy's SSAO still writes the texture; where
    // the filter's last pass wrote it, nothing is left to combine.
    if !ao_view.replaces_bevy_ssao() || !ready || filter_wrote {
        return;
    }
    let (Some(size), Some(compute_pipeline)) = (
        camera.physical_viewport_size,
        pipeline_cache.get_compute_pipeline(pipeline.for_view(ao_view)),
    ) else {
        return;
    };

    let step = ComputeStep {
        label: "dynamic_ao_compose",
        pipeline: compute_pipeline,
        bind_group: &bind_group.0,
        offsets: &[settings_index.index(), view_offset.offset],
        texels: size,
        workgroup: Workgroup::Square,
    };
    record_passes(&mut ctx, &span_start, "dynamic_ao_compose", true, &[step]);
}

pub(crate) fn debug_view_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &ViewTarget,
        &DebugViewPipelineId,
        &DebugViewBindGroup,
    )>,
    pipeline_cache: Res<PipelineCache>,
    mut ctx: RenderContext,
) {
    let (camera, target, pipeline_id, bind_group) = view.into_inner();
    let Some(pipeline) = pipeline_cache.get_render_pipeline(pipeline_id.0) else {
        return;
    };
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("dynamic_ao_debug_view"),
        color_attachments: &[Some(target.get_unsampled_color_attachment())],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let pass_span = diagnostics.pass_span(&mut pass, "dynamic_ao_debug_view");
    if let Some(viewport) = camera.viewport.as_ref() {
        pass.set_camera_viewport(viewport);
    }
    pass.set_render_pipeline(pipeline);
    pass.set_bind_group(0, &bind_group.0, &[]);
    pass.draw(0..3, 0..1);
    pass_span.end(&mut pass);
}

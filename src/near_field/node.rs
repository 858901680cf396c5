//! The near-field pass.

use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    diagnostic::RecordDiagnostics,
    extract_component::DynamicUniformIndex,
    render_resource::{ComputePassDescriptor, PipelineCache},
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::pipeline::{NearFieldBindGroup, NearFieldPipeline};
use crate::settings::AoTechnique;
use crate::view::{DynamicAoUniform, DynamicAoView};

pub(crate) fn near_field_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &DynamicAoView,
        &NearFieldBindGroup,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipeline: Res<NearFieldPipeline>,
    pipeline_cache: Res<PipelineCache>,
    mut ctx: RenderContext,
) {
    let (camera, ao_view, bind_group, view_offset, settings_index) = view.into_inner();
    if ao_view.technique != AoTechnique::NearField {
        return;
    }
    let scale = if ao_view.half_resolution { 2 } else { 1 };
    let (Some(size), Some(compute_pipeline)) = (
        camera.physical_viewport_size,
        pipeline_cache.get_compute_pipeline(pipeline.pipeline),
    ) else {
        return;
    };

    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let time_span = diagnostics.time_span(ctx.command_encoder(), "dynamic_ao_near_field");
    let encoder = ctx.command_encoder();
    encoder.push_debug_group("dynamic_ao_near_field");
    {
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some("dynamic_ao_near_field"),
            timestamp_writes: None,
        });
        pass.set_pipeline(compute_pipeline);
        pass.set_bind_group(
            0,
            &bind_group.0,
            &[view_offset.offset, settings_index.index()],
        );
        // One invocation per texel of the occlusion buffer (half size at half resolution).
        let texels = (size + (scale - 1)) / scale;
        pass.dispatch_workgroups(texels.x.div_ceil(8), texels.y.div_ceil(8), 1);
    }
    encoder.pop_debug_group();
    time_span.end(ctx.command_encoder());
}

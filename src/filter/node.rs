//! The two blur passes.

use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    diagnostic::RecordDiagnostics,
    extract_component::DynamicUniformIndex,
    render_resource::{ComputePassDescriptor, PipelineCache},
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::pipeline::{BlurBindGroups, BlurPipelines, UpsampleBindGroup};
use crate::view::DynamicAoUniform;

pub(crate) fn blur_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &BlurBindGroups,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipelines: Res<BlurPipelines>,
    pipeline_cache: Res<PipelineCache>,
    mut ctx: RenderContext,
) {
    let (camera, bind_groups, view_offset, settings_index) = view.into_inner();
    let (Some(size), Some(x), Some(y)) = (
        camera.physical_viewport_size,
        pipeline_cache.get_compute_pipeline(pipelines.one.x),
        pipeline_cache.get_compute_pipeline(pipelines.one.y),
    ) else {
        return;
    };
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let time_span = diagnostics.time_span(ctx.command_encoder(), "dynamic_ao_blur");
    let encoder = ctx.command_encoder();
    encoder.push_debug_group("dynamic_ao_blur");
    for (label, pipeline, bind_group) in [
        ("dynamic_ao_blur_x", x, &bind_groups.x),
        ("dynamic_ao_blur_y", y, &bind_groups.y),
    ] {
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind_group, &[view_offset.offset, settings_index.index()]);
        pass.dispatch_workgroups(size.x.div_ceil(8), size.y.div_ceil(8), 1);
    }
    encoder.pop_debug_group();
    time_span.end(ctx.command_encoder());
}

pub(crate) fn upsample_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &UpsampleBindGroup,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipelines: Res<BlurPipelines>,
    pipeline_cache: Res<PipelineCache>,
    mut ctx: RenderContext,
) {
    let (camera, bind_group, view_offset, settings_index) = view.into_inner();
    let (Some(size), Some(pipeline)) = (
        camera.physical_viewport_size,
        pipeline_cache.get_compute_pipeline(pipelines.one.upsample),
    ) else {
        return;
    };
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let time_span = diagnostics.time_span(ctx.command_encoder(), "dynamic_ao_upsample");
    let encoder = ctx.command_encoder();
    encoder.push_debug_group("dynamic_ao_upsample");
    {
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some("dynamic_ao_upsample"),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(
            0,
            &bind_group.0,
            &[view_offset.offset, settings_index.index()],
        );
        pass.dispatch_workgroups(size.x.div_ceil(8), size.y.div_ceil(8), 1);
    }
    encoder.pop_debug_group();
    time_span.end(ctx.command_encoder());
}

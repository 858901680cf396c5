//! The two blur passes.

use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    extract_component::DynamicUniformIndex,
    render_resource::PipelineCache,
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::pipeline::{BlurBindGroups, BlurPipelines, UpsampleBindGroup};
use crate::dispatch::{ComputeStep, record_passes};
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
    let offsets = [view_offset.offset, settings_index.index()];
    let steps = [
        ("dynamic_ao_blur_x", x, &bind_groups.x),
        ("dynamic_ao_blur_y", y, &bind_groups.y),
    ]
    .map(|(label, pipeline, bind_group)| ComputeStep {
        label,
        pipeline,
        bind_group,
        offsets: &offsets,
        texels: size,
    });
    record_passes(&mut ctx, "dynamic_ao_blur", true, &steps);
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
    let step = ComputeStep {
        label: "dynamic_ao_upsample",
        pipeline,
        bind_group: &bind_group.0,
        offsets: &[view_offset.offset, settings_index.index()],
        // One invocation per 2 × 2 pixels (`upsample.wgsl`).
        texels: (size + 1) / 2,
    };
    record_passes(&mut ctx, "dynamic_ao_upsample", true, &[step]);
}

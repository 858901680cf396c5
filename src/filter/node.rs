//! The two blur passes.

use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    extract_component::DynamicUniformIndex,
    render_resource::{BindGroup, CachedComputePipelineId, ComputePipeline, PipelineCache},
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::bind_groups::{BlurBindGroups, UpsampleBindGroup, VisibilityBindGroup};
use super::pipeline::BlurPipelines;
use crate::dispatch::{ComputeStep, SpanStart, Workgroup, record_passes};
use crate::view::AoPassesReady;
use crate::view::DynamicAoUniform;

/// The pipeline and bind group of a view's last filter pass: `own`, or once our passes write
/// Bevy's texture and the view has one, the variant that writes visibility there (`to_visibility`
/// gives its pipeline for a bind group that is guided or not).
fn last_pass<'a>(
    cache: &'a PipelineCache,
    own: (CachedComputePipelineId, &'a BindGroup),
    to_visibility: impl Fn(bool) -> CachedComputePipelineId,
    visibility: Option<&'a VisibilityBindGroup>,
    ready: bool,
) -> Option<(&'a ComputePipeline, &'a BindGroup)> {
    let (id, bind_group) = match visibility.filter(|_| ready) {
        Some(visibility) => (to_visibility(visibility.guided), &visibility.bind_group),
        None => own,
    };
    Some((cache.get_compute_pipeline(id)?, bind_group))
}

pub(crate) fn blur_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &BlurBindGroups,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
        Option<&VisibilityBindGroup>,
        Has<AoPassesReady>,
    )>,
    pipelines: Res<BlurPipelines>,
    pipeline_cache: Res<PipelineCache>,
    span_start: Res<SpanStart>,
    mut ctx: RenderContext,
) {
    let (camera, bind_groups, view_offset, settings_index, visibility, ready) = view.into_inner();
    let (Some(size), Some(x), Some((y, y_bind_group))) = (
        camera.physical_viewport_size,
        pipeline_cache.get_compute_pipeline(pipelines.one.x),
        last_pass(
            &pipeline_cache,
            (pipelines.one.y, &bind_groups.y),
            |_| pipelines.to_visibility.y,
            visibility,
            ready,
        ),
    ) else {
        return;
    };
    let offsets = [view_offset.offset, settings_index.index()];
    let steps = [
        ("dynamic_ao_blur_x", x, &bind_groups.x),
        ("dynamic_ao_blur_y", y, y_bind_group),
    ]
    .map(|(label, pipeline, bind_group)| ComputeStep {
        label,
        pipeline,
        bind_group,
        offsets: &offsets,
        texels: size,
        workgroup: Workgroup::Square,
    });
    record_passes(&mut ctx, &span_start, "dynamic_ao_blur", true, &steps);
}

pub(crate) fn upsample_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &UpsampleBindGroup,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
        Option<&BlurBindGroups>,
        Option<&VisibilityBindGroup>,
        Has<AoPassesReady>,
    )>,
    pipelines: Res<BlurPipelines>,
    pipeline_cache: Res<PipelineCache>,
    span_start: Res<SpanStart>,
    mut ctx: RenderContext,
) {
    let (camera, upsample, view_offset, settings_index, blur, visibility, ready) =
        view.into_inner();
    // Where the blur runs, its Y pass is the last and the upsampling writes occlusion.
    let visibility = visibility.filter(|_| blur.is_none());
    let own = match (upsample.guided, &pipelines.one.guided) {
        (true, Some(guided)) => guided.pipeline,
        _ => pipelines.one.upsample,
    };
    let to_visibility = |guided: bool| match guided {
        true => pipelines.to_visibility.guided.pipeline,
        false => pipelines.to_visibility.upsample,
    };
    let (Some(size), Some((pipeline, bind_group))) = (
        camera.physical_viewport_size,
        last_pass(
            &pipeline_cache,
            (own, &upsample.bind_group),
            to_visibility,
            visibility,
            ready,
        ),
    ) else {
        return;
    };
    let step = ComputeStep {
        label: "dynamic_ao_upsample",
        pipeline,
        bind_group,
        offsets: &[view_offset.offset, settings_index.index()],
        // One invocation per 2 × 2 pixels (`upsample.wgsl`).
        texels: (size + 1) / 2,
        workgroup: Workgroup::Row,
    };
    record_passes(&mut ctx, &span_start, "dynamic_ao_upsample", true, &[step]);
}

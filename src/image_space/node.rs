//! The image-space pass of a view: one dispatch of its technique's pipeline.

use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    extract_component::DynamicUniformIndex,
    render_resource::*,
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use crate::dispatch::{ComputeStep, SpanStart, Workgroup, record_passes};
use crate::settings::AoTechnique;
use crate::view::{DynamicAoUniform, DynamicAoView};

use super::pipeline::{ImageSpaceBindGroup, ImageSpacePipelines};

pub(super) fn image_space_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &DynamicAoView,
        &ImageSpaceBindGroup,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipelines: Res<ImageSpacePipelines>,
    pipeline_cache: Res<PipelineCache>,
    span_start: Res<SpanStart>,
    mut ctx: RenderContext,
) {
    let (camera, ao_view, bind_group, view_offset, settings_index) = view.into_inner();
    let (Some(size), Some(compute_pipeline)) = (
        camera.physical_viewport_size,
        pipelines
            .pipeline(ao_view.technique(), ao_view.half_resolution)
            .and_then(|id| pipeline_cache.get_compute_pipeline(id)),
    ) else {
        return;
    };
    let label = match ao_view.technique() {
        AoTechnique::Horizon => "dynamic_ao_horizon",
        AoTechnique::RayMarch => "dynamic_ao_ray_march",
        _ => "dynamic_ao_near_field",
    };
    // One invocation per texel of the occlusion buffer (half size at half resolution).
    let scale = if ao_view.half_resolution { 2 } else { 1 };
    let mut texels = (size + (scale - 1)) / scale;
    // The checkerboard marches one texel of two in each row.
    if ao_view.checkerboard {
        texels.x = texels.x.div_ceil(2);
    }
    let step = ComputeStep {
        label,
        pipeline: compute_pipeline,
        bind_group: &bind_group.0,
        offsets: &[view_offset.offset, settings_index.index()],
        texels,
        workgroup: Workgroup::Square,
    };
    record_passes(&mut ctx, &span_start, label, true, &[step]);
}

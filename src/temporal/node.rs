//! The temporal pass of a view (one dispatch over its occlusion buffer), and the count of views
//! waiting for it to compile.

use bevy::ecs::prelude::*;
use bevy::math::UVec2;
use bevy::render::{
    render_resource::PipelineCache,
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::pipeline::{Channels, TemporalBindGroup, TemporalPipeline};
use super::view::TemporalHistory;
use crate::dispatch::{ComputeStep, SpanStart, Workgroup, record_passes};
use crate::view::{DynamicAoTextures, DynamicAoView, PendingPasses};

pub(crate) fn temporal_pass(
    view: ViewQuery<(
        &DynamicAoView,
        &DynamicAoTextures,
        &TemporalBindGroup,
        &TemporalHistory,
        &ViewUniformOffset,
    )>,
    pipeline: Res<TemporalPipeline>,
    pipeline_cache: Res<PipelineCache>,
    span_start: Res<SpanStart>,
    mut ctx: RenderContext,
) {
    let (ao_view, textures, bind_group, history, view_offset) = view.into_inner();
    let (true, Some(compute_pipeline)) = (
        ao_view.temporal,
        pipeline_cache.get_compute_pipeline(pipeline.one.pipeline(history.clamps())),
    ) else {
        return;
    };
    let size = textures.near_occlusion.texture.size();
    let step = ComputeStep {
        label: "dynamic_ao_temporal",
        pipeline: compute_pipeline,
        bind_group: &bind_group.0,
        offsets: &[view_offset.offset],
        texels: UVec2::new(size.width, size.height),
        workgroup: Workgroup::Row,
    };
    record_passes(&mut ctx, &span_start, "dynamic_ao_temporal", true, &[step]);
}

/// The temporal pass counts until its pipeline has compiled.
pub(crate) fn wait_for_temporal(
    pipeline_cache: Res<PipelineCache>,
    pipeline: Res<TemporalPipeline>,
    mut views: Query<(&DynamicAoView, &mut PendingPasses)>,
) {
    let ready = pipeline.ready(&pipeline_cache, Channels::One);
    for (view, mut pending) in &mut views {
        pending.wait_for(!view.temporal || ready);
    }
}

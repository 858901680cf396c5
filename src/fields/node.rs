//! The pass that draws every occluder's grid box into a view's field buffer.

use bevy::ecs::prelude::*;
use bevy::render::{
    extract_component::DynamicUniformIndex,
    render_resource::PipelineCache,
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::buffers::FieldBuffers;
use super::pipeline::{FieldBindGroup, FieldPipelines};
use crate::dispatch::{DrawStep, record_draw_pass};
use crate::view::{DynamicAoUniform, DynamicAoView, FarFieldOutputs, FarTerm};

pub(crate) fn field_pass(
    view: ViewQuery<(
        &DynamicAoView,
        &FarFieldOutputs,
        Option<&FieldBindGroup>,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipelines: Res<FieldPipelines>,
    pipeline_cache: Res<PipelineCache>,
    buffers: Res<FieldBuffers>,
    mut ctx: RenderContext,
) {
    let (ao_view, outputs, bind_group, view_offset, settings_index) = view.into_inner();
    let (true, Some(visibility)) = (ao_view.has(FarTerm::Fields), outputs.get(FarTerm::Fields))
    else {
        return;
    };
    // Visibility starts at 1 (open) and each occluder multiplies it down; alpha, the largest
    // occlusion among the fields that join by their union, starts at 0.
    let offsets = [view_offset.offset, settings_index.index()];
    record_draw_pass(
        &mut ctx,
        "dynamic_ao_fields",
        &visibility.default_view,
        bevy::color::LinearRgba::new(1.0, 1.0, 1.0, 0.0),
        bind_group
            .zip(
                pipeline_cache
                    .get_render_pipeline(pipelines.for_shading(ao_view.settings.field_shading)),
            )
            .map(|(bind_group, pipeline)| DrawStep {
                pipeline,
                bind_group: &bind_group.0,
                offsets: &offsets,
                vertices: 36,
                instances: buffers.count,
            }),
    );
}

//! The pass that draws every occluder's grid box into a view's field buffer.

use bevy::ecs::prelude::*;
use bevy::render::{
    diagnostic::RecordDiagnostics,
    extract_component::DynamicUniformIndex,
    render_resource::{
        LoadOp, Operations, PipelineCache, RenderPassColorAttachment, RenderPassDescriptor, StoreOp,
    },
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::buffers::FieldBuffers;
use super::pipeline::{FieldBindGroup, FieldPipelines};
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
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    // Visibility starts at 1 (open) and each occluder multiplies it down; cleared even when no
    // occluder is drawn, because compose reads it whenever fields are on.
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("dynamic_ao_fields"),
        color_attachments: &[Some(RenderPassColorAttachment {
            view: &visibility.default_view,
            depth_slice: None,
            resolve_target: None,
            ops: Operations {
                load: LoadOp::Clear(bevy::color::LinearRgba::WHITE.into()),
                store: StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let pass_span = diagnostics.pass_span(&mut pass, "dynamic_ao_fields");
    let pipeline = pipelines.for_shading(ao_view.settings.field_shading);
    if buffers.count > 0
        && let Some(bind_group) = bind_group
        && let Some(render_pipeline) = pipeline_cache.get_render_pipeline(pipeline)
    {
        pass.set_render_pipeline(render_pipeline);
        pass.set_bind_group(
            0,
            &bind_group.0,
            &[view_offset.offset, settings_index.index()],
        );
        pass.draw(0..36, 0..buffers.count);
    }
    pass_span.end(&mut pass);
}

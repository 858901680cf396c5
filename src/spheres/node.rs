//! The pass that splats the proxies of every occluder into a view's far-field visibility buffer.

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

use super::buffers::SphereBuffer;
use super::pipeline::{SplatBindGroup, SplatPipeline};
use crate::view::{DynamicAoUniform, DynamicAoView, FarFieldOutputs, FarTerm};

pub(crate) fn splat_pass(
    view: ViewQuery<(
        &DynamicAoView,
        &FarFieldOutputs,
        Option<&SplatBindGroup>,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipeline: Res<SplatPipeline>,
    pipeline_cache: Res<PipelineCache>,
    spheres: Res<SphereBuffer>,
    mut ctx: RenderContext,
) {
    let (ao_view, outputs, bind_group, view_offset, settings_index) = view.into_inner();
    let (true, Some(visibility)) = (ao_view.has(FarTerm::Spheres), outputs.get(FarTerm::Spheres))
    else {
        return;
    };
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    // Visibility starts at 1 (open) and each proxy multiplies it down; the largest occlusion (alpha)
    // starts at 0. Cleared even without proxies, because compose reads this buffer whenever the
    // far field is on.
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("dynamic_ao_spheres"),
        color_attachments: &[Some(RenderPassColorAttachment {
            view: &visibility.default_view,
            depth_slice: None,
            resolve_target: None,
            ops: Operations {
                load: LoadOp::Clear(bevy::color::LinearRgba::new(1.0, 1.0, 1.0, 0.0).into()),
                store: StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let pass_span = diagnostics.pass_span(&mut pass, "dynamic_ao_spheres");
    if spheres.count > 0
        && let Some(bind_group) = bind_group
        && let Some(render_pipeline) = pipeline_cache.get_render_pipeline(pipeline.pipeline)
    {
        pass.set_render_pipeline(render_pipeline);
        pass.set_bind_group(
            0,
            &bind_group.0,
            &[view_offset.offset, settings_index.index()],
        );
        pass.draw(0..6, 0..spheres.count);
    }
    pass_span.end(&mut pass);
}

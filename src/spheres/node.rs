//! The pass that splats the proxies of every occluder into a view's far-field visibility buffer.

use bevy::ecs::prelude::*;
use bevy::render::{
    extract_component::DynamicUniformIndex,
    render_resource::PipelineCache,
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::buffers::SphereBuffer;
use super::pipeline::{SplatBindGroup, SplatPipeline};
use crate::dispatch::{DrawStep, record_draw_pass};
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
    // Visibility starts at 1 (open) and each proxy multiplies it down; the largest occlusion
    // (alpha) starts at 0.
    let offsets = [view_offset.offset, settings_index.index()];
    record_draw_pass(
        &mut ctx,
        "dynamic_ao_spheres",
        &visibility.default_view,
        bevy::color::LinearRgba::new(1.0, 1.0, 1.0, 0.0),
        bind_group
            .zip(pipeline_cache.get_render_pipeline(pipeline.pipeline))
            .map(|(bind_group, pipeline)| DrawStep {
                pipeline,
                bind_group: &bind_group.0,
                offsets: &offsets,
                vertices: 6,
                instances: spheres.count,
            }),
    );
}

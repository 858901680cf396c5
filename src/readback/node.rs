//! The read-back copy pass.

use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    extract_component::DynamicUniformIndex,
    render_resource::*,
    renderer::{RenderContext, ViewQuery},
};

use super::pipeline::{ReadbackBindGroup, ReadbackPipeline};
use crate::view::DynamicAoUniform;

pub(crate) fn readback_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &ReadbackBindGroup,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipeline: Res<ReadbackPipeline>,
    pipeline_cache: Res<PipelineCache>,
    mut ctx: RenderContext,
) {
    let (camera, bind_group, settings_index) = view.into_inner();
    let (Some(size), Some(compute_pipeline)) = (
        camera.physical_viewport_size,
        pipeline_cache.get_compute_pipeline(pipeline.pipeline),
    ) else {
        return;
    };
    let encoder = ctx.command_encoder();
    encoder.push_debug_group("dynamic_ao_readback");
    {
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some("dynamic_ao_readback"),
            timestamp_writes: None,
        });
        pass.set_pipeline(compute_pipeline);
        pass.set_bind_group(0, &bind_group.0, &[settings_index.index()]);
        pass.dispatch_workgroups(size.x.div_ceil(8), size.y.div_ceil(8), 1);
    }
    encoder.pop_debug_group();
}

//! The read-back copy pass.

use bevy::ecs::prelude::*;
use bevy::pbr::SsaoPipelineId;
use bevy::render::{
    camera::ExtractedCamera,
    extract_component::DynamicUniformIndex,
    render_resource::*,
    renderer::{RenderContext, ViewQuery},
};

use super::pipeline::{ReadbackBindGroup, ReadbackPipeline};
use crate::compose::{AoShown, FailedPipelines, bevy_ssao_runs, shown};
use crate::view::{AoPassesReady, DynamicAoUniform, DynamicAoView};

pub(crate) fn readback_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &ReadbackBindGroup,
        &DynamicUniformIndex<DynamicAoUniform>,
        &DynamicAoView,
        Has<AoPassesReady>,
        Option<&SsaoPipelineId>,
    )>,
    pipeline: Res<ReadbackPipeline>,
    pipeline_cache: Res<PipelineCache>,
    failed: Res<FailedPipelines>,
    mut ctx: RenderContext,
) {
    let (camera, bind_group, settings_index, ao_view, ours_ready, bevy_ssao) = view.into_inner();
    // Until the passes of the view's technique have compiled, its texture holds zeros or, in
    // their place, Bevy's SSAO: the copy says so rather than pass either off as the view's AO.
    // Where one of ours failed for good, Bevy's SSAO is the fallback the camera keeps.
    let written = shown(
        ao_view.replaces_bevy_ssao(),
        ours_ready,
        bevy_ssao_runs(bevy_ssao, &pipeline_cache),
        failed.any(),
    ) != AoShown::Pending;
    let variant = if written {
        pipeline.pipeline
    } else {
        pipeline.not_written
    };
    let (Some(size), Some(compute_pipeline)) = (
        camera.physical_viewport_size,
        pipeline_cache.get_compute_pipeline(variant),
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

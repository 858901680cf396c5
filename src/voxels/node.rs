//! The voxel passes of a view: building the grids (once per frame, by the first view that needs
//! them), sampling the half-size AO map, accumulating it over frames, upsampling and blurring it.

use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    diagnostic::RecordDiagnostics,
    extract_component::DynamicUniformIndex,
    render_resource::{ComputePassDescriptor, PipelineCache},
    renderer::{RenderContext, ViewQuery},
    view::ViewUniformOffset,
};

use super::buffers::VoxelBuffers;
use super::pipeline::{VoxelBindGroups, VoxelPipelines};
use crate::dispatch::{ComputeStep, SpanStart, Workgroup, record_passes};
use crate::filter::BlurPipelines;
use crate::temporal::{Channels, TemporalPipeline};
use crate::view::{DynamicAoUniform, DynamicAoView, FarTerm, PendingPasses};

/// Most workgroups along one dispatch dimension (WebGPU's guaranteed limit).
const MAX_WORKGROUPS: u32 = 65535;

pub(crate) fn voxel_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &VoxelBindGroups,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    mut buffers: ResMut<VoxelBuffers>,
    pipelines: Res<VoxelPipelines>,
    blur: Res<BlurPipelines>,
    temporal: Res<TemporalPipeline>,
    pipeline_cache: Res<PipelineCache>,
    span_start: Res<SpanStart>,
    mut ctx: RenderContext,
) {
    let (camera, bind_groups, view_offset, settings_index) = view.into_inner();
    let (Some(size), Some(voxelize), Some(sample), Some(upsample), Some(blur_x), Some(blur_y)) = (
        camera.physical_viewport_size,
        pipeline_cache.get_compute_pipeline(pipelines.voxelize),
        pipeline_cache.get_compute_pipeline(pipelines.sample),
        pipeline_cache.get_compute_pipeline(blur.two.upsample),
        pipeline_cache.get_compute_pipeline(blur.two.x),
        pipeline_cache.get_compute_pipeline(blur.two.y),
    ) else {
        return;
    };
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();

    if buffers.needs_voxelizing
        && let (Some(grid), Some(bind_group), Some(fill_interior), Some(mark_bricks)) = (
            buffers.grid(),
            &buffers.voxelize_bind_group,
            pipeline_cache.get_compute_pipeline(pipelines.fill_interior),
            pipeline_cache.get_compute_pipeline(pipelines.mark_bricks),
        )
    {
        ctx.command_encoder().clear_buffer(
            grid,
            0,
            Some(u64::from(buffers.words + buffers.brick_words) * 4),
        );
        let triangles = buffers.counts.triangles;
        if triangles > 0 {
            {
                let mut pass = ctx
                    .command_encoder()
                    .begin_compute_pass(&ComputePassDescriptor {
                        label: Some("dynamic_ao_voxelize"),
                        timestamp_writes: None,
                    });
                let pass_span = diagnostics.pass_span(&mut pass, "dynamic_ao_voxelize");
                pass.set_pipeline(voxelize);
                pass.set_bind_group(0, bind_group, &[]);
                // One workgroup per triangle, folded into two dimensions past the per-dimension
                // limit.
                let x = triangles.min(MAX_WORKGROUPS);
                pass.dispatch_workgroups(x, triangles.div_ceil(x), 1);
                // One invocation per column of the largest grid, one row per volume.
                pass.set_pipeline(fill_interior);
                let columns = buffers.largest_resolution().pow(2);
                pass.dispatch_workgroups(columns.div_ceil(64), buffers.counts.volumes, 1);
                // One row per volume (at most 64³ invocations, 4,096 workgroups, at 512³ cells).
                pass.set_pipeline(mark_bricks);
                let invocations = buffers.brick_marking_invocations();
                pass.dispatch_workgroups(invocations.div_ceil(64), buffers.counts.volumes, 1);
                pass_span.end(&mut pass);
            }
        }
        if let Some((target, bytes)) = &buffers.readback {
            ctx.command_encoder()
                .copy_buffer_to_buffer(grid, 0, target, 0, *bytes);
        }
        buffers.needs_voxelizing = false;
    }

    // No debug groups in this file: lavapipe crashes recording one after the grid's buffer
    // clear (the passes keep their labels).
    let offsets = [view_offset.offset, settings_index.index()];
    let sample_step = ComputeStep {
        label: "dynamic_ao_voxel_ao",
        pipeline: sample,
        bind_group: &bind_groups.sample,
        offsets: &offsets,
        texels: (size + 1) / 2,
        workgroup: Workgroup::Square,
    };
    record_passes(
        &mut ctx,
        &span_start,
        "dynamic_ao_voxel_ao",
        false,
        &[sample_step],
    );

    if let (Some(bind_group), Some(accumulate)) = (
        &bind_groups.temporal,
        pipeline_cache.get_compute_pipeline(temporal.pair.clamped),
    ) {
        let step = ComputeStep {
            label: "dynamic_ao_voxel_temporal",
            pipeline: accumulate,
            bind_group,
            offsets: &offsets[..1],
            texels: (size + 1) / 2,
            workgroup: Workgroup::Row,
        };
        record_passes(
            &mut ctx,
            &span_start,
            "dynamic_ao_voxel_temporal",
            false,
            &[step],
        );
    }

    // The upsampling runs one invocation per 2 × 2 pixels (`filter/upsample.wgsl`).
    let mut passes = vec![(
        "dynamic_ao_voxel_upsample",
        upsample,
        &bind_groups.upsample,
        (size + 1) / 2,
        Workgroup::Row,
    )];
    if let Some(groups) = &bind_groups.blur {
        passes.push((
            "dynamic_ao_voxel_blur_x",
            blur_x,
            &groups.x,
            size,
            Workgroup::Square,
        ));
        passes.push((
            "dynamic_ao_voxel_blur_y",
            blur_y,
            &groups.y,
            size,
            Workgroup::Square,
        ));
    }
    let steps: Vec<ComputeStep> = passes
        .into_iter()
        .map(
            |(label, pipeline, bind_group, texels, workgroup)| ComputeStep {
                label,
                pipeline,
                bind_group,
                offsets: &offsets,
                texels,
                workgroup,
            },
        )
        .collect();
    record_passes(
        &mut ctx,
        &span_start,
        "dynamic_ao_voxel_filter",
        false,
        &steps,
    );
}

/// A view with voxel volumes counts their passes until they have compiled.
pub(crate) fn wait_for_voxels(
    pipeline_cache: Res<PipelineCache>,
    pipelines: Res<VoxelPipelines>,
    blur: Res<BlurPipelines>,
    temporal: Res<TemporalPipeline>,
    mut views: Query<(&DynamicAoView, &mut PendingPasses)>,
) {
    let ready = |id| pipeline_cache.get_compute_pipeline(id).is_some();
    let all_ready = ready(pipelines.voxelize)
        && ready(pipelines.fill_interior)
        && ready(pipelines.mark_bricks)
        && ready(pipelines.sample)
        && blur.two.ready(&pipeline_cache);
    let temporal_ready = temporal.ready(&pipeline_cache, Channels::Pair);
    for (view, mut pending) in &mut views {
        if view.has(FarTerm::Voxels) {
            pending.wait_for(all_ready && (!view.voxel_temporal || temporal_ready));
        }
    }
}

//! Recording the plugin's passes: one helper for compute passes and one for the far field's
//! draws, so that every pass gets its label, its debug group and its GPU time span the same way
//! (`cargo bench --bench gpu_passes` reads the spans by these labels).

use bevy::color::LinearRgba;
use bevy::ecs::prelude::*;
use bevy::math::UVec2;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{
    BindGroup, ComputePassDescriptor, ComputePipeline, LoadOp, Operations,
    RenderPassColorAttachment, RenderPassDescriptor, RenderPipeline, StoreOp, TextureView,
    WgpuFeatures,
};
use bevy::render::renderer::{RenderContext, RenderDevice};
use wgpu::{QuerySet, QuerySetDescriptor, QueryType};

/// A timestamp query the compute passes' time spans write right after their start, and nothing
/// reads. lavapipe takes a timestamp's time when it next runs the draws it has queued (it bins the
/// query with them), while it runs a compute dispatch at once: the start of a span whose passes
/// read no freshly drawn texture was taken after their work, and the span read empty (the
/// temporal pass's and the upsampling's, in most frames on models on a floor). Writing a
/// timestamp makes lavapipe run what it has queued first, so the span's start is taken there. On
/// other adapters the write costs next to nothing. `None` where the device cannot write
/// timestamps between passes, and on macOS, where Bevy writes none there either.
#[derive(Resource)]
pub(crate) struct SpanStart(Option<QuerySet>);

impl FromWorld for SpanStart {
    fn from_world(world: &mut World) -> Self {
        let device = world.resource::<RenderDevice>();
        let needed = WgpuFeatures::TIMESTAMP_QUERY | WgpuFeatures::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let writable = !cfg!(target_os = "macos") && device.features().contains(needed);
        Self(writable.then(|| {
            device.wgpu_device().create_query_set(&QuerySetDescriptor {
                label: Some("dynamic_ao_span_start"),
                ty: QueryType::Timestamp,
                count: 1,
            })
        }))
    }
}

/// The shape of a compute shader's workgroup, which its WGSL's `@workgroup_size` states too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Workgroup {
    /// 8 × 8 invocations: passes that read scattered texels (rays) or none in particular.
    Square,
    /// 64 × 1 invocations: passes that read each texel's neighbours in the rows around it. On
    /// lavapipe (8 lanes a row, texture reads as gathers) a workgroup that walks along rows reads
    /// texels the previous lanes brought into the cache: the upsampling cost 14–18% less and the
    /// temporal pass 13% less than in 8 × 8 workgroups (BENCHMARKS.md, "Workgroups along rows").
    Row,
}

impl Workgroup {
    /// Invocations along x and y.
    pub fn size(self) -> UVec2 {
        match self {
            Self::Square => UVec2::splat(8),
            Self::Row => UVec2::new(64, 1),
        }
    }
}

/// One compute pass: workgroups of `workgroup` over `texels`.
pub(crate) struct ComputeStep<'a> {
    /// The pass's label.
    pub label: &'static str,
    pub pipeline: &'a ComputePipeline,
    /// Bound at group 0 with `offsets`.
    pub bind_group: &'a BindGroup,
    pub offsets: &'a [u32],
    /// The texels one invocation each covers.
    pub texels: UVec2,
    /// The shader's workgroup.
    pub workgroup: Workgroup,
}

/// Records `steps` in order within one GPU time span named `label`, inside a debug group of the
/// same name when `debug_group` is set.
pub(crate) fn record_passes(
    ctx: &mut RenderContext,
    span_start: &SpanStart,
    label: &'static str,
    debug_group: bool,
    steps: &[ComputeStep],
) {
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let time_span = diagnostics.time_span(ctx.command_encoder(), label);
    let encoder = ctx.command_encoder();
    if let (Some(_), Some(query)) = (diagnostics, span_start.0.as_ref()) {
        encoder.write_timestamp(query, 0);
    }
    if debug_group {
        encoder.push_debug_group(label);
    }
    for step in steps {
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some(step.label),
            timestamp_writes: None,
        });
        pass.set_pipeline(step.pipeline);
        pass.set_bind_group(0, step.bind_group, step.offsets);
        let size = step.workgroup.size();
        let (x, y) = (
            step.texels.x.div_ceil(size.x),
            step.texels.y.div_ceil(size.y),
        );
        pass.dispatch_workgroups(x, y, 1);
    }
    if debug_group {
        encoder.pop_debug_group();
    }
    time_span.end(ctx.command_encoder());
}

/// One instanced draw: `vertices` per instance, `instances` of them.
pub(crate) struct DrawStep<'a> {
    pub pipeline: &'a RenderPipeline,
    /// Bound at group 0 with `offsets`.
    pub bind_group: &'a BindGroup,
    pub offsets: &'a [u32],
    pub vertices: u32,
    pub instances: u32,
}

/// Records one render pass named `label` into `target`, cleared to `clear` first (even when
/// there is nothing to draw, since compose reads the target whenever its term is on), inside a
/// GPU time span of the same name.
pub(crate) fn record_draw_pass(
    ctx: &mut RenderContext,
    label: &'static str,
    target: &TextureView,
    clear: LinearRgba,
    step: Option<DrawStep>,
) {
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: Operations {
                load: LoadOp::Clear(clear.into()),
                store: StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let pass_span = diagnostics.pass_span(&mut pass, label);
    if let Some(step) = step.filter(|step| step.instances > 0) {
        pass.set_render_pipeline(step.pipeline);
        pass.set_bind_group(0, step.bind_group, step.offsets);
        pass.draw(0..step.vertices, 0..step.instances);
    }
    pass_span.end(&mut pass);
}

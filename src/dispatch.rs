//! Recording the plugin's compute passes: one helper, so that every pass gets its label, its
//! debug group and its GPU time span the same way (`cargo bench --bench gpu_passes` reads the
//! spans by these labels).

use bevy::math::UVec2;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{BindGroup, ComputePassDescriptor, ComputePipeline};
use bevy::render::renderer::RenderContext;

/// One compute pass: 8 × 8 workgroups over `texels`.
pub(crate) struct ComputeStep<'a> {
    /// The pass's label.
    pub label: &'static str,
    pub pipeline: &'a ComputePipeline,
    /// Bound at group 0 with `offsets`.
    pub bind_group: &'a BindGroup,
    pub offsets: &'a [u32],
    /// The texels one invocation each covers.
    pub texels: UVec2,
}

/// Records `steps` in order within one GPU time span named `label`, inside a debug group of the
/// same name when `debug_group` is set.
pub(crate) fn record_passes(
    ctx: &mut RenderContext,
    label: &'static str,
    debug_group: bool,
    steps: &[ComputeStep],
) {
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let time_span = diagnostics.time_span(ctx.command_encoder(), label);
    let encoder = ctx.command_encoder();
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
        pass.dispatch_workgroups(step.texels.x.div_ceil(8), step.texels.y.div_ceil(8), 1);
    }
    if debug_group {
        encoder.pop_debug_group();
    }
    time_span.end(ctx.command_encoder());
}

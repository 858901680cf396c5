//! A pass that never compiles leaves its cameras on Bevy's SSAO (see
//! [`hand_over_from_bevy_ssao`](super::hand_over_from_bevy_ssao)); this says so, once per pass.

use bevy::ecs::prelude::*;
use bevy::log::error;
use bevy::platform::collections::HashSet;
use bevy::render::render_resource::{CachedPipelineState, PipelineCache, PipelineDescriptor};

use crate::view::retried;

/// Every pipeline of this crate has a label that starts so.
const LABEL_PREFIX: &str = "dynamic_ao";

/// The labels of our pipelines that failed for good: while any has, a camera showing Bevy's
/// SSAO shows its fallback, not a pass still compiling.
#[derive(Resource, Default)]
pub(crate) struct FailedPipelines(HashSet<String>);

impl FailedPipelines {
    /// Whether any of our pipelines failed for good.
    pub fn any(&self) -> bool {
        !self.0.is_empty()
    }
}

/// Logs an error naming each of our pipelines that failed for good (a shader that does not
/// compile on this adapter): the cameras that need it keep Bevy's SSAO.
pub(super) fn report_failed_pipelines(
    pipeline_cache: Res<PipelineCache>,
    mut reported: ResMut<FailedPipelines>,
) {
    for pipeline in pipeline_cache.pipelines() {
        let CachedPipelineState::Err(error) = &pipeline.state else {
            continue;
        };
        if retried(error) {
            continue;
        }
        let label = match &pipeline.descriptor {
            PipelineDescriptor::RenderPipelineDescriptor(d) => d.label.as_deref(),
            PipelineDescriptor::ComputePipelineDescriptor(d) => d.label.as_deref(),
        };
        let Some(label) = label.filter(|l| l.starts_with(LABEL_PREFIX)) else {
            continue;
        };
        if reported.0.insert(label.to_owned()) {
            error!(
                "bevy_dynamic_ao: the pipeline '{label}' failed to compile on this adapter \
                 ({error}); cameras that need it keep Bevy's SSAO"
            );
        }
    }
}

//! The per-view state of AO field occluders: whether any exist and whether the pipeline of the
//! view's shading has compiled (their visibility buffer is made by `view::prepare_far_visibility`).

use bevy::ecs::prelude::*;
use bevy::render::{Extract, render_resource::PipelineCache};

use super::pipeline::FieldPipelines;
use super::systems::ActiveAoField;
use crate::view::{DynamicAoView, FarTerm, FarTermsPresent, PendingPasses};

pub(crate) fn note_field_occluders(
    mut present: ResMut<FarTermsPresent>,
    occluders: Extract<Query<(), With<ActiveAoField>>>,
) {
    present.set(FarTerm::Fields, !occluders.is_empty());
}

pub(crate) fn wait_for_fields(
    pipeline_cache: Res<PipelineCache>,
    pipelines: Res<FieldPipelines>,
    mut views: Query<(&DynamicAoView, &mut PendingPasses)>,
) {
    for (view, mut pending) in &mut views {
        if view.has(FarTerm::Fields) {
            let pipeline = pipelines.for_shading(view.settings.field_shading);
            pending.wait_for(pipeline_cache.get_render_pipeline(pipeline).is_some());
        }
    }
}

//! The per-view state of sphere occluders: whether any exist and whether the splat pass has
//! compiled (their visibility buffer is made by `view::prepare_far_visibility`).

use bevy::ecs::prelude::*;
use bevy::render::{Extract, render_resource::PipelineCache};

use super::component::OccluderSpheres;
use super::pipeline::SplatPipeline;
use crate::view::{DynamicAoView, FarTerm, FarTermsPresent, PendingPasses};

pub(crate) fn note_sphere_occluders(
    mut present: ResMut<FarTermsPresent>,
    occluders: Extract<Query<(), With<OccluderSpheres>>>,
) {
    present.set(FarTerm::Spheres, !occluders.is_empty());
}

pub(crate) fn wait_for_splat(
    pipeline_cache: Res<PipelineCache>,
    splat: Res<SplatPipeline>,
    mut views: Query<(&DynamicAoView, &mut PendingPasses)>,
) {
    let ready = pipeline_cache.get_render_pipeline(splat.pipeline).is_some();
    for (view, mut pending) in &mut views {
        if view.has(FarTerm::Spheres) {
            pending.wait_for(ready);
        }
    }
}

//! The per-view state of AO field occluders: whether any exist, their visibility buffer and
//! whether the pipeline of the view's shading has compiled.

use bevy::ecs::prelude::*;
use bevy::render::{
    Extract,
    camera::ExtractedCamera,
    render_resource::{PipelineCache, TextureUsages},
    renderer::RenderDevice,
    texture::TextureCache,
};

use super::render::FieldPipelines;
use super::systems::ActiveAoField;
use crate::view::{
    DynamicAoView, FAR_OCCLUSION_FORMAT, FarFieldOutputs, FarTerm, FarTermsPresent, PendingPasses,
    view_size, view_texture,
};

pub(crate) fn note_field_occluders(
    mut present: ResMut<FarTermsPresent>,
    occluders: Extract<Query<(), With<ActiveAoField>>>,
) {
    present.set(FarTerm::Fields, !occluders.is_empty());
}

/// The product of the AO field occluders' visibilities, full size, on every view they take part
/// in.
pub(crate) fn prepare_field_visibility(
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    mut views: Query<(&ExtractedCamera, &DynamicAoView, &mut FarFieldOutputs)>,
) {
    for (camera, view, mut outputs) in &mut views {
        if let (true, Some(size)) = (view.has(FarTerm::Fields), view_size(camera)) {
            let texture = view_texture(
                &mut texture_cache,
                &render_device,
                "dynamic_ao_field_visibility",
                size,
                FAR_OCCLUSION_FORMAT,
                TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING,
            );
            outputs.set(FarTerm::Fields, texture);
        }
    }
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

//! The per-view state of sphere occluders: whether any exist, their visibility buffer and
//! whether the splat pass has compiled.

use bevy::ecs::prelude::*;
use bevy::render::{
    Extract,
    camera::ExtractedCamera,
    render_resource::{PipelineCache, TextureUsages},
    renderer::RenderDevice,
    texture::TextureCache,
};

use super::component::OccluderSpheres;
use super::splat::SplatPipeline;
use crate::view::{
    DynamicAoView, FAR_OCCLUSION_FORMAT, FarFieldOutputs, FarTerm, FarTermsPresent, PendingPasses,
    view_size, view_texture,
};

pub(crate) fn note_sphere_occluders(
    mut present: ResMut<FarTermsPresent>,
    occluders: Extract<Query<(), With<OccluderSpheres>>>,
) {
    present.set(FarTerm::Spheres, !occluders.is_empty());
}

/// The product of the sphere occluders' visibilities, full size, on every view they take part in.
pub(crate) fn prepare_sphere_visibility(
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    mut views: Query<(&ExtractedCamera, &DynamicAoView, &mut FarFieldOutputs)>,
) {
    for (camera, view, mut outputs) in &mut views {
        if let (true, Some(size)) = (view.has(FarTerm::Spheres), view_size(camera)) {
            let texture = view_texture(
                &mut texture_cache,
                &render_device,
                "dynamic_ao_sphere_visibility",
                size,
                FAR_OCCLUSION_FORMAT,
                TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING,
            );
            outputs.set(FarTerm::Spheres, texture);
        }
    }
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

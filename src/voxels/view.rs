//! The per-view state of voxel volumes: whether any exist and their occlusion buffers (whether
//! their passes have compiled is counted in `node.rs`).

use bevy::ecs::prelude::*;
use bevy::render::{
    Extract,
    camera::ExtractedCamera,
    render_resource::TextureUsages,
    renderer::RenderDevice,
    texture::{CachedTexture, TextureCache},
};

use super::component::VoxelGridInfo;
use crate::filter::OCCLUSION_PAIR_FORMAT;
use crate::view::{
    DynamicAoView, FarFieldOutputs, FarTerm, FarTermsPresent, half_size, view_size, view_texture,
};

pub(crate) fn note_voxel_volumes(
    mut present: ResMut<FarTermsPresent>,
    volumes: Extract<Query<(), With<VoxelGridInfo>>>,
) {
    present.set(FarTerm::Voxels, !volumes.is_empty());
}

/// The voxel buffers of a view besides its output (the upsampled, filtered occlusion, which
/// compose reads from [`FarFieldOutputs`]). Each has two channels: the near field's share and
/// the rest.
#[derive(Component)]
pub(crate) struct VoxelTextures {
    /// Occlusion as sampled, half size.
    pub low: CachedTexture,
    /// Between the two passes of the voxel blur; only while the blur is on.
    pub scratch: Option<CachedTexture>,
}

impl VoxelTextures {
    /// Whether the upsampled voxel occlusion is blurred on `view`.
    pub fn blurred(view: &DynamicAoView) -> bool {
        view.settings.blur.sanitized().radius > 0
    }
}

pub(crate) fn prepare_voxel_textures(
    mut commands: Commands,
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    mut views: Query<(
        Entity,
        &ExtractedCamera,
        &DynamicAoView,
        &mut FarFieldOutputs,
    )>,
) {
    for (entity, camera, view, mut outputs) in &mut views {
        let (true, Some(size)) = (view.has(FarTerm::Voxels), view_size(camera)) else {
            commands.entity(entity).remove::<VoxelTextures>();
            continue;
        };
        let mut texture = |label, size| {
            view_texture(
                &mut texture_cache,
                &render_device,
                label,
                size,
                OCCLUSION_PAIR_FORMAT,
                TextureUsages::STORAGE_BINDING | TextureUsages::TEXTURE_BINDING,
            )
        };
        let low = texture("dynamic_ao_voxel_low", half_size(size));
        outputs.set(FarTerm::Voxels, texture("dynamic_ao_voxel_occlusion", size));
        let scratch =
            VoxelTextures::blurred(view).then(|| texture("dynamic_ao_voxel_scratch", size));
        commands
            .entity(entity)
            .insert(VoxelTextures { low, scratch });
    }
}

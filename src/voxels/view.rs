//! The per-view state of voxel volumes: whether any exist and their occlusion buffers (whether
//! their passes have compiled is counted in `node.rs`).

use crate::nd_buffer::FrontLayer;
use bevy::ecs::prelude::*;
use bevy::render::{
    Extract,
    camera::ExtractedCamera,
    render_resource::TextureUsages,
    renderer::{RenderDevice, RenderQueue},
    texture::{CachedTexture, TextureCache},
};

use super::component::VoxelGridInfo;
use crate::memory::DynamicAoGpuMemory;
use crate::temporal::{HistoryFrame, TemporalHistory, started_over};
use crate::view::OCCLUSION_PAIR_FORMAT;
use crate::view::{
    DynamicAoUniform, DynamicAoView, FarFieldOutputs, FarTerm, FarTermsPresent, half_size,
    view_size, view_texture,
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
    /// Under temporal accumulation, `low` joined with its history, half size: what the
    /// upsampling reads.
    pub accumulated: Option<CachedTexture>,
    /// Between the two passes of the voxel blur; only while the blur is on.
    pub scratch: Option<CachedTexture>,
}

impl VoxelTextures {
    /// The half-size map the upsampling reads.
    pub fn upsampled(&self) -> &CachedTexture {
        self.accumulated.as_ref().unwrap_or(&self.low)
    }

    /// Whether the upsampled voxel occlusion is blurred on `view`: by
    /// [`AoBlur::voxel_radius`](crate::AoBlur::voxel_radius), which is the accumulated radius where
    /// the view accumulates the voxel term.
    pub fn blurred(view: &DynamicAoView) -> bool {
        view.settings
            .blur
            .sanitized()
            .voxel_radius(view.voxel_temporal)
            > 0
    }
}

/// The voxel term's temporal history on a view that accumulates it.
#[derive(Component)]
pub(crate) struct VoxelHistory(pub TemporalHistory);

pub(crate) fn prepare_voxel_textures(
    mut commands: Commands,
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut views: Query<(
        Entity,
        &ExtractedCamera,
        &DynamicAoView,
        &mut FarFieldOutputs,
        Option<FrontLayer>,
        Option<&mut VoxelHistory>,
        Option<&DynamicAoUniform>,
    )>,
    memory: Res<DynamicAoGpuMemory>,
) {
    // What last frame left; this frame's new and dropped histories count from the next.
    let bytes = views
        .iter()
        .filter_map(|(.., history, _)| history.map(|h| h.0.bytes()))
        .sum();
    memory.report("voxel temporal", bytes);
    for (entity, camera, view, mut outputs, prepass, history, uniform) in &mut views {
        let (true, Some(size)) = (view.has(FarTerm::Voxels), view_size(camera)) else {
            commands
                .entity(entity)
                .remove::<(VoxelTextures, VoxelHistory)>();
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
        let accumulated = view
            .voxel_temporal
            .then(|| texture("dynamic_ao_voxel_accumulated", half_size(size)));
        if view.voxel_temporal {
            let frame = HistoryFrame {
                size: half_size(size),
                scale: 2,
                settings: &view.settings,
                started_over: started_over(uniform),
                motion_vectors: prepass
                    .as_ref()
                    .is_some_and(|p| p.motion_vectors().is_some()),
                frame: 0,
            };
            let history = history.map(|h| &mut h.into_inner().0);
            if let Some(new) = TemporalHistory::advance(history, &render_device, &queue, frame) {
                commands.entity(entity).insert(VoxelHistory(new));
            }
        } else if history.is_some() {
            commands.entity(entity).remove::<VoxelHistory>();
        }
        commands.entity(entity).insert(VoxelTextures {
            low,
            accumulated,
            scratch,
        });
    }
}

//! The per-view state of temporal accumulation: the two history textures, which one is read this
//! frame, and whether the history is dropped (when is the view's sequence's to say, in
//! `sequence.rs`; whether the pass has compiled is counted in `node.rs`).

use crate::nd_buffer::FrontLayer;
use bevy::ecs::prelude::*;
use bevy::image::ToExtents;
use bevy::math::UVec2;
use bevy::render::{
    render_resource::{
        ShaderType, Texture, TextureDescriptor, TextureDimension, TextureFormat, TextureUsages,
        TextureView, TextureViewDescriptor, UniformBuffer,
    },
    renderer::{RenderDevice, RenderQueue},
};

use super::sequence::started_over;
use crate::memory::DynamicAoGpuMemory;
use crate::settings::DynamicAo;
use crate::view::{DynamicAoTextures, DynamicAoUniform, DynamicAoView};

/// Format of a history texel: occlusion, linear depth and frame count as f32 bits, and the
/// normal as 4 × 8-bit snorm.
const HISTORY_FORMAT: TextureFormat = TextureFormat::Rgba32Uint;

/// `TemporalUniform` in `temporal.wgsl`.
#[derive(ShaderType, Clone, Copy, Default)]
pub(super) struct TemporalUniform {
    pub reset: u32,
    pub max_frames: f32,
    pub scale: u32,
    pub frame: u32,
}

/// A view's history of one accumulated quantity, kept across frames.
#[derive(Component)]
pub(crate) struct TemporalHistory {
    size: UVec2,
    textures: [(Texture, TextureView); 2],
    /// Which texture is read this frame; the other is written.
    read: usize,
    pub(super) uniform: UniformBuffer<TemporalUniform>,
}

/// What a history is told each frame.
pub(crate) struct HistoryFrame<'a> {
    /// Size of the accumulated texture, texels.
    pub size: UVec2,
    /// Full-resolution pixels per texel along each axis.
    pub scale: u32,
    /// The camera's settings this frame.
    pub settings: &'a DynamicAo,
    /// Whether the view's sequence started over this frame ([`super::sequence::started_over`]):
    /// the history starts over with it, so that the two never disagree on where it began.
    pub started_over: bool,
    /// Whether the view has motion vectors: without them the history is dropped (and the
    /// sequence goes on, since the sample pattern does not need them).
    pub motion_vectors: bool,
    /// Under the ray march's checkerboard, the view's place in its sample sequence
    /// (`DynamicAoUniform::frame_index`), which says the texels marched this frame; 0 where every
    /// texel is.
    pub frame: u32,
}

impl TemporalHistory {
    /// GPU bytes its two textures take.
    pub fn bytes(&self) -> u64 {
        let texel = u64::from(HISTORY_FORMAT.block_copy_size(None).unwrap_or(16));
        2 * u64::from(self.size.x) * u64::from(self.size.y) * texel
    }

    /// The history this frame reads and the one it writes.
    pub(super) fn views(&self) -> (&TextureView, &TextureView) {
        (&self.textures[self.read].1, &self.textures[1 - self.read].1)
    }

    /// Whether the image-space history is clamped this frame: on the frames that read texture 0,
    /// every other frame from the last reset (why: the module's docs, "Ghosting").
    pub(super) fn clamps(&self) -> bool {
        self.read == 0
    }

    /// The history this frame writes: once the temporal pass has run, each texel holds the
    /// accumulated occlusion, its linear depth and frame count (f32 bits) and its normal
    /// (4 × 8-bit snorm), read as a `texture_2d<u32>`.
    pub fn written(&self) -> &TextureView {
        self.views().1
    }

    /// Moves `history` on by a frame: swaps its textures and writes its uniform, dropping what it
    /// holds where the view's sequence started over or motion vectors are missing. Returns a new
    /// history (which holds nothing yet) where there was none or its size differs.
    pub fn advance(
        history: Option<&mut TemporalHistory>,
        device: &RenderDevice,
        queue: &RenderQueue,
        frame: HistoryFrame,
    ) -> Option<TemporalHistory> {
        let reset = frame.started_over || !frame.motion_vectors;
        let uniform = |reset: bool| TemporalUniform {
            reset: u32::from(reset),
            max_frames: frame.settings.temporal.frames() as f32,
            scale: frame.scale,
            frame: frame.frame,
        };
        match history {
            Some(history) if history.size == frame.size => {
                // Counted from the reset, as the view's sequence is, so that the frames that clamp
                // are the same ones in every capture that accumulates the same frames.
                history.read = if reset { 0 } else { 1 - history.read };
                history.uniform.set(uniform(reset));
                history.uniform.write_buffer(device, queue);
                None
            }
            _ => {
                let mut history = TemporalHistory {
                    size: frame.size,
                    textures: history_textures(device, frame.size),
                    read: 0,
                    uniform: UniformBuffer::default(),
                };
                history.uniform.set(uniform(true));
                history.uniform.write_buffer(device, queue);
                Some(history)
            }
        }
    }
}

fn history_textures(device: &RenderDevice, size: UVec2) -> [(Texture, TextureView); 2] {
    ["dynamic_ao_history_a", "dynamic_ao_history_b"].map(|label| {
        let texture = device.create_texture(&TextureDescriptor {
            label: Some(label),
            size: size.to_extents(),
            mip_level_count: 1,
            sample_count: 1,
            dimension: TextureDimension::D2,
            format: HISTORY_FORMAT,
            usage: TextureUsages::STORAGE_BINDING | TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&TextureViewDescriptor::default());
        (texture, view)
    })
}

/// Makes, swaps or drops the image-space occlusion's history of each view.
pub(crate) fn prepare_history(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut views: Query<(
        Entity,
        &DynamicAoView,
        Option<&DynamicAoTextures>,
        Option<FrontLayer>,
        Option<&mut TemporalHistory>,
        Option<&DynamicAoUniform>,
    )>,
    memory: Res<DynamicAoGpuMemory>,
) {
    // What last frame left; this frame's new and dropped histories count from the next.
    let bytes = views
        .iter()
        .filter_map(|(.., history, _)| history.map(TemporalHistory::bytes))
        .sum();
    memory.report("temporal", bytes);
    for (entity, view, textures, prepass, history, ao_uniform) in &mut views {
        let (true, Some(textures)) = (view.temporal, textures) else {
            if history.is_some() {
                commands.entity(entity).remove::<TemporalHistory>();
            }
            continue;
        };
        let size = textures.near_occlusion.texture.size();
        let frame = HistoryFrame {
            size: UVec2::new(size.width, size.height),
            scale: if view.half_resolution { 2 } else { 1 },
            settings: &view.settings,
            started_over: started_over(ao_uniform),
            motion_vectors: prepass.is_some_and(|p| p.motion_vectors().is_some()),
            frame: match view.checkerboard {
                true => ao_uniform.map_or(0, |u| u.frame_index),
                false => 0,
            },
        };
        let history = history.map(Mut::into_inner);
        if let Some(new) = TemporalHistory::advance(history, &device, &queue, frame) {
            commands.entity(entity).insert(new);
        }
    }
}

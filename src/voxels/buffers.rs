//! This frame's triangles and volumes on the GPU and the bit grid they are voxelized into.

use bevy::asset::Handle;
use bevy::ecs::prelude::*;
use bevy::log::warn;
use bevy::render::{
    Extract,
    render_asset::RenderAssets,
    render_resource::*,
    renderer::{RenderDevice, RenderQueue},
    storage::{GpuShaderBuffer, ShaderBuffer},
};
use bytemuck::Zeroable;

use crate::capabilities::cap_to_storage_binding;
use crate::memory::DynamicAoGpuMemory;

use super::component::{BRICK_CELLS, VoxelGridReadback, brick_words, grid_words};
use super::grid_data::{GpuVolume, GridTriangle, VoxelFrame};

/// Counts of this frame's buffers (`VoxelParams` in `voxel_grid.wgsl`).
#[derive(ShaderType, Clone, Copy, Debug, Default)]
pub(crate) struct VoxelParams {
    pub triangles: u32,
    pub volumes: u32,
    /// First word of the interior bits: the surface bits of every volume come first.
    pub solid_offset: u32,
    /// First word of the coarse occupancy bits, which follow every volume's interior bits.
    pub brick_offset: u32,
}

/// This frame's voxel data on the GPU.
#[derive(Resource)]
pub(crate) struct VoxelBuffers {
    pub(super) triangles: RawBufferVec<GridTriangle>,
    pub(super) volumes: RawBufferVec<GpuVolume>,
    pub(super) params: UniformBuffer<VoxelParams>,
    /// The bit grids of all volumes, back to back; grows, never shrinks.
    pub(super) grid: Option<Buffer>,
    /// 32-bit words of `grid` in use this frame for surface and interior bits.
    pub words: u32,
    /// 32-bit words of the coarse occupancy bits after them.
    pub brick_words: u32,
    pub counts: VoxelParams,
    /// The storage buffer asset [`VoxelGridReadback`] names, if any.
    readback_request: Option<Handle<ShaderBuffer>>,
    /// Where the grids are copied for [`VoxelGridReadback`], and how many bytes.
    pub readback: Option<(Buffer, u64)>,
    /// Set each frame; the first view that samples the grids builds them and clears it.
    pub needs_voxelizing: bool,
    pub voxelize_bind_group: Option<BindGroup>,
}

impl Default for VoxelBuffers {
    fn default() -> Self {
        Self {
            triangles: RawBufferVec::new(BufferUsages::STORAGE),
            volumes: RawBufferVec::new(BufferUsages::STORAGE),
            params: UniformBuffer::default(),
            grid: None,
            words: 0,
            brick_words: 0,
            counts: VoxelParams::default(),
            readback_request: None,
            readback: None,
            needs_voxelizing: false,
            voxelize_bind_group: None,
        }
    }
}

impl VoxelBuffers {
    pub fn grid(&self) -> Option<&Buffer> {
        self.grid.as_ref()
    }

    /// Cells per axis of the finest grid in use (0 with none).
    pub fn largest_resolution(&self) -> u32 {
        self.volumes.values()[..self.counts.volumes as usize]
            .iter()
            .map(|v| v.resolution)
            .max()
            .unwrap_or(0)
    }

    /// Invocations `mark_bricks` (`voxelize.wgsl`) needs for the volume that needs the most: one
    /// per word's width of bricks where rows of cells fill whole words, else one per brick.
    pub fn brick_marking_invocations(&self) -> u32 {
        self.volumes.values()[..self.counts.volumes as usize]
            .iter()
            .map(|v| {
                let bricks = v.resolution.div_ceil(BRICK_CELLS);
                match v.resolution % 32 {
                    0 => v.resolution / 32 * bricks * bricks,
                    _ => bricks.pow(3),
                }
            })
            .max()
            .unwrap_or(0)
    }

    /// Whether a volume in use asks for its occupied voxels to be drawn.
    pub fn any_shown(&self) -> bool {
        self.volumes.values()[..self.counts.volumes as usize]
            .iter()
            .any(|v| v.flags & 1 != 0)
    }

    /// Volumes, grid and counts, for the passes that read the grids.
    pub fn bindings(
        &self,
    ) -> Option<(
        BindingResource<'_>,
        BindingResource<'_>,
        BindingResource<'_>,
    )> {
        Some((
            self.volumes.buffer()?.as_entire_binding(),
            self.grid.as_ref()?.as_entire_binding(),
            self.params.binding()?,
        ))
    }
}

/// Main world's triangles and volumes of this frame, copied into the staging vectors.
pub(crate) fn extract_voxels(
    mut buffers: ResMut<VoxelBuffers>,
    frame: Extract<Res<VoxelFrame>>,
    readback: Extract<Option<Res<VoxelGridReadback>>>,
) {
    buffers.triangles.clear();
    buffers.triangles.extend(frame.triangles.iter().copied());
    buffers.volumes.clear();
    buffers.volumes.extend(frame.volumes.iter().copied());
    buffers.readback_request = readback.as_ref().map(|r| r.0.clone());
}

/// Uploads this frame's data and makes sure the grid buffer is large enough.
pub(crate) fn write_voxel_buffers(
    mut buffers: ResMut<VoxelBuffers>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    storage_buffers: Res<RenderAssets<GpuShaderBuffer>>,
    mut warned: Local<(bool, bool, bool)>,
    memory: Res<DynamicAoGpuMemory>,
) {
    let buffers = buffers.as_mut();
    let max_bytes = device.limits().max_storage_buffer_binding_size;
    let (kept, words, bricks) = volumes_that_fit(buffers.volumes.values(), max_bytes);
    let total = buffers.volumes.len();
    if kept < total && !warned.0 {
        warned.0 = true;
        warn!(
            "VoxelAoVolume: the grids of {total} volumes need more than this device's largest \
             storage buffer ({} MiB); the last {} cast no occlusion",
            max_bytes / (1 << 20),
            total - kept
        );
    }
    buffers.volumes.truncate(kept);
    buffers.counts = VoxelParams {
        triangles: buffers.triangles.len() as u32,
        volumes: kept as u32,
        solid_offset: words as u32,
        brick_offset: words as u32 * 2,
    };
    if kept < total {
        // Triangles of dropped volumes would index past the kept ones.
        let kept = kept as u32;
        let values: Vec<GridTriangle> = buffers
            .triangles
            .values()
            .iter()
            .filter(|t| t.a[3].to_bits() < kept)
            .copied()
            .collect();
        buffers.triangles.clear();
        buffers.triangles.extend(values);
        buffers.counts.triangles = buffers.triangles.len() as u32;
    }
    let len = buffers.triangles.len();
    let kept_triangles = cap_to_storage_binding::<GridTriangle>(
        "VoxelAoVolume triangles",
        len,
        max_bytes,
        &mut warned.2,
    );
    if kept_triangles < len {
        buffers.triangles.truncate(kept_triangles);
        buffers.counts.triangles = kept_triangles as u32;
    }
    buffers.words = words as u32 * 2;
    buffers.brick_words = bricks as u32;
    // Bindings need a buffer even when there is nothing to bind; nothing reads these entries.
    if buffers.triangles.is_empty() {
        buffers.triangles.push(GridTriangle::zeroed());
    }
    if buffers.volumes.is_empty() {
        buffers.volumes.push(GpuVolume::zeroed());
    }
    buffers.triangles.write_buffer(&device, &queue);
    buffers.volumes.write_buffer(&device, &queue);
    buffers.params.set(buffers.counts);
    buffers.params.write_buffer(&device, &queue);
    let needed = u64::from((buffers.words + buffers.brick_words).max(1)) * 4;
    if buffers.grid.as_ref().is_none_or(|g| g.size() < needed) {
        buffers.grid = Some(device.create_buffer(&BufferDescriptor {
            label: Some("dynamic_ao_voxel_grid"),
            size: needed,
            usage: BufferUsages::STORAGE | BufferUsages::COPY_DST | BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }));
    }
    buffers.needs_voxelizing = buffers.counts.volumes > 0;
    memory.report(
        "voxels",
        [
            buffers.triangles.buffer(),
            buffers.volumes.buffer(),
            buffers.grid.as_ref(),
        ]
        .into_iter()
        .flatten()
        .map(|b| b.size())
        .sum(),
    );

    buffers.readback = None;
    if let Some(request) = &buffers.readback_request
        && let Some(target) = storage_buffers.get(request)
    {
        let bytes = u64::from(buffers.words) * 4;
        if target.buffer.size() >= bytes {
            buffers.readback = Some((target.buffer.clone(), bytes));
        } else if !warned.1 {
            warned.1 = true;
            warn!(
                "VoxelGridReadback: the buffer has {} bytes but the grids need {bytes}; nothing \
                 is copied",
                target.buffer.size()
            );
        }
    }
}

/// How many of `volumes`, in order, fit in one storage binding of `max_bytes` (each grid takes
/// its words twice, surface bits and interior bits, and its bricks' bits), the words per layer
/// they take and the words of their bricks. Volumes that do not fit are dropped, last first.
fn volumes_that_fit(volumes: &[GpuVolume], max_bytes: u64) -> (usize, u64, u64) {
    let limit = max_bytes / 4;
    let (mut words, mut bricks) = (0u64, 0u64);
    let mut kept = 0;
    for volume in volumes {
        let end = u64::from(volume.offset) + u64::from(grid_words(volume.resolution));
        let bricks_end = u64::from(volume.brick_offset) + u64::from(brick_words(volume.resolution));
        if 2 * end + bricks_end > limit {
            break;
        }
        (words, bricks) = (end, bricks_end);
        kept += 1;
    }
    (kept, words, bricks)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volumes_past_the_binding_limit_are_dropped_last_first() {
        // 512³ cells are 4 Mi words, 16 MiB per layer, and their 64³ bricks 8 Ki words
        // (32 KiB): four volumes need 128 MiB and 128 KiB.
        let words = grid_words(512);
        let bricks = brick_words(512);
        assert_eq!((words, bricks), (4 << 20, 8 << 10));
        let volumes: Vec<GpuVolume> = (0..5)
            .map(|i| GpuVolume {
                offset: i * words,
                brick_offset: i * bricks,
                resolution: 512,
                ..Default::default()
            })
            .collect();
        let fit = |n: u64| (n as usize, n * u64::from(words), n * u64::from(bricks));
        assert_eq!(
            volumes_that_fit(&volumes, (128 << 20) + (128 << 10)),
            fit(4)
        );
        // Without room for the fourth volume's bricks, it is dropped.
        assert_eq!(volumes_that_fit(&volumes, 128 << 20), fit(3));
        assert_eq!(volumes_that_fit(&volumes, 1 << 30), fit(5));
        assert_eq!(volumes_that_fit(&volumes, 32 << 20), fit(0));
    }
}

//! What the main world hands the voxel passes each frame: every volume and every triangle in its
//! volume's grid space, laid out as `voxel_grid.wgsl` reads them.

use bevy::ecs::prelude::*;
use bevy::math::Affine3A;
use bytemuck::{Pod, Zeroable};

use super::component::{VoxelAoVolume, VoxelFalloff, VoxelMarch, VoxelRays};

/// One triangle in the grid space of one volume; `a[3]` holds the volume's index (as bits).
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GridTriangle {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
}

/// One volume as the shaders read it (`VoxelVolume` in `voxel_grid.wgsl`).
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuVolume {
    /// Rows of the world → grid affine map.
    pub grid_from_world: [[f32; 4]; 3],
    /// First word of the grid in the grid buffer.
    pub offset: u32,
    /// Cells per axis; 0 marks an unused slot.
    pub resolution: u32,
    pub rays: u32,
    /// Evenly spaced tests per ray; 0: every cell the ray crosses.
    pub steps: u32,
    /// cos of the cone half-angle the rays fill.
    pub cos_spread: f32,
    /// Metres; 0: the camera's radius.
    pub d_max: f32,
    /// How far rays start off the surface, metres: one voxel diagonal, so a ray never tests
    /// the voxels its own surface occupies.
    pub bias: f32,
    /// Size of the world-space cells the ray jitter is constant over, metres.
    pub noise_cell: f32,
    /// World-space size of one cell along each grid axis, metres.
    pub cell: [f32; 3],
    /// Bit 0: the occupied voxels are drawn (`ShowOccupiedVoxels`); bit 1: hits count without
    /// falloff (`VoxelFalloff::None`).
    pub flags: u32,
    /// The volume's `RenderLayers` as bits (see `view::layer_bits`): views on none of them do
    /// not sample it.
    pub layers: [u32; 2],
    /// Rays per pixel on views that accumulate the voxel term; at most `rays`.
    pub accumulated_rays: u32,
    /// First word of this volume's coarse occupancy bits, counted from the first of every
    /// volume's (`VoxelParams::brick_offset`).
    pub brick_offset: u32,
}

impl GpuVolume {
    /// The shader-side description of `volume` (already sanitized) placed by `world_from_volume`,
    /// its grid at word `offset` and its bricks at `brick_offset`, with its grid → world map, or
    /// `None` when that transform leaves no volume.
    pub(crate) fn new(
        volume: &VoxelAoVolume,
        world_from_volume: Affine3A,
        (offset, brick_offset): (u32, u32),
        show: bool,
    ) -> Option<(Self, Affine3A, VoxelRays)> {
        let n = volume.resolution as f32;
        // Grid cell (x, y, z) spans [x, x + 1]³; the box spans [−h, h] in the entity's space.
        let volume_from_grid = Affine3A::from_scale_rotation_translation(
            volume.half_extents * 2.0 / n,
            bevy::math::Quat::IDENTITY,
            -volume.half_extents,
        );
        let world_from_grid = world_from_volume * volume_from_grid;
        let det = world_from_grid.matrix3.determinant();
        if !world_from_grid.is_finite() || !det.is_finite() || det.abs() < 1e-12 {
            return None;
        }
        let grid_from_world = world_from_grid.inverse();
        let rays = VoxelRays::new(volume, grid_from_world);
        Some((
            Self {
                grid_from_world: Affine3ARows::from(grid_from_world).0,
                offset,
                resolution: volume.resolution,
                rays: rays.rays,
                steps: match rays.march {
                    VoxelMarch::Cells => 0,
                    VoxelMarch::Steps(steps) => steps,
                },
                cos_spread: rays.cos_spread,
                d_max: rays.d_max.unwrap_or(0.0),
                bias: rays.bias,
                noise_cell: rays.noise_cell,
                cell: rays.cell.to_array(),
                flags: u32::from(show) | (u32::from(rays.falloff == VoxelFalloff::None) << 1),
                layers: [1, 0],
                accumulated_rays: rays.accumulated_rays,
                brick_offset,
            },
            grid_from_world,
            rays,
        ))
    }
}

/// An affine map as three rows `[m0, m1, m2, t]`, the layout the shaders multiply with.
struct Affine3ARows([[f32; 4]; 3]);

impl From<Affine3A> for Affine3ARows {
    fn from(a: Affine3A) -> Self {
        let m = bevy::math::Mat3::from(a.matrix3).transpose();
        let t = a.translation;
        Self([
            [m.x_axis.x, m.x_axis.y, m.x_axis.z, t.x],
            [m.y_axis.x, m.y_axis.y, m.y_axis.z, t.y],
            [m.z_axis.x, m.z_axis.y, m.z_axis.z, t.z],
        ])
    }
}

/// What the render world receives each frame.
#[derive(Resource, Default)]
pub(crate) struct VoxelFrame {
    pub volumes: Vec<GpuVolume>,
    pub triangles: Vec<GridTriangle>,
}

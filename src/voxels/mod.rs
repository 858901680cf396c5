//! Voxel volumes: hybrid ambient occlusion from geometry rasterized into bit grids every frame
//! (Reinbothe, Boubekeur & Alexa 2009, "Hybrid Ambient Occlusion").
//!
//! A [`VoxelAoVolume`] marks a region of interest that follows its entity. Each frame:
//!
//! 1. **Gather** (main world, [`PostUpdate`] after transform propagation): every visible mesh
//!    reaching into a volume is deformed (skin, morph targets) on the CPU and its triangles are
//!    moved into the volume's grid space.
//! 2. **Voxelize** (GPU, once per frame, §5): the grids are cleared, then every triangle sets the
//!    bit of every cell it touches. The paper rasterizes from one orthographic camera, which
//!    drops triangles seen edge-on, and turns that camera by a random angle to make the loss
//!    rare. Here a compute pass tests each triangle against each cell its plane crosses with the
//!    separating-axis test, which is exact and conservative: no triangle is lost whatever its
//!    orientation, and the CPU twin ([`reference::voxels`](crate::reference::voxels)) agrees
//!    cell for cell. Bit grids as in the paper, one bit per cell.
//!
//!    Departure: the interior of closed meshes is filled too (parity along the grid's z axis,
//!    with shared edges counted once by the top-left rule: each closed triangle flips one cell
//!    per column it covers, and a second dispatch carries the flips up the columns, so the cost
//!    grows with columns, not cells). A surface-only grid is a shell one or
//!    two cells thick, and the paper's few evenly spaced steps per ray jump over it into the
//!    hollow inside: on our test scenes that found only half the occlusion ground truth does
//!    (0.108 against 0.213 next to an off-screen box), with the fill 0.208. Meshes whose edges
//!    are not all shared by exactly two triangles (planes, open shells) stay surface-only, and
//!    where two closed meshes overlap, their common part reads as empty.
//!
//!    A third dispatch builds a coarse occupancy level: one bit per brick of 8³ cells, set where
//!    any of its cells is occupied. Not in the paper, and it changes no hit (see step 3).
//! 3. **Sample** (GPU, per view, §6): each pixel of a half-resolution AO map traces rays through
//!    the grids; jitter comes from a hash of the pixel's world position, so it does not crawl
//!    when the camera moves. Under [`AoTemporal`](crate::AoTemporal) the jitter also turns every
//!    frame and the map is accumulated over frames like the image-space occlusion (see
//!    [`temporal`](crate::temporal)): with 4 rays per pixel, the RMSE against 64 rays on the CPU
//!    falls from 0.068 in one frame to 0.011. So a camera that accumulates traces
//!    [`accumulated_rays`](VoxelAoVolume::accumulated_rays) a frame (8 by default, a quarter of
//!    `rays`): the pass costs a quarter, and the converged error is the same. Its blur keeps its
//!    full radius then: what is left of its error is mostly the grid's steps, which frames do not average away. Rays start one cell diagonal off the surface, so they never test
//!    the cells the surface itself occupies. Eq. 4 is normalized by the sum of the rays' cosines
//!    (as printed, a fully enclosed surface would read ½). Departures, to measure what ground
//!    truth measures:
//!
//!    - rays reach as far as the camera's [`radius`](crate::DynamicAo::radius) R (the paper's
//!      d_max is an option of the volume);
//!    - every hit within reach counts fully ([`VoxelFalloff::None`]); Wendland's kernel (eq. 3)
//!      weights a hit at half the reach by 0.19 and found 0.022 of the 0.126 a ray tracer finds
//!      next to a box just off-screen;
//!    - a ray walks every cell it crosses ([`VoxelMarch::Cells`]): the paper's 8 evenly spaced
//!      tests step over a floor one cell thick. Where its reach spans at least four bricks it
//!      crosses a brick with no occupied cell in one step, so the cells it visits are those of
//!      the walk without bricks less empty ones, and the hits are the same (the CPU twin walks
//!      every cell): most of a ray's reach is air, and on lavapipe the pass takes 0.4–0.6× the
//!      time at R = 0.75 m on a model on a floor at 256³, and 0.2–0.3× at 2 m;
//!    - a ray is blocked once it has travelled [`VoxelAoVolume::HIT_DEPTH`] (0.9) cells through
//!      occupied cells in a row, not at the first occupied cell it enters: conservative
//!      voxelization grows every occluder by up to a cell, and a ray that only grazes that rim
//!      would not meet the mesh, while a ray across a plane one cell thick still travels a
//!      whole cell through it;
//!    - counted once: under [`FarFieldBlend::CountOnce`](crate::FarFieldBlend::CountOnce) a hit
//!      within the near field's reach goes to one channel unless the ND-buffer holds it (the near
//!      field counts those), the rest to a second channel as a share of the rays the first
//!      leaves open.
//! 4. **Filter** (§7): the joint bilateral upsampling of [`filter`](crate::filter) (eq. 5–7,
//!    a 3 × 3 window of the half-resolution map, both channels) brings the map to full resolution, then the
//!    near field's cross-bilateral blur smooths the remaining noise. That blur is separable like
//!    eq. 8, but weights taps by a Gaussian of pixel distance and by depth difference rather
//!    than by eq. 7's Wendland kernels over normals, positions and AO values.
//! 5. **Compose**: the result joins the far field next to sphere and field occluders, and the
//!    far field combines with the near field as [`FarFieldBlend`](crate::FarFieldBlend) says.
//!
//! A volume's cells bound what it can resolve: conservative voxelization grows every occluder by
//! up to a cell, which the hit depth takes back only in part, and a character's thin limbs come
//! out fat in cells a few centimetres wide. Size a volume to what occludes the surfaces the
//! camera sees, not to everything it sees: an open floor far from anything occludes nothing and
//! needs no cells. `ao_capture` covers the bounds of what rays from the visible surfaces hit
//! within R; for characters standing on a 20 m floor that gave cells several times finer than
//! covering the visible floor grown by R did, and the voxel term alone went from 0.049 to 0.029
//! RMSE (the walker, R = 2 m; 0.041 with the hit depth alone), the box just off-screen from 0.183
//! to 0.167 against 0.169 (`cargo bench --bench far_field`).
//!
//! [`ShowOccupiedVoxels`] on a volume draws its occupied cells over the image.

mod buffers;
mod component;
mod grid_data;
mod mesh_cache;
mod node;
mod pipeline;
mod show;
mod systems;
mod view;

use bevy::app::{App, Plugin, PostUpdate};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::render::render_resource::SpecializedRenderPipelines;
use bevy::render::{ExtractSchedule, GpuResourceAppExt, Render, RenderSystems};
use bevy::shader::load_shader_library;

pub use component::{
    NotVoxelOccluder, ShowOccupiedVoxels, VoxelAoVolume, VoxelFalloff, VoxelGridInfo,
    VoxelGridReadback, VoxelMarch, VoxelRays, VoxelVolumeError,
};

pub(crate) use pipeline::VoxelPipelines;

use crate::capabilities;
use crate::schedule::{
    self, DynamicAoExtract, DynamicAoPrepare, DynamicAoSystems, DynamicAoUpdate,
};
use crate::view::drop_without_ao;

/// Voxel volumes: per-frame gathering, voxelization, sampling and the occupied-voxel view.
pub struct VoxelAoPlugin;

impl Plugin for VoxelAoPlugin {
    fn build(&self, app: &mut App) {
        schedule::configure_update(app);
        load_shader_library!(app, "voxel_grid.wgsl");
        embedded_asset!(app, "voxelize.wgsl");
        embedded_asset!(app, "voxel_ao.wgsl");
        embedded_asset!(app, "show_voxels.wgsl");
        app.register_type::<VoxelAoVolume>()
            .register_type::<VoxelFalloff>()
            .register_type::<VoxelMarch>()
            .register_type::<ShowOccupiedVoxels>()
            .register_type::<NotVoxelOccluder>()
            .init_resource::<grid_data::VoxelFrame>()
            .init_resource::<mesh_cache::VoxelMeshCache>()
            .add_systems(
                PostUpdate,
                (
                    mesh_cache::forget_changed_meshes.in_set(DynamicAoUpdate::ForgetChangedMeshes),
                    (systems::forget_removed_volumes, systems::gather_triangles)
                        .in_set(DynamicAoUpdate::Occluders),
                    systems::require_motion_vectors,
                ),
            );
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_resource::<buffers::VoxelBuffers>()
            .init_resource::<SpecializedRenderPipelines<show::ShowVoxelsPipeline>>()
            .add_systems(
                ExtractSchedule,
                (
                    buffers::extract_voxels,
                    view::note_voxel_volumes.in_set(DynamicAoExtract::Occluders),
                ),
            )
            .add_systems(
                Render,
                (
                    (buffers::write_voxel_buffers, view::prepare_voxel_textures)
                        .in_set(RenderSystems::PrepareResources),
                    node::wait_for_voxels.in_set(DynamicAoPrepare::Readiness),
                    pipeline::prepare_voxel_bind_groups.in_set(DynamicAoPrepare::BindGroups),
                    drop_without_ao::<(
                        view::VoxelTextures,
                        view::VoxelHistory,
                        pipeline::VoxelBindGroups,
                        show::ShowVoxels,
                    )>
                        .in_set(DynamicAoPrepare::BindGroups),
                    show::prepare_show_voxels.in_set(DynamicAoPrepare::OverlayBindGroups),
                ),
            )
            .add_systems(
                Core3d,
                (
                    node::voxel_pass.in_set(DynamicAoSystems::FarField),
                    show::show_voxels_pass.in_set(DynamicAoSystems::DebugOverlay),
                ),
            );
        render_app
            .init_gpu_resource::<VoxelPipelines>()
            .init_gpu_resource::<show::ShowVoxelsPipeline>();
    }
}

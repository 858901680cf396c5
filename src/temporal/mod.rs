//! Temporal accumulation of the image-space occlusion (near field, horizon-based, ray march) and of
//! the voxel term.
//!
//! Each frame the image-space technique moves its sample pattern along a low-discrepancy sequence
//! (`frame_offset` in `shaders/sampling.wgsl`: a frame's rotation and ring or step offsets) and
//! writes its result into a raw buffer. The temporal pass (`temporal.wgsl`) joins it with the
//! pixel's history:
//!
//! - **Reprojection.** The history is read where the surface was last frame: this pixel's UV
//!   minus Bevy's motion vector, which follows camera motion and moving, skinned and morphed
//!   meshes alike.
//! - **Disocclusion.** Of the four history texels around that place, only those whose linear
//!   depth (within 5 %) and normal (cosine ≥ 0.9) match this surface count, weighted bilinearly;
//!   where none does, the history starts again from this frame.
//! - **Ghosting.** The history is clamped around the mean of this frame's values on the pixel's
//!   plane in the 5 × 5 texels around it (each texel's reverse-Z depth, which is affine across
//!   the screen on a plane, off the plane by no more than 2 % of the pixel's linear depth would
//!   move it; the plane's slope from the nearer neighbour along each axis): within
//!   1.5 standard errors of that mean plus 0.05, the band reaching as far as the mean of the
//!   window's texel pairs symmetric about the pixel where the plane ends inside the window (so a
//!   converged edge keeps its own occlusion, not the plane's inside's). An occluder that moves
//!   away without a motion vector on the receiver (a contact shadow on a still floor) leaves no
//!   trail; a history the clamp moved by more than 0.03 counts as at most four frames, so the
//!   change settles quickly. The image-space clamp runs on every other frame: it is there for
//!   changes the motion vectors miss, which it catches a frame later, not for noise, which the
//!   average removes; the frames between run a pipeline compiled without its workgroup tile and
//!   window (BENCHMARKS.md, "The clamp every other frame" and "A temporal pipeline without the
//!   clamp"). The voxel term keeps the range of its 3 × 3 neighbours widened by
//!   0.05 (the mean biased it at the voxel grid's steps), every frame.
//! - **Average.** Running mean over at most [`AoTemporal::max_frames`] frames: the history keeps
//!   its frame count, and each frame weighs 1 / count.
//! - **Checkerboard.** The ray march by default marches one texel of two each frame
//!   ([`crate::RayMarchParams::checkerboard`]), alternating, for about half its cost. A texel it
//!   skipped keeps its reprojected (and, on clamp frames, clamped) history with its count
//!   unchanged: the count is of samples, so a history of `max_frames` samples spans twice as many
//!   frames. Where a skipped texel has no history (a disocclusion), it takes the mean of its
//!   four neighbours on its surface, all marched this frame, counted as half a sample (read from
//!   the clamp's tile on the frames that fill one). The
//!   clamp's window reads the skipped texels' values of last frame, which the march left in
//!   place: at the default budget this kept the converged error of marching every texel, where
//!   a window of the marched texels alone raised it by 2–16% (BENCHMARKS.md, "Half the texels
//!   a frame").
//! - **Reset.** The history is dropped on resize (its textures are made again), when any other
//!   setting of the camera changes, when [`AoTemporal::reset`] is set (camera cuts), and where
//!   the camera has no motion vectors yet, and on every frame before all of the view's passes run
//!   (while shaders load or reload, Bevy's SSAO stands in and no image shows the history).
//!
//! The history lives in two textures per view (read one, write the other, swapped every frame),
//! kept across frames on the render-world view and made again only when the view's size changes.
//! The upsampling reads the history written this frame, whose texels carry the depth and normal
//! it needs ([`crate::filter`]). The blur that follows runs at half its radius.
//!
//! The voxel term ([`crate::voxels`]) accumulates the same way, in a history of its own: its rays
//! turn every frame by the same sequence, and the pass (`PAIR` in `temporal.wgsl`) runs on its
//! half-resolution map of two channels before the upsampling.

mod node;
mod pipeline;
mod sequence;
pub mod settings;
mod view;

pub(crate) use pipeline::{AccumulationTextures, Channels, TemporalPipeline};
pub(crate) use sequence::started_over;
pub(crate) use view::{HistoryFrame, TemporalHistory};

use bevy::app::{App, Plugin, PostUpdate};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::prepass::MotionVectorPrepass;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::render::{ExtractSchedule, GpuResourceAppExt, MainWorld, Render, RenderSystems};

use crate::capabilities;
use crate::schedule::{DynamicAoExtract, DynamicAoPrepare, DynamicAoSystems};
use crate::settings::DynamicAo;
use crate::view::drop_without_ao;
pub use settings::AoTemporal;

/// Accumulates the image-space occlusion of cameras whose [`AoTemporal`] is on.
pub struct TemporalPlugin;

impl Plugin for TemporalPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "temporal.wgsl");
        app.register_type::<AoTemporal>()
            .add_systems(PostUpdate, require_motion_vectors);
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::TemporalPipeline>()
            .add_systems(
                Render,
                (
                    view::prepare_history.in_set(RenderSystems::PrepareResources),
                    // Before the uniform goes to the GPU (in `PrepareResources`).
                    sequence::advance_sequences.in_set(RenderSystems::PrepareViews),
                    node::wait_for_temporal.in_set(DynamicAoPrepare::Readiness),
                    pipeline::prepare_temporal_bind_groups.in_set(DynamicAoPrepare::BindGroups),
                    drop_without_ao::<(TemporalHistory, pipeline::TemporalBindGroup)>
                        .in_set(DynamicAoPrepare::BindGroups),
                ),
            )
            .add_systems(
                ExtractSchedule,
                clear_reset.in_set(DynamicAoExtract::Consumed),
            )
            .add_systems(
                Core3d,
                node::temporal_pass.in_set(DynamicAoSystems::Temporal),
            );
    }
}

/// Cameras that accumulate need Bevy's motion vectors.
fn require_motion_vectors(
    mut commands: Commands,
    cameras: Query<(Entity, &DynamicAo), Without<MotionVectorPrepass>>,
) {
    for (entity, ao) in &cameras {
        // Our image-space techniques accumulate (and the voxel term, whose plugin asks for motion
        // vectors itself): Bevy's SSAO, spheres and fields need none.
        if ao.temporal.enabled && ao.technique.is_image_space() {
            commands.entity(entity).insert(MotionVectorPrepass);
        }
    }
}

/// A reset lasts one frame: cleared in the main world once this frame's views have read it.
fn clear_reset(
    mut main_world: ResMut<MainWorld>,
    mut cameras: Local<Option<QueryState<&'static mut DynamicAo>>>,
) {
    // Kept from frame to frame: the main world moves in and out of `MainWorld` but stays the
    // same world.
    let cameras = cameras.get_or_insert_with(|| main_world.query());
    for mut ao in cameras.iter_mut(&mut main_world) {
        if ao.temporal.reset {
            ao.bypass_change_detection().temporal.reset = false;
        }
    }
}

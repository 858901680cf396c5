//! What each camera's image showed: the plugin's AO, Bevy's SSAO standing in, or nothing yet,
//! and for how many frames. The render world decides it once the view's passes are handed over;
//! extraction copies it onto the main-world camera as [`DynamicAoStatus`].

use bevy::ecs::entity::EntityHashMap;
use bevy::ecs::prelude::*;
use bevy::pbr::SsaoPipelineId;
use bevy::reflect::Reflect;
use bevy::render::{MainWorld, render_resource::PipelineCache, sync_world::MainEntity};

use super::{FailedPipelines, bevy_ssao_runs};
use crate::settings::{AoTechnique, DynamicAo};
use crate::view::{AoPassesReady, DynamicAoUniform, DynamicAoView};

/// What a camera's ambient occlusion texture held on a rendered frame.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AoShown {
    /// Nothing the camera asked for: its passes are still compiling (their shaders wait on the
    /// asset loader, or are reloading), or, before its first frame shown, the pipelines that
    /// draw its meshes into the back-face layer are; Bevy's SSAO, or open visibility, stands in.
    /// Also a camera that did not render (inactive, or no longer carrying [`DynamicAo`]).
    #[default]
    Pending,
    /// What the camera's [`DynamicAo`] asks for: the plugin's technique and far-field terms, or
    /// Bevy's own SSAO where the technique is [`AoTechnique::BevySsao`].
    Shown,
    /// One of the plugin's pipelines failed for good (an error named it) and Bevy's SSAO stands
    /// in for the camera's technique.
    Fallback,
}

/// Whether, and for how many frames, a camera's image has shown its ambient occlusion.
///
/// The plugin inserts it on every camera with [`DynamicAo`] at the first extraction after the
/// component arrives, and updates it at each extraction with the frame the renderer finished
/// last: in an `Update` system it describes the frame begun two app updates before, with Bevy's
/// pipelined rendering on or off (extraction runs after `Update`). Watch it to hide a loading screen until the AO is in the image, or to take a
/// screenshot once the accumulation has converged; the examples' headless `--frames N` and
/// `ao_capture` count their frames from its first [`AoShown::Shown`].
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Component)]
pub struct DynamicAoStatus {
    /// What the camera's AO texture held.
    pub shown: AoShown,
    /// Frames in a row it held that, 0 while [`AoShown::Pending`]. On a camera whose plugin AO
    /// accumulates over frames ([`crate::AoTemporal`]) and is shown: the frames since its
    /// accumulation last started over (the first frame shown, [`crate::AoTemporal::reset`], a
    /// change of settings or size), the frames its history may hold.
    pub frames: u32,
}

/// What each view showed on the frame the render world is on, by main-world camera; the next
/// extraction copies it to the cameras.
#[derive(Resource, Default)]
pub(crate) struct RenderedStatuses(EntityHashMap<DynamicAoStatus>);

/// What a view's AO texture holds this frame: its own passes once all of them are ready (they
/// write from the frame they become ready), Bevy's SSAO where that is its technique or where one
/// of ours failed for good, otherwise nothing it asked for.
/// `replaces_bevy_ssao`: the view runs a technique of ours ([`DynamicAoView::replaces_bevy_ssao`]);
/// `failed`: one of our pipelines failed for good ([`FailedPipelines::any`]).
pub(crate) fn shown(
    replaces_bevy_ssao: bool,
    ours_ready: bool,
    bevy_ssao_ran: bool,
    failed: bool,
) -> AoShown {
    match (replaces_bevy_ssao, ours_ready, bevy_ssao_ran) {
        (true, true, _) | (false, _, true) => AoShown::Shown,
        (true, false, true) if failed => AoShown::Fallback,
        _ => AoShown::Pending,
    }
}

/// Records each view's status once its passes are handed over (after every system that moves
/// Bevy's SSAO pipeline id on or off the view).
pub(crate) fn record_statuses(
    mut rendered: ResMut<RenderedStatuses>,
    views: Query<(
        &MainEntity,
        &DynamicAoView,
        Has<AoPassesReady>,
        Option<&SsaoPipelineId>,
        Option<&DynamicAoUniform>,
    )>,
    pipeline_cache: Res<PipelineCache>,
    failed: Res<FailedPipelines>,
) {
    let last = std::mem::take(&mut rendered.0);
    for (camera, view, ours_ready, bevy_ssao, uniform) in &views {
        let bevy_ssao_ran = bevy_ssao_runs(bevy_ssao, &pipeline_cache);
        let shown = shown(
            view.replaces_bevy_ssao(),
            ours_ready,
            bevy_ssao_ran,
            failed.any(),
        );
        // The accumulating view's sequence (`temporal/sequence.rs`) starts over where its
        // history does, which a count of frames in a row would not see.
        let accumulated = uniform
            .map(|u| u.frame_index)
            .filter(|&frames| frames > 0 && view.technique() != AoTechnique::BevySsao);
        let frames = match (shown, accumulated) {
            (AoShown::Pending, _) => 0,
            (AoShown::Shown, Some(frames)) => frames,
            _ => match last.get(&camera.id()) {
                Some(status) if status.shown == shown => status.frames.saturating_add(1),
                _ => 1,
            },
        };
        rendered
            .0
            .insert(camera.id(), DynamicAoStatus { shown, frames });
    }
}

/// The main-world cameras [`publish_statuses`] writes to.
type StatusCameras = QueryState<
    (Entity, Option<&'static mut DynamicAoStatus>),
    Or<(With<DynamicAo>, With<DynamicAoStatus>)>,
>;

/// Copies the statuses of the frame last rendered onto the main-world cameras: inserted on a
/// camera with [`DynamicAo`] that has none yet, and [`AoShown::Pending`] on one that did not
/// render. Written only where it changed, so `Changed<DynamicAoStatus>` says when it did.
pub(crate) fn publish_statuses(
    mut main_world: ResMut<MainWorld>,
    rendered: Res<RenderedStatuses>,
    mut cameras: Local<Option<StatusCameras>>,
    mut missing: Local<Vec<(Entity, DynamicAoStatus)>>,
) {
    // Kept from frame to frame, as Bevy's `Extract` keeps its queries: the main world moves in
    // and out of `MainWorld` but stays the same world.
    let cameras = cameras.get_or_insert_with(|| main_world.query_filtered());
    for (camera, status) in cameras.iter_mut(&mut main_world) {
        let now = rendered.0.get(&camera).copied().unwrap_or_default();
        match status {
            Some(mut status) => {
                status.set_if_neq(now);
            }
            None => missing.push((camera, now)),
        }
    }
    for (camera, status) in missing.drain(..) {
        main_world.entity_mut(camera).insert(status);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_view_shows_its_own_passes_once_ready_and_bevy_ssao_only_where_asked_or_failed() {
        // A technique of ours: shown once its passes are ready, whatever Bevy's SSAO did.
        assert_eq!(shown(true, true, false, false), AoShown::Shown);
        assert_eq!(shown(true, true, true, true), AoShown::Shown);
        // Bevy's SSAO standing in while ours compile is not what the camera asked for...
        assert_eq!(shown(true, false, true, false), AoShown::Pending);
        assert_eq!(shown(true, false, false, true), AoShown::Pending);
        // ...but it is the fallback once one of ours failed for good.
        assert_eq!(shown(true, false, true, true), AoShown::Fallback);
        // A camera that asked for Bevy's SSAO: shown once Bevy's pass runs.
        assert_eq!(shown(false, false, true, false), AoShown::Shown);
        assert_eq!(shown(false, true, false, false), AoShown::Pending);
    }
}

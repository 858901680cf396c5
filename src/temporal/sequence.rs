//! Each view's place in the sample pattern's sequence: the frames since its history began.
//!
//! Counted per view, not from the app's frame count, so that a still camera converges to the
//! same image however many frames the app ran before the camera got its AO or its settings last
//! changed: two captures of one view that accumulate the same number of frames are equal, with
//! or without MSAA. Nor does it count the frames before all of the view's passes run (shaders
//! still loading or reloading): it starts on the first frame the view's AO is shown.
//!
//! The sequence alone decides where accumulation starts over; each history (image space, voxels)
//! starts over on the frames it does ([`started_over`]), so the two cannot disagree.

use bevy::ecs::prelude::*;
use bevy::math::UVec2;
use bevy::render::camera::ExtractedCamera;

use crate::settings::DynamicAo;
use crate::view::AoPassesReady;
use crate::view::{DynamicAoUniform, DynamicAoView};

/// Frames a view has accumulated since its history last started over.
#[derive(Component)]
pub(crate) struct TemporalSequence {
    frames: u32,
    settings: DynamicAo,
    size: Option<UVec2>,
}

/// Counts each accumulating view's frames, starting over where its history does (a reset, new
/// settings, a new size, a frame before all its passes have run), and gives the count to its
/// uniform.
pub(crate) fn advance_sequences(
    mut commands: Commands,
    mut views: Query<(
        Entity,
        &DynamicAoView,
        &ExtractedCamera,
        &mut DynamicAoUniform,
        Option<&mut TemporalSequence>,
        Has<AoPassesReady>,
    )>,
) {
    for (entity, view, camera, mut uniform, sequence, passes_ready) in &mut views {
        // Extraction leaves 0 where nothing accumulates; the sequence ends there, so that
        // accumulation switched on again starts one (its settings may equal the last ones).
        if uniform.frame_index == 0 {
            if sequence.is_some() {
                commands.entity(entity).remove::<TemporalSequence>();
            }
            continue;
        }
        let settings = history_key(&view.settings);
        let size = camera.physical_viewport_size;
        match sequence {
            Some(mut sequence)
                if passes_ready
                    && !view.settings.temporal.reset
                    && sequence.size == size
                    && sequence.settings == settings =>
            {
                // Past `u32::MAX` the count goes on from 2: 1 would start the history over.
                sequence.frames = sequence.frames.checked_add(1).unwrap_or(2);
                uniform.frame_index = sequence.frames;
            }
            _ => {
                uniform.frame_index = 1;
                commands.entity(entity).insert(TemporalSequence {
                    frames: 1,
                    settings,
                    size,
                });
            }
        }
    }
}

/// Whether the view's sequence started over this frame (its `frame_index` is 1, or the view has
/// no uniform): where it does, its histories start over too.
pub(crate) fn started_over(uniform: Option<&DynamicAoUniform>) -> bool {
    uniform.is_none_or(|uniform| uniform.frame_index <= 1)
}

/// The settings that do not start the sequence over when they change.
pub(super) fn history_key(settings: &DynamicAo) -> DynamicAo {
    let mut key = settings.clone();
    key.debug_view = false;
    key.temporal.reset = false;
    key
}

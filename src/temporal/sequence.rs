//! Each view's place in the sample pattern's sequence: the frames since its history began.
//!
//! Counted per view, not from the app's frame count, so that a still camera converges to the
//! same image however many frames the app ran before the camera got its AO or its settings last
//! changed: two captures of one view that accumulate the same number of frames are equal, with
//! or without MSAA. Nor does it count the frames before all of the view's passes run (shaders
//! still loading or reloading): the history is dropped on those, and the sequence starts with
//! it on the first frame the view's AO is shown.

use bevy::ecs::prelude::*;
use bevy::math::UVec2;
use bevy::render::camera::ExtractedCamera;

use super::view::history_key;
use crate::compose::AoPassesReady;
use crate::settings::DynamicAo;
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
        // Extraction leaves 0 where nothing accumulates.
        if uniform.frame_index == 0 {
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
                sequence.frames = sequence.frames.wrapping_add(1).max(1);
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

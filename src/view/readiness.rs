//! When a view's AO is ready to show: every pass it needs has compiled, and before its first
//! frame shown, every mesh it draws into the ND-buffer's own layers.

use bevy::ecs::prelude::*;
use bevy::render::render_resource::{CachedPipelineState, CachedRenderPipelineId, PipelineCache};
use bevy::shader::ShaderCacheError;

/// Marks a view whose passes have all compiled (and, before its first frame shown, the pipelines
/// that draw its meshes into our layers): from then on ours write the AO texture, not Bevy's
/// SSAO.
#[derive(Component)]
pub(crate) struct AoPassesReady;

/// Whether the pipeline cache retries a pipeline that failed with `error`: its shader, or one it
/// imports, has not loaded yet (at startup, or for a moment while a file reloads).
pub(crate) fn retried(error: &ShaderCacheError) -> bool {
    matches!(
        error,
        ShaderCacheError::ShaderNotLoaded(_) | ShaderCacheError::ShaderImportNotYetAvailable
    )
}

/// Whether the render pipeline `id` is still on its way: queued, compiling, or waiting for a
/// shader (see [`retried`]). One that failed for good is not.
pub(crate) fn still_compiling(cache: &PipelineCache, id: CachedRenderPipelineId) -> bool {
    match cache.get_render_pipeline_state(id) {
        CachedPipelineState::Queued | CachedPipelineState::Creating(_) => true,
        CachedPipelineState::Ok(_) => false,
        CachedPipelineState::Err(error) => retried(error),
    }
}

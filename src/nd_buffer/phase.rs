//! The phase item of the back-face layer.

use core::ops::Range;

use bevy::camera::{Camera, Camera3d};
use bevy::ecs::entity::EntityHash;
use bevy::ecs::prelude::*;
use bevy::math::FloatOrd;
use bevy::pbr::{
    DrawMesh, SetMeshBindGroup, SetMeshViewBindGroup, SetMeshViewBindingArrayBindGroup,
};
use bevy::platform::collections::HashSet;
use bevy::render::{
    Extract,
    render_phase::{
        CachedRenderPipelinePhaseItem, DrawFunctionId, PhaseItem, PhaseItemExtraIndex,
        SetItemPipeline, SortedPhaseItem, ViewSortedRenderPhases,
    },
    render_resource::CachedRenderPipelineId,
    sync_world::MainEntity,
    view::{ExtractedView, RetainedViewEntity},
};
use indexmap::IndexMap;

use crate::settings::DynamicAo;

/// One mesh drawn into the back-face layer of the ND-buffer.
pub struct BackFace3d {
    /// Distance from the camera, for a front-to-back draw order (metres).
    pub distance: f32,
    /// The mesh entity: render-world and main-world ids.
    pub entity: (Entity, MainEntity),
    /// The specialized back-face pipeline of this mesh.
    pub pipeline: CachedRenderPipelineId,
    /// The draw commands (Bevy's mesh draw).
    pub draw_function: DrawFunctionId,
    /// Instances drawn by this item, set by Bevy's batching.
    pub batch_range: Range<u32>,
    /// Dynamic offset or indirect-parameters index, set by Bevy's batching.
    pub extra_index: PhaseItemExtraIndex,
    /// Whether the mesh has an index buffer.
    pub indexed: bool,
}

impl PhaseItem for BackFace3d {
    fn entity(&self) -> Entity {
        self.entity.0
    }

    fn main_entity(&self) -> MainEntity {
        self.entity.1
    }

    fn draw_function(&self) -> DrawFunctionId {
        self.draw_function
    }

    fn batch_range(&self) -> &Range<u32> {
        &self.batch_range
    }

    fn batch_range_mut(&mut self) -> &mut Range<u32> {
        &mut self.batch_range
    }

    fn extra_index(&self) -> PhaseItemExtraIndex {
        self.extra_index.clone()
    }

    fn batch_range_and_extra_index_mut(&mut self) -> (&mut Range<u32>, &mut PhaseItemExtraIndex) {
        (&mut self.batch_range, &mut self.extra_index)
    }
}

impl SortedPhaseItem for BackFace3d {
    type SortKey = FloatOrd;

    fn sort_key(&self) -> Self::SortKey {
        FloatOrd(self.distance)
    }

    fn recalculate_sort_keys(
        _items: &mut IndexMap<(Entity, MainEntity), Self, EntityHash>,
        _view: &ExtractedView,
    ) {
        // The distance is set when the item is queued, every frame.
    }

    fn indexed(&self) -> bool {
        self.indexed
    }
}

impl CachedRenderPipelinePhaseItem for BackFace3d {
    fn cached_pipeline(&self) -> CachedRenderPipelineId {
        self.pipeline
    }
}

/// Bevy's own mesh draw commands: group 2 carries each mesh's skin and morph data.
pub(crate) type DrawBackFaces = (
    SetItemPipeline,
    SetMeshViewBindGroup<0>,
    SetMeshViewBindingArrayBindGroup<1>,
    SetMeshBindGroup<2>,
    DrawMesh,
);

pub(crate) fn extract_back_face_phases(
    mut phases: ResMut<ViewSortedRenderPhases<BackFace3d>>,
    cameras: Extract<Query<(Entity, &Camera), (With<Camera3d>, With<DynamicAo>)>>,
    mut live: Local<HashSet<RetainedViewEntity>>,
) {
    live.clear();
    for (main_entity, camera) in &cameras {
        if !camera.is_active {
            continue;
        }
        // A camera's main view is its first subview.
        let view = RetainedViewEntity::new(main_entity.into(), None, 0);
        phases.prepare_for_new_frame(view);
        live.insert(view);
    }
    phases.retain(|view, _| live.contains(view));
}

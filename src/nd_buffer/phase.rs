//! The phase items of the layers this crate draws with Bevy's mesh pipeline: the back-face layer,
//! and on MSAA cameras the front layer's depth at pixel centres.

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
    render_resource::{CachedRenderPipelineId, PipelineCache},
    sync_world::MainEntity,
    view::{ExtractedView, RetainedViewEntity},
};
use indexmap::IndexMap;

use crate::settings::DynamicAo;
use crate::view::{AoPassesReady, PendingPasses, still_compiling};

/// One mesh drawn into a layer of the ND-buffer drawn by this crate: the back faces when `BACK`
/// ([`BackFace3d`]), else the front faces' depth at pixel centres ([`CentreSample3d`]).
pub struct NdLayer3d<const BACK: bool> {
    /// Distance from the camera, for a front-to-back draw order (metres).
    pub distance: f32,
    /// The mesh entity: render-world and main-world ids.
    pub entity: (Entity, MainEntity),
    /// The specialized pipeline of this mesh for this layer.
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

impl<const BACK: bool> NdLayer3d<BACK> {
    /// A mesh's item, before Bevy's batching.
    pub fn new(
        entity: (Entity, MainEntity),
        pipeline: CachedRenderPipelineId,
        draw_function: DrawFunctionId,
        indexed: bool,
    ) -> Self {
        Self {
            // Render-world mesh instances carry no world-space centre to sort by; the layers
            // are depth-tested, so order only affects overdraw.
            distance: 0.0,
            entity,
            pipeline,
            draw_function,
            batch_range: 0..1,
            extra_index: PhaseItemExtraIndex::None,
            indexed,
        }
    }
}

/// One mesh drawn into the back-face layer of the ND-buffer.
pub type BackFace3d = NdLayer3d<true>;

/// One mesh drawn into the single-sampled depth of an MSAA camera's front layer (see
/// `front_layer.rs`: it tells which surface a pixel's centre shows).
pub type CentreSample3d = NdLayer3d<false>;

impl<const BACK: bool> PhaseItem for NdLayer3d<BACK> {
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

impl<const BACK: bool> SortedPhaseItem for NdLayer3d<BACK> {
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

impl<const BACK: bool> CachedRenderPipelinePhaseItem for NdLayer3d<BACK> {
    fn cached_pipeline(&self) -> CachedRenderPipelineId {
        self.pipeline
    }
}

/// Bevy's own mesh draw commands: group 2 carries each mesh's skin and morph data.
pub(crate) type DrawLayerMeshes = (
    SetItemPipeline,
    SetMeshViewBindGroup<0>,
    SetMeshViewBindingArrayBindGroup<1>,
    SetMeshBindGroup<2>,
    DrawMesh,
);

/// Gives every active AO camera an empty phase of the layer each frame (meshes are queued into it
/// where the camera needs the layer) and drops those of cameras gone.
pub(crate) fn extract_layer_phases<const BACK: bool>(
    mut phases: ResMut<ViewSortedRenderPhases<NdLayer3d<BACK>>>,
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

/// Until a view first shows its AO, it also waits for the pipelines that draw its meshes into
/// the back-face layer and the centre sample: each mesh's own, compiled in the background like
/// the passes', and until then missing from the layer. Without this the first frame shown could
/// read a back layer that still lacked meshes the front layer held (in one CI run the ray march
/// read 0.25 off). Once shown, a mesh whose pipeline compiles later (one spawned with a new
/// vertex layout) is drawn from the frame it is ready, as Bevy draws it, rather than sending the
/// camera back to Bevy's SSAO meanwhile. A pipeline that failed for good is not waited for: an
/// error names it, and the layer goes without that mesh.
pub(crate) fn wait_for_layer_draws(
    pipeline_cache: Res<PipelineCache>,
    back: Res<ViewSortedRenderPhases<BackFace3d>>,
    centre: Res<ViewSortedRenderPhases<CentreSample3d>>,
    mut views: Query<(&ExtractedView, &mut PendingPasses), Without<AoPassesReady>>,
) {
    for (view, mut pending) in &mut views {
        let key = view.retained_view_entity;
        let back = back.get(&key).into_iter().flat_map(|p| p.items.values());
        let centre = centre.get(&key).into_iter().flat_map(|p| p.items.values());
        let mut pipelines = back
            .map(|item| item.pipeline)
            .chain(centre.map(|item| item.pipeline));
        pending.wait_for(!pipelines.any(|id| still_compiling(&pipeline_cache, id)));
    }
}

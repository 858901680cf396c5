//! The passes that draw the layers of Bevy's mesh pipeline: the back-face layer, and (called by
//! the front-layer copy) the centre sample of MSAA cameras.

use bevy::camera::Viewport;
use bevy::ecs::prelude::*;
use bevy::log::error;
use bevy::render::{
    camera::ExtractedCamera,
    diagnostic::RecordDiagnostics,
    render_phase::{SortedRenderPhase, TrackedRenderPass, ViewSortedRenderPhases},
    render_resource::{
        LoadOp, Operations, RenderPassColorAttachment, RenderPassDepthStencilAttachment,
        RenderPassDescriptor, StoreOp, TextureView,
    },
    renderer::{RenderContext, ViewQuery},
    view::{ExtractedView, ViewUniformOffset},
};

use super::coarse::CoarseBackFaces;
use super::phase::{BackFace3d, NdLayer3d};
use crate::settings::AoTechnique;
use crate::view::{DynamicAoTextures, DynamicAoView};

pub(crate) fn back_face_pass(
    world: &World,
    view: ViewQuery<(
        &ExtractedCamera,
        &ExtractedView,
        &DynamicAoTextures,
        &DynamicAoView,
        &ViewUniformOffset,
    )>,
    phases: Res<ViewSortedRenderPhases<BackFace3d>>,
    coarse: CoarseBackFaces,
    mut ctx: RenderContext,
) {
    let view_entity = view.entity();
    let (camera, extracted_view, textures, ao_view, view_offset) = view.into_inner();
    // Under Bevy's own SSAO none of our passes reads the layer.
    if ao_view.technique() == AoTechnique::BevySsao {
        return;
    }
    // Its normals are a target only where the near field reads them (see `LayerDraw`).
    let normals = ao_view
        .back_normals
        .then(|| cleared(&textures.back_normal.default_view));
    draw_layer(
        &mut ctx,
        world,
        view_entity,
        camera,
        LayerTargets {
            label: "dynamic_ao_back_faces",
            colors: normals.as_slice(),
            depth: &textures.back_depth.default_view,
        },
        phases.get(&extracted_view.retained_view_entity),
        |pass| coarse.draw(pass, extracted_view.retained_view_entity, view_offset),
    );
}

/// A colour attachment cleared to zero.
pub(super) fn cleared(view: &TextureView) -> Option<RenderPassColorAttachment<'_>> {
    Some(RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: Operations {
            load: LoadOp::Clear(Default::default()),
            store: StoreOp::Store,
        },
    })
}

/// Where a layer is drawn: the pass's label (also its time span's), colour targets and depth.
pub(super) struct LayerTargets<'a> {
    pub label: &'static str,
    pub colors: &'a [Option<RenderPassColorAttachment<'a>>],
    pub depth: &'a TextureView,
}

/// Draws `phase` into `targets`, the size of the camera's viewport, then whatever `more` draws in
/// the same pass. The targets are cleared even when nothing is drawn: an empty texel reads as
/// "no surface".
pub(super) fn draw_layer<'a, const BACK: bool>(
    ctx: &'a mut RenderContext,
    world: &'a World,
    view_entity: Entity,
    camera: &ExtractedCamera,
    targets: LayerTargets,
    phase: Option<&SortedRenderPhase<NdLayer3d<BACK>>>,
    more: impl FnOnce(&mut TrackedRenderPass<'a>),
) {
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some(targets.label),
        color_attachments: targets.colors,
        depth_stencil_attachment: Some(RenderPassDepthStencilAttachment {
            view: targets.depth,
            depth_ops: Some(Operations {
                load: LoadOp::Clear(0.0),
                store: StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let pass_span = diagnostics.pass_span(&mut pass, targets.label);
    if let Some(viewport) = camera.viewport.as_ref() {
        // Our layers have the size of the viewport, so draw from its origin.
        pass.set_camera_viewport(&Viewport {
            physical_position: Default::default(),
            ..viewport.clone()
        });
    }
    if let Some(phase) = phase
        && let Err(err) = phase.render(&mut pass, world, view_entity)
    {
        error!("dynamic AO: error while drawing {}: {err:?}", targets.label);
    }
    more(&mut pass);
    pass_span.end(&mut pass);
}

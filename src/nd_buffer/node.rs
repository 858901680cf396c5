//! The pass that draws the back-face layer.

use bevy::camera::Viewport;
use bevy::ecs::prelude::*;
use bevy::log::error;
use bevy::render::{
    camera::ExtractedCamera,
    diagnostic::RecordDiagnostics,
    render_phase::ViewSortedRenderPhases,
    render_resource::{
        LoadOp, Operations, RenderPassColorAttachment, RenderPassDepthStencilAttachment,
        RenderPassDescriptor, StoreOp,
    },
    renderer::{RenderContext, ViewQuery},
    view::ExtractedView,
};

use super::phase::BackFace3d;
use crate::settings::AoTechnique;
use crate::view::{DynamicAoTextures, DynamicAoView};

pub(crate) fn back_face_pass(
    world: &World,
    view: ViewQuery<(
        &ExtractedCamera,
        &ExtractedView,
        &DynamicAoTextures,
        &DynamicAoView,
    )>,
    phases: Res<ViewSortedRenderPhases<BackFace3d>>,
    mut ctx: RenderContext,
) {
    let view_entity = view.entity();
    let (camera, extracted_view, textures, ao_view) = view.into_inner();
    // Under Bevy's own SSAO none of our passes reads the layer.
    if ao_view.technique() == AoTechnique::BevySsao {
        return;
    }

    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();

    // The layer is cleared even when nothing is drawn: an empty layer reads as "no surface".
    // Its normals are a target only where the near field reads them (see `BackFaceKey`).
    let normals = ao_view.back_normals.then(|| RenderPassColorAttachment {
        view: &textures.back_normal.default_view,
        depth_slice: None,
        resolve_target: None,
        ops: Operations {
            load: LoadOp::Clear(Default::default()),
            store: StoreOp::Store,
        },
    });
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("dynamic_ao_back_faces"),
        color_attachments: if normals.is_some() {
            std::slice::from_ref(&normals)
        } else {
            &[]
        },
        depth_stencil_attachment: Some(RenderPassDepthStencilAttachment {
            view: &textures.back_depth.default_view,
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
    let pass_span = diagnostics.pass_span(&mut pass, "dynamic_ao_back_faces");
    if let Some(viewport) = camera.viewport.as_ref() {
        // Our layer has the size of the viewport, so draw from its origin.
        let viewport = Viewport {
            physical_position: Default::default(),
            ..viewport.clone()
        };
        pass.set_camera_viewport(&viewport);
    }
    if let Some(phase) = phases.get(&extracted_view.retained_view_entity)
        && let Err(err) = phase.render(&mut pass, world, view_entity)
    {
        error!("dynamic AO: error while drawing the back-face layer: {err:?}");
    }
    pass_span.end(&mut pass);
}

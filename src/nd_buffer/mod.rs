//! The two-layer ND-buffer (normals + depth) of Shanmugam & Arikan 2007, §4.2.
//!
//! The front layer is Bevy's own depth and normal prepass, which `front_layer.rs` copies first where
//! the passes cannot read it as it is (MSAA, split-screen viewports). This module draws the
//! second layer:
//! the nearest back faces, through a mesh phase of our own that reuses Bevy's mesh pipeline, so
//! skinned and morph-target meshes deform exactly as in the front layer. On MSAA cameras a second
//! phase of the same kind draws the front faces' depth single-sampled, which tells the copy which
//! of a pixel's samples show the surface at its centre. Both layers use the
//! same encoding: reverse-Z `Depth32Float` depth and world-space normals stored as `n*0.5+0.5` in
//! `Rgb10a2Unorm`. WGSL helpers to read them live in `shaders/nd_buffer.wgsl`. The back layer's
//! normals are drawn only where the near field reads them; for every other technique the layer
//! is depth only, drawn without a fragment stage and with a vertex stage of its own
//! (`back_depth.wgsl`) that computes the clip position alone, through the same morph, skin and
//! transform functions as Bevy's; rigid meshes of many triangles are drawn into that layer from
//! coarse copies (`coarse`).

mod coarse;
mod front_layer;
mod node;
mod phase;
mod pipeline;

use bevy::app::{App, Plugin};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::schedule::IntoScheduleConfigs;
use bevy::pbr::MeshPipeline;
use bevy::render::{
    ExtractSchedule, GpuResourceAppExt, Render, RenderDebugFlags, RenderStartup, RenderSystems,
    render_phase::{AddRenderCommand, DrawFunctions, SortedRenderPhasePlugin, sort_phase_system},
    render_resource::{SpecializedMeshPipelines, SpecializedRenderPipelines},
};

use crate::capabilities;
use crate::schedule::{DynamicAoPrepare, DynamicAoStartup, DynamicAoSystems};
use crate::view::drop_without_ao;
pub use coarse::COARSE_BACK_FACES_ABOVE;
pub(crate) use front_layer::{FrontLayer, FrontLayerViews};
pub use phase::{BackFace3d, CentreSample3d, NdLayer3d};

/// Registers the back-face phase, its pipeline and its pass.
pub struct NdBufferPlugin;

impl Plugin for NdBufferPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "layer_normals.wgsl");
        embedded_asset!(app, "back_depth.wgsl");
        embedded_asset!(app, "front_layer.wgsl");
        embedded_asset!(app, "coarse/coarse_back_depth.wgsl");
        app.add_plugins((
            SortedRenderPhasePlugin::<BackFace3d, MeshPipeline>::new(RenderDebugFlags::default()),
            SortedRenderPhasePlugin::<CentreSample3d, MeshPipeline>::new(
                RenderDebugFlags::default(),
            ),
        ));
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_resource::<SpecializedMeshPipelines<pipeline::BackFacePipeline>>()
            .init_resource::<DrawFunctions<BackFace3d>>()
            .init_resource::<DrawFunctions<CentreSample3d>>()
            .init_resource::<SpecializedRenderPipelines<front_layer::FrontLayerCopyPipeline>>()
            .init_resource::<coarse::CoarseMeshes>()
            .init_resource::<coarse::CoarseInstances>()
            .init_resource::<coarse::CoarseDraws>()
            .add_render_command::<BackFace3d, phase::DrawLayerMeshes>()
            .add_render_command::<CentreSample3d, phase::DrawLayerMeshes>()
            .add_systems(
                RenderStartup,
                (
                    pipeline::init_back_face_pipeline.in_set(DynamicAoStartup::MeshPipelines),
                    front_layer::init_front_layer_copy_pipeline,
                ),
            )
            .add_systems(
                ExtractSchedule,
                (
                    phase::extract_layer_phases::<true>,
                    phase::extract_layer_phases::<false>,
                    coarse::extract_coarse_back_faces,
                ),
            )
            .add_systems(
                Render,
                (
                    pipeline::queue_layers.in_set(RenderSystems::QueueMeshes),
                    sort_phase_system::<BackFace3d>.in_set(RenderSystems::PhaseSort),
                    sort_phase_system::<CentreSample3d>.in_set(RenderSystems::PhaseSort),
                    front_layer::prepare_front_layer_copies.in_set(RenderSystems::PrepareResources),
                    coarse::prepare_coarse_back_faces.in_set(RenderSystems::PrepareBindGroups),
                    front_layer::wait_for_front_layer_copy.in_set(DynamicAoPrepare::Readiness),
                    phase::wait_for_layer_draws.in_set(DynamicAoPrepare::Readiness),
                    front_layer::prepare_front_layer_copy_bind_groups
                        .in_set(DynamicAoPrepare::BindGroups),
                    drop_without_ao::<(
                        front_layer::FrontLayerCopy,
                        front_layer::FrontLayerCopyBindGroup,
                    )>
                        .in_set(DynamicAoPrepare::BindGroups),
                ),
            )
            .add_systems(
                Core3d,
                (
                    front_layer::front_layer_copy_pass.in_set(DynamicAoSystems::FrontLayer),
                    node::back_face_pass.in_set(DynamicAoSystems::BackFaces),
                ),
            );
        render_app.init_gpu_resource::<coarse::CoarseBackPipeline>();
    }
}

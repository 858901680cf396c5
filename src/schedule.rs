//! The order of every pass of the plugin, in one place.
//!
//! All passes run in Bevy's [`Core3d`] schedule, once per camera that has a
//! [`DynamicAo`](crate::DynamicAo) component.

use bevy::app::{App, PostUpdate};
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::ecs::schedule::{IntoScheduleConfigs, SystemSet};
use bevy::pbr::{MeshPipelineSystems, main_build_indirect_parameters};
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderStartup, RenderSystems};
use bevy::transform::TransformSystems;

/// The plugin's main-world systems in `PostUpdate`, listed in the order they run.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DynamicAoUpdate {
    /// Caches drop what they hold for meshes whose asset changed.
    ForgetChangedMeshes,
    /// Far-field occluders follow this frame: sphere proxies are refit, voxel volumes gather
    /// their triangles, AO fields are loaded or baked.
    Occluders,
    /// Debug drawing of this frame's proxies.
    Gizmos,
}

/// The passes of the plugin in the [`Core3d`] schedule, listed in the order they run.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DynamicAoSystems {
    /// Copies the front layer out of Bevy's prepass where the passes cannot read it as it is
    /// (MSAA, split-screen viewports).
    FrontLayer,
    /// Draws the back faces of the scene into the second ND-buffer layer.
    BackFaces,
    /// The view's image-space technique (near-field, horizon-based or ray march).
    NearField,
    /// Temporal accumulation of the image-space occlusion.
    Temporal,
    /// The far field: splats the spheres of sphere occluders, and draws the grid boxes of AO
    /// field occluders.
    FarField,
    /// Joint bilateral upsampling of half-resolution occlusion to full resolution.
    Upsample,
    /// Cross-bilateral blur of the occlusion.
    Filter,
    /// Combines the occlusion terms and writes visibility for Bevy's PBR lighting.
    Compose,
    /// Debug view and read-back copies, after the lit image exists.
    Debug,
    /// Overlays drawn over the debug view (occupied voxels).
    DebugOverlay,
}

/// Extraction of the plugin's per-view state, in order.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum DynamicAoExtract {
    /// Each far-field technique notes whether it has occluders this frame.
    Occluders,
    /// The settings and uniform of each view, which switch off the terms without occluders.
    Views,
    /// One-frame requests the views have read (a temporal reset) are cleared in the main world,
    /// as Bevy's TAA clears its own: after extraction, so none is lost whenever it was set. And
    /// what the frame rendered last showed is copied onto the cameras (`DynamicAoStatus`).
    Consumed,
}

/// Preparation steps of the plugin that need an order in Bevy's [`Render`] schedule.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum DynamicAoPrepare {
    /// Bevy's SSAO texture made fit for our passes on split-screen and MSAA views, between Bevy
    /// making it and the bind groups that bind it (see `compose::ssao_slot`).
    SsaoSlot,
    /// Each technique counts the passes of a view that have not compiled yet.
    Readiness,
    /// Our passes take over Bevy's SSAO texture on views where all have compiled.
    HandOver,
    /// The bind groups of the passes.
    BindGroups,
    /// The bind groups of debug overlays.
    OverlayBindGroups,
    /// MSAA views get back the SSAO resources held aside while Bevy made its bind groups.
    RestoreSsao,
    /// What each view's AO texture holds this frame is recorded (`DynamicAoStatus`), once
    /// nothing moves Bevy's SSAO on or off the view any more.
    Status,
}

/// Pipelines built once, when the renderer starts.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum DynamicAoStartup {
    /// Pipelines derived from Bevy's mesh pipeline (the back-face layer's).
    MeshPipelines,
}

/// Orders the main-world systems; each plugin that adds some calls it, so that it also holds
/// where that plugin is used without [`DynamicAoPlugin`](crate::DynamicAoPlugin).
pub(crate) fn configure_update(app: &mut App) {
    use DynamicAoUpdate::*;
    app.configure_sets(
        PostUpdate,
        (ForgetChangedMeshes, Occluders, Gizmos)
            .chain()
            // Joints and meshes have their final world transforms of this frame: proxies are
            // refit, triangles gathered and skinned or morphed meshes baked in this pose.
            .after(TransformSystems::Propagate),
    );
}

pub(crate) fn configure(app: &mut App) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    use DynamicAoSystems::*;
    render_app.configure_sets(
        Core3d,
        // At half resolution the blur runs on the upsampled, full-resolution AO.
        (
            FrontLayer, BackFaces, NearField, Temporal, FarField, Upsample, Filter, Compose,
        )
            .chain()
            // The front layer is Bevy's prepass output.
            .after(Core3dSystems::Prepass)
            // Before this system the indirect draw arguments of our phase can be stale, which
            // only shows when the set of visible meshes changes on a frame.
            .after(main_build_indirect_parameters)
            // The PBR shader of the main pass reads what Compose writes.
            .before(Core3dSystems::MainPass),
    );
    render_app.configure_sets(
        Core3d,
        (Debug, DebugOverlay)
            .chain()
            // The debug view overwrites the lit image, and read-backs copy final values.
            .after(Core3dSystems::MainPass)
            // Tonemapping and the rest of post-processing still apply to the debug view.
            .before(Core3dSystems::EarlyPostProcess),
    );
    render_app.configure_sets(
        ExtractSchedule,
        // A view's uniform leaves out the far-field terms that have no occluders.
        (
            DynamicAoExtract::Occluders,
            DynamicAoExtract::Views,
            DynamicAoExtract::Consumed,
        )
            .chain(),
    );
    render_app.configure_sets(
        Render,
        (DynamicAoPrepare::Readiness, DynamicAoPrepare::HandOver)
            .chain()
            // Pipelines are compiled during `Prepare`, and Bevy inserts `SsaoPipelineId` there,
            // which the hand-over removes before Bevy's pass would read it.
            .after(RenderSystems::Prepare)
            .before(RenderSystems::Render),
    );
    render_app.configure_sets(
        Render,
        (
            DynamicAoPrepare::BindGroups,
            DynamicAoPrepare::OverlayBindGroups,
        )
            .chain()
            .in_set(RenderSystems::PrepareBindGroups),
        // The occupied-voxel overlay and the voxel passes both use the voxel buffers, which the
        // voxel bind groups may recreate: a fixed order instead of whichever the executor picks.
    );
    render_app.configure_sets(
        Render,
        DynamicAoPrepare::SsaoSlot
            .after(RenderSystems::PrepareResourcesFlush)
            .before(RenderSystems::PrepareBindGroups),
    );
    render_app.configure_sets(
        Render,
        DynamicAoPrepare::RestoreSsao
            .after(RenderSystems::PrepareBindGroups)
            .before(RenderSystems::Render),
    );
    render_app.configure_sets(
        Render,
        DynamicAoPrepare::Status
            .after(DynamicAoPrepare::HandOver)
            .after(DynamicAoPrepare::RestoreSsao)
            .before(RenderSystems::Render),
    );
    render_app.configure_sets(
        RenderStartup,
        // The back-face pipeline is built on Bevy's mesh pipeline and its layouts.
        DynamicAoStartup::MeshPipelines.after(MeshPipelineSystems),
    );
}

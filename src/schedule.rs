//! The order of every pass of the plugin, in one place.
//!
//! All passes run in Bevy's [`Core3d`] schedule, once per camera that has a
//! [`DynamicAo`](crate::DynamicAo) component.

use bevy::app::App;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::ecs::schedule::{IntoScheduleConfigs, SystemSet};
use bevy::pbr::main_build_indirect_parameters;
use bevy::render::RenderApp;

/// The passes of the plugin in the [`Core3d`] schedule, listed in the order they run.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DynamicAoSystems {
    /// Draws the back faces of the scene into the second ND-buffer layer.
    BackFaces,
    /// The view's image-space technique (near-field, horizon-based or ray march).
    NearField,
    /// The far field: splats the spheres of sphere occluders, and draws the grid boxes of AO
    /// field occluders.
    FarField,
    /// Cross-bilateral blur of the occlusion.
    Filter,
    /// Combines the occlusion terms and writes visibility for Bevy's PBR lighting.
    Compose,
    /// Debug view and read-back copies, after the lit image exists.
    Debug,
}

pub(crate) fn configure(app: &mut App) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    use DynamicAoSystems::*;
    render_app.configure_sets(
        Core3d,
        (BackFaces, NearField, FarField, Filter, Compose)
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
        Debug
            // The debug view overwrites the lit image, and read-backs copy final values.
            .after(Core3dSystems::MainPass)
            // Tonemapping and the rest of post-processing still apply to the debug view.
            .before(Core3dSystems::EarlyPostProcess),
    );
}

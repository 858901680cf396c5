//! Precomputed ambient occlusion fields for rigid occluders (Malmer et al. 2005).
//!
//! A field is a small 3D grid around an object, in the object's own space, holding at every
//! grid point the fraction of the sphere of directions the object blocks (eq. 2) and the average
//! occluded direction. [`baker`] computes it by ray casting (grid extent by eq. 4, border
//! rescale §3.4.1, interior fill §3.4.2); [`format`](mod@format) stores it as a versioned, checksummed
//! `.aofield` file; [`AoFieldLoader`] loads such files as [`AoFieldData`] assets, and bad files
//! fail to load with a message instead of panicking. The `ao_bake` example bakes every mesh of
//! a glTF file.
//!
//! At render time (§3.1) each occluder with an [`AoField`] draws the back faces of its grid box;
//! every pixel inside the box reads the field at its world position and the receiver's normal,
//! and the occluders' visibilities multiply (§3.3.2). [`FieldShading`](crate::FieldShading) on
//! the camera picks the occlusion-only shading (2a, §3.2) or the cone (T_clip, §3.3.1, the
//! default: it needs no special case for the object's own surface).

pub mod baker;
mod component;
pub mod format;
mod loader;
mod node;
mod render;
mod systems;
pub mod t_clip;

use bevy::app::{App, Plugin, PostUpdate};
use bevy::asset::{AssetApp, embedded_asset};
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::render::{ExtractSchedule, GpuResourceAppExt, Render, RenderApp, RenderSystems};

pub use baker::{BakeError, BakeSettings, bake, grid_box};
pub use component::{AoField, AoFieldCache};
pub use format::{AoFieldData, AoFieldError};
pub use loader::AoFieldLoader;
pub use systems::ActiveAoField;

pub(crate) use render::FieldPipelines;

use crate::schedule::DynamicAoSystems;

/// AO fields: the asset and its loader, baking on load, and the box pass.
pub struct AoFieldPlugin;

impl Plugin for AoFieldPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "fields.wgsl");
        app.init_asset::<AoFieldData>()
            .register_asset_loader(AoFieldLoader)
            .register_type::<AoField>()
            .init_resource::<AoFieldCache>()
            .init_resource::<systems::BakedFields>()
            .add_systems(PostUpdate, systems::resolve_fields);
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_resource::<render::FieldBuffers>()
            .add_systems(ExtractSchedule, render::extract_fields)
            .add_systems(
                Render,
                (
                    render::write_field_buffers.in_set(RenderSystems::PrepareResources),
                    render::prepare_field_bind_groups.in_set(RenderSystems::PrepareBindGroups),
                ),
            )
            .add_systems(Core3d, node::field_pass.in_set(DynamicAoSystems::FarField));
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app.init_gpu_resource::<FieldPipelines>();
    }
}

//! Precomputed ambient occlusion fields for rigid occluders (Malmer et al. 2005).
//!
//! A field is a small 3D grid around an object, in the object's own space, holding at every
//! grid point the fraction of the sphere of directions the object blocks (eq. 2) and the average
//! occluded direction. [`baker`] computes it by ray casting; [`format`](mod@format) stores it as a
//! versioned, checksummed `.aofield` file; [`AoFieldLoader`] loads such files as [`AoFieldData`]
//! assets, and bad files fail to load with a message instead of panicking. The `ao_bake`
//! example bakes every mesh of a glTF file.
//!
//! At render time (§3.1) each occluder with an [`AoField`] draws the back faces of its grid box;
//! every pixel inside the box reads the field at its world position and the receiver's normal,
//! and the occluders' visibilities multiply (§3.3.2), but for those of objects that fill one
//! another's bounds ([`join`]). [`FieldShading`](crate::FieldShading) on
//! the camera picks the occlusion-only shading (2a, §3.2) or the cone (T_clip, §3.3.1, the
//! default, evaluated in closed form by `shaders/cap_occlusion.wgsl`).
//!
//! Where this departs from the paper, and why (each measured in `tests/gpu/far_field.rs` and
//! `cargo bench --bench far_field`):
//!
//! - **What ground truth measures.** The paper counts hits at any distance, cuts the grid where
//!   occlusion falls below ε (eq. 4) and rescales every value so the border reads 0 (§3.4.1),
//!   which lowered the occlusion next to a box just off-screen from 0.205 to 0.091. Here rays
//!   count hits within the camera's [`radius`](crate::DynamicAo::radius) R
//!   ([`FieldReach::CameraRadius`], baked again in the background when the cameras' radius
//!   changes), so the grid is the object's bounds grown by R and is exactly 0 at its border: no
//!   rescale is needed. The paper's field is [`BakeSettings::paper`].
//! - **Counted once.** Each grid point stores a second occlusion and direction for hits within the
//!   near field's reach, and the mean point those rays meet: under
//!   [`FarFieldBlend::CountOnce`](crate::FarFieldBlend::CountOnce) that part is left to the near
//!   field where the ND-buffer holds that point, and the rest joins as the part beyond.
//! - **Never on its own surface.** A thin object (a floor, a wall, a table top) has grid points on
//!   both sides, and interpolating across it mixed values from both, so an open floor read
//!   0.4–0.6. Grid points store their signed distance to the object; the lookup interpolates only
//!   points outside it (no interior fill needed) and fades the field out over the half cell next
//!   to the object, so the object's own surface is left to the near field: an open floor with its
//!   own field reads 1. Only receivers that lie along the surface there fade (their normal within
//!   about 45° of the signed distance's gradient, either side): another object's surface that
//!   touches this one (a slab standing on a floor with a field) stands across it and keeps the
//!   field's full value, where the fade left a bright band half a cell wide along the contact (a
//!   bumpy ball and a slab on a floor, the default joined to fields: RMSE 0.0405 → 0.0390 at
//!   R = 2 m, 0.0451 → 0.0448 at 0.75 m).
//! - **Its own surface beyond the near field's reach.** Under count-once the near field reaches
//!   only [`near_field_radius`](crate::DynamicAo::near_field_radius) (0.5 m), so a concave
//!   object's occlusion of itself beyond that (a ring's far side across its hole) was counted by
//!   nothing: joined to the default at 2 m an AO field made a ring on a floor worse than no field
//!   (1.10× the error). Grid points outside the object within two cells of its surface store,
//!   for the surface point nearest them (the nearest of their rays' hits), the share of its
//!   cosine-weighted hemisphere the object blocks between the near reach and R among the
//!   directions open within the near reach, and that surface's normal on their side; the lookup
//!   reads it where the field fades out, from the points whose surface faces the way the
//!   receiver does (so a thin object's two sides stay apart), and it joins the part beyond the
//!   near field's reach. The ring: 0.68×.
//!   Not on skinned or morphed meshes: their surface moves away from the pose they were baked in
//!   (a running fox's legs read darker than with no field at 2 m).
//! - **The cone corrected on the axes.** T_clip treats the blocked directions as a cap around
//!   their mean; a large flat occluder blocks another shape, and beside a wall the floor read
//!   0.017 darker than traced on average (0.040 at worst; the wall just off-screen at R = 2 m:
//!   0.465 against 0.424). Each grid point also stores, for receivers facing ±x, ±y and ±z, the
//!   traced occlusion of that hemisphere minus the cone's ([`AoFieldData::axes`], from the same
//!   rays), and the lookup adds them weighted by the squared components of the receiver's
//!   mesh-space normal: exact on the axes, blended between them
//!   ([`BakeSettings::axis_correction`]; the floor beside the wall 0.0015 on average, `cargo test
//!   --lib axis_corrections -- --nocapture`; the wall just off-screen 0.428 against 0.424). A
//!   cell takes 112 bytes instead of 64.
//! - **Reach in world units.** A field the plugin bakes is baked from the mesh scaled by its
//!   entity's world scale and placed without that scale, so R counts metres whatever units the
//!   mesh was modelled in. Baked in mesh space, a model in centimetres scaled by 0.01 reached
//!   0.01 R and cast almost nothing on the floor it stood on.
//! - **Cells of about the same size along every axis**, within a budget of `resolution`³ cells,
//!   and at least [`THIN_AXIS_CELLS`](baker::THIN_AXIS_CELLS) × `resolution` across a thin side:
//!   a 20 m floor's field at R = 0.75 m gets 12 cells of 13 cm across its height, not 4 of 36 cm,
//!   whose steps striped the sides of a box standing on it (AnimatedMorphCube on such a floor,
//!   joined to the default: 0.0156 → 0.0096 RMSE, the default alone 0.0104).
//! - **Objects that fill another's bounds join by their union.** The product of §3.3.2 counts an
//!   occluder once only where the objects lie in different directions from the receiver. An object
//!   that fills another's bounds (BoxAnimated's box, which fills its frame at the start of the
//!   animation) stands behind it as a receiver outside sees them, and the product counted what
//!   they share twice: the floor around the frame read darker than with no field (joined to the
//!   default at R = 2 m, 0.0527 against 0.0215 alone). Outside the outer bounds they now join by
//!   the union compose takes for a character's proxies ([`join`]): 0.0334.
//!
//! A field is rigid: on a skinned or morphed mesh it is baked in the pose the mesh has when it is
//! first seen (with a warning); animated meshes belong to [`SphereOccluder`](crate::spheres::SphereOccluder)
//! or a [`VoxelAoVolume`](crate::voxels::VoxelAoVolume).

pub mod baker;
mod buffers;
mod cache;
mod component;
pub mod format;
pub mod join;
mod loader;
mod node;
mod pipeline;
pub mod settings;
mod systems;
mod view;

use bevy::app::{App, Plugin, PostUpdate};
use bevy::asset::{AssetApp, embedded_asset};
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::render::{ExtractSchedule, GpuResourceAppExt, Render, RenderSystems};

pub use baker::{BakeError, BakeSettings, FieldReach, bake, grid_box, grid_resolution};
pub use component::{AoField, AoFieldCache, default_cache_folder};
pub use format::{AoFieldData, AoFieldError};
pub use loader::AoFieldLoader;
pub use systems::{ActiveAoField, PendingAoField};

pub(crate) use pipeline::FieldPipelines;

use crate::capabilities;
use crate::schedule::{
    self, DynamicAoExtract, DynamicAoPrepare, DynamicAoSystems, DynamicAoUpdate,
};
use crate::view::{FarTerm, drop_without_ao, prepare_far_visibility};

/// AO fields: the asset and its loader, baking on load, and the box pass.
pub struct AoFieldPlugin;

impl Plugin for AoFieldPlugin {
    fn build(&self, app: &mut App) {
        schedule::configure_update(app);
        embedded_asset!(app, "fields.wgsl");
        app.init_asset::<AoFieldData>()
            .register_asset_loader(AoFieldLoader)
            .register_type::<AoField>()
            .init_resource::<AoFieldCache>()
            .init_resource::<systems::BakedFields>()
            .add_observer(systems::remove_active_field)
            .add_systems(
                PostUpdate,
                systems::resolve_fields.in_set(DynamicAoUpdate::Occluders),
            );
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_resource::<buffers::FieldBuffers>()
            .add_systems(
                ExtractSchedule,
                (
                    buffers::extract_fields,
                    view::note_field_occluders.in_set(DynamicAoExtract::Occluders),
                ),
            )
            .add_systems(
                Render,
                (
                    (
                        buffers::write_field_buffers,
                        prepare_far_visibility(FarTerm::Fields, "dynamic_ao_field_visibility"),
                    )
                        .in_set(RenderSystems::PrepareResources),
                    view::wait_for_fields.in_set(DynamicAoPrepare::Readiness),
                    pipeline::prepare_field_bind_groups.in_set(DynamicAoPrepare::BindGroups),
                    drop_without_ao::<pipeline::FieldBindGroup>
                        .in_set(DynamicAoPrepare::BindGroups),
                ),
            )
            .add_systems(Core3d, node::field_pass.in_set(DynamicAoSystems::FarField));
        render_app.init_gpu_resource::<FieldPipelines>();
    }
}

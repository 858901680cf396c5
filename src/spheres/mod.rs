//! Far-field occlusion from simple proxies that follow their meshes (Shanmugam & Arikan 2007,
//! §5–6, with boxes in place of its spheres by default).
//!
//! Screen-space AO cannot see what is off-screen or behind the first surface, and its reach is
//! a few pixels. Here each occluder mesh stands in for itself through a handful of proxies:
//!
//! 1. Once per mesh asset, [`fit`] covers the mesh's solid with a few oriented boxes (one for a
//!    box, a wall or a floor, one per bone for a character, cut further where a box would be
//!    mostly empty), or, as the paper does, [`lloyd`] clusters its area-weighted vertices into
//!    spheres inside the surface ([`ProxyShape::Spheres`]). Large meshes are fitted on the async
//!    compute pool.
//! 2. Every frame, after animation and transform propagation, [`refit`] moves the proxies with
//!    the skinned and morphed vertices ([`OccluderSpheres`] holds the result): a box is skinned
//!    like a vertex with its bone weights and turns with its bones, a box of an unskinned morphed
//!    mesh takes the spread of its vertices along each of its axes; a sphere follows the centroid
//!    and spread of its cluster (§5.3).
//! 3. The splat pass draws one billboard per proxy over every pixel its occlusion can reach and
//!    writes the share of ambient light the proxy blocks (`shaders/proxy_occlusion.wgsl`):
//!
//!    - **What ground truth measures.** A box blocks the cosine-weighted solid angle of the faces
//!      it turns to the receiver, integrated exactly (Lambert's formula for polygons) after
//!      clipping each face to the receiver's tangent plane and to the part a ray shorter than the
//!      camera's [`radius`](crate::DynamicAo::radius) R can meet; a sphere blocks the cap of
//!      directions that meet it within R. The paper's cut-off (eq. 5: influence ends where it
//!      falls below ε, and is unlimited before) is [`ProxyReach::Epsilon`].
//!    - **Counted once.** Under [`FarFieldBlend::CountOnce`](crate::FarFieldBlend::CountOnce)
//!      the part of a proxy within the near field's reach goes to one channel, left out where
//!      the ND-buffer holds it (the near field counts that), and the part beyond goes to another.
//!      A box face the camera sees edge-on is not left out, even where the ND-buffer holds it:
//!      image-space samples are spread over the screen, so a wall seen edge-on gets almost none
//!      (inside a room open towards the camera this left light bands along the side walls).
//!    - **Together.** Proxies multiply their visibilities per channel; the buffer also keeps the
//!      product of skinned meshes' proxies alone and the largest of their occlusions. A
//!      character's proxies stand one behind another (an arm before the torso), so their product
//!      counts hidden parts too; compose takes their union halfway between the largest proxy and
//!      the product (measured against the proxies themselves ray-traced, on the floor around
//!      characters: within 15 % where the product was 40–80 % over). So it does for a rigid mesh
//!      that encloses a volume and got several boxes (a ring's near and far sides: with the
//!      product, a bumpy ring on a floor at R = 2 m read 0.100 joined to the default, 0.068
//!      without the far field, 0.048 with the union), and for an open rigid mesh with several
//!      proxies (a window frame, a room) where the receiver lies outside the box that bounds
//!      them, with the meshes inside that box ([`join`]: BoxAnimated's cube frame and the box in
//!      it, joined to the default at 2 m, 0.103 → 0.030; the default alone 0.022). It joins every
//!      other proxy as an independent occluder. Walls, floors and props lie in different
//!      directions and hide nothing of one another: the union over every proxy undercounted a
//!      room's walls (the Cornell box at 2 m: 0.162 RMSE, 0.106 now). Under
//!      count-once, what the union-joined proxies cast beyond the near field's reach joins what
//!      counts within it by the same union: the near field has counted the solid's near side,
//!      which hides its far side from receivers beside it (the bumpy ring joined to the default
//!      at 2 m: 0.0484 joined independently, 0.0341 so; the default alone 0.0318).
//!
//! How well the proxies stand for their meshes, measured (`fit` and `far_field` tests): a box
//! and a wall within 1.5 % of the mesh's own occlusion at a distance, a ball 9 % over, a 3 cm
//! rod 20 % over, the project's skinned walker 6–7 % over on the floor around it.
//!
//! Add [`SphereOccluder`] to a mesh entity or a scene root. The camera's
//! [`DynamicAo::spheres`](crate::DynamicAo::spheres) switches the far field on or off per view.

mod buffers;
mod component;
pub mod fit;
#[cfg(feature = "gizmos")]
mod gizmos;
pub mod join;
pub mod lloyd;
mod node;
mod pipeline;
pub mod refit;

mod systems;
mod view;

use bevy::app::{App, Plugin, PostUpdate};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::render::{ExtractSchedule, GpuResourceAppExt, Render, RenderSystems};

pub use component::{
    OccluderSphere, OccluderSpheres, ProxyReach, ProxyShape, SphereOccluder, far_field_reach,
};
#[cfg(feature = "gizmos")]
pub use gizmos::ShowOccluderSpheres;
pub use systems::ASYNC_CLUSTERING_VERTICES;

pub(crate) use pipeline::SplatPipeline;

use crate::capabilities;
use crate::schedule::{
    self, DynamicAoExtract, DynamicAoPrepare, DynamicAoSystems, DynamicAoUpdate,
};
use crate::view::{FarTerm, drop_without_ao, prepare_far_visibility};

/// Sphere occluders: clustering, per-frame refit, and the splat pass.
pub struct SphereOccluderPlugin;

/// The main-world system that refits the spheres, for ordering against it.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RefitSpheres;

impl Plugin for SphereOccluderPlugin {
    fn build(&self, app: &mut App) {
        schedule::configure_update(app);
        embedded_asset!(app, "splat.wgsl");
        app.register_type::<SphereOccluder>()
            .register_type::<OccluderSpheres>()
            .register_type::<ProxyShape>()
            .register_type::<ProxyReach>()
            .init_resource::<systems::SphereCache>()
            .add_systems(
                PostUpdate,
                (
                    systems::forget_changed_meshes.in_set(DynamicAoUpdate::ForgetChangedMeshes),
                    systems::refit_spheres
                        .in_set(RefitSpheres)
                        .in_set(DynamicAoUpdate::Occluders),
                ),
            );
        #[cfg(feature = "gizmos")]
        app.init_resource::<ShowOccluderSpheres>()
            .register_type::<ShowOccluderSpheres>()
            .add_systems(
                PostUpdate,
                gizmos::draw_spheres.in_set(DynamicAoUpdate::Gizmos),
            );
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_resource::<buffers::SphereBuffer>()
            .add_systems(
                ExtractSchedule,
                (
                    buffers::extract_spheres,
                    view::note_sphere_occluders.in_set(DynamicAoExtract::Occluders),
                ),
            )
            .add_systems(
                Render,
                (
                    (
                        buffers::write_sphere_buffer,
                        prepare_far_visibility(FarTerm::Spheres, "dynamic_ao_sphere_visibility"),
                    )
                        .in_set(RenderSystems::PrepareResources),
                    view::wait_for_splat.in_set(DynamicAoPrepare::Readiness),
                    pipeline::prepare_splat_bind_groups.in_set(DynamicAoPrepare::BindGroups),
                    drop_without_ao::<pipeline::SplatBindGroup>
                        .in_set(DynamicAoPrepare::BindGroups),
                ),
            )
            .add_systems(Core3d, node::splat_pass.in_set(DynamicAoSystems::FarField));
        render_app.init_gpu_resource::<SplatPipeline>();
    }
}

//! Far-field occlusion from spheres (Shanmugam & Arikan 2007, §5–6).
//!
//! Screen-space AO cannot see what is off-screen or behind the first surface, and its reach is
//! a few pixels. Here each occluder mesh is approximated by a handful of spheres:
//!
//! 1. [`lloyd`]: once per mesh asset, Lloyd clustering of the area-weighted rest-pose vertices;
//!    each cluster becomes a sphere inside the surface (cached; large meshes are clustered on
//!    the async compute pool).
//! 2. [`refit`]: every frame, after animation and transform propagation, the spheres follow the
//!    skinned and morphed vertices of their cluster ([`OccluderSpheres`] holds the result).
//! 3. The splat pass draws one billboard per sphere covering every pixel within d_far
//!    ([`far_field_reach`], eq. 5) and adds A_ψ (eq. 2–3, 1 inside the sphere) into a far-field
//!    buffer with additive blending; compose adds it to the near field and clamps (§6).
//!
//! Add [`SphereOccluder`] to a mesh entity or a scene root. The camera's
//! [`DynamicAo::spheres`](crate::DynamicAo::spheres) switches the far field on or off per view.

mod component;
#[cfg(feature = "gizmos")]
mod gizmos;
pub mod lloyd;
mod node;
pub mod refit;
pub mod rest_mesh;
mod splat;
mod systems;

use bevy::app::{App, Plugin, PostUpdate};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::render::{ExtractSchedule, GpuResourceAppExt, Render, RenderApp, RenderSystems};
use bevy::transform::TransformSystems;

pub use component::{OccluderSphere, OccluderSpheres, SphereOccluder, far_field_reach};
#[cfg(feature = "gizmos")]
pub use gizmos::ShowOccluderSpheres;
pub use systems::ASYNC_CLUSTERING_VERTICES;
pub(crate) use systems::{mesh_morph_weights, skin_joints};

pub(crate) use splat::SplatPipeline;

use crate::schedule::DynamicAoSystems;

/// Sphere occluders: clustering, per-frame refit, and the splat pass.
pub struct SphereOccluderPlugin;

/// The main-world system that refits the spheres, for ordering against it.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RefitSpheres;

impl Plugin for SphereOccluderPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "splat.wgsl");
        app.register_type::<SphereOccluder>()
            .register_type::<OccluderSpheres>()
            .init_resource::<systems::SphereCache>()
            .add_systems(
                PostUpdate,
                (systems::forget_changed_meshes, systems::refit_spheres)
                    .chain()
                    .in_set(RefitSpheres)
                    // Joints and meshes have their final world transforms this frame.
                    .after(TransformSystems::Propagate),
            );
        #[cfg(feature = "gizmos")]
        app.init_resource::<ShowOccluderSpheres>()
            .register_type::<ShowOccluderSpheres>()
            .add_systems(PostUpdate, gizmos::draw_spheres.after(RefitSpheres));

        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_resource::<splat::SphereBuffer>()
            .add_systems(ExtractSchedule, splat::extract_spheres)
            .add_systems(
                Render,
                (
                    splat::write_sphere_buffer.in_set(RenderSystems::PrepareResources),
                    splat::prepare_splat_bind_groups.in_set(RenderSystems::PrepareBindGroups),
                ),
            )
            .add_systems(Core3d, node::splat_pass.in_set(DynamicAoSystems::FarField));
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app.init_gpu_resource::<SplatPipeline>();
    }
}

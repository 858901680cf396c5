//! Dynamic ambient occlusion for Bevy.
//!
//! Add [`DynamicAoPlugin`] to the app and [`DynamicAo`] to a 3D camera:
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_dynamic_ao::prelude::*;
//!
//! App::new()
//!     .add_plugins((DefaultPlugins, DynamicAoPlugin))
//!     .add_systems(Startup, |mut commands: Commands| {
//!         commands.spawn((Camera3d::default(), DynamicAo::default()));
//!     })
//!     .run();
//! ```
//!
//! What runs each frame, per camera (the order lives in [`schedule`]):
//!
//! 1. Bevy's depth and normal prepass gives the front layer of the ND-buffer (copied into a
//!    single-sampled, viewport-sized layer first on MSAA and split-screen cameras); our
//!    [`nd_buffer`] pass draws the back faces into a second layer (Shanmugam & Arikan 2007, §4.2).
//! 2. [`ray_march`] (the default) marches a few rays per pixel through both layers at half
//!    resolution (Bavoil & Sainz 2008), counting a step just behind the back-face layer as
//!    solid, since models are shells ([`RayMarchParams::thickness`]), and [`temporal`]
//!    accumulates them over frames through
//!    Bevy's motion vectors; or [`near_field`] computes image-space occlusion from both layers
//!    (S&A eq. 2–4), or [`horizon`] horizon-based occlusion from the front layer.
//! 3. [`spheres`] adds far-field occlusion from the proxies (boxes, or the paper's spheres) of
//!    every [`SphereOccluder`](spheres::SphereOccluder), refit each frame to skinned and morphed
//!    meshes (S&A §5), [`fields`] from the precomputed AO field of every
//!    [`AoField`](fields::AoField) (Malmer et al. 2005), and [`voxels`] from the geometry in every
//!    [`VoxelAoVolume`](voxels::VoxelAoVolume), revoxelized each frame (Reinbothe et al. 2009);
//!    all include occluders that are off-screen or hidden. Every term measures what a ray tracer
//!    measures: the share of the cosine-weighted hemisphere blocked within the camera's
//!    [`radius`](DynamicAo::radius); the papers' own weightings are options.
//! 4. [`filter`] brings half-resolution occlusion back to full resolution with a joint bilateral
//!    upsampling, and without temporal accumulation smooths it with a separable cross-bilateral
//!    blur that does not cross depth edges (Bavoil & Sainz 2008), nor creases and panel lines,
//!    where the normal turns ([`AoBlur::normal_sharpness`]); under accumulation the history
//!    averages the noise instead ([`AoBlur::accumulated_radius`]; a viewport too small for half
//!    resolution, [`DynamicAo::small_viewport_pixels`], keeps a blur of one pixel). A fine-detail term read from
//!    the full-resolution front layer, for the grooves the ray march's steps step over
//!    ([`AoBlur::detail_reach`]), joins the ray march's occlusion: in the ray march itself, a
//!    side a frame, under accumulation, else in the blur's last pass.
//! 5. [`compose`] joins near- and far-field occlusion, counting each occluder once
//!    ([`FarFieldBlend`]), turns it into visibility and writes it into the texture Bevy's PBR
//!    shader already reads for its own SSAO, so only ambient/indirect diffuse light and
//!    environment specular darken; direct lights are untouched. On MSAA cameras, where Bevy makes
//!    no such texture, and on split-screen viewports, where its texture is too small, compose
//!    makes one fit.
//!
//! # Architecture
//!
//! One frame, from the camera component to PBR. Boxes are modules; every arrow into
//! `compose` goes through the neutral per-view state of `view/` (settings, uniform, the
//! far-field outputs and the count of passes still compiling), so `view/` and `compose`
//! import no technique, and a technique is its folder plus one line in the plugin list below
//! and one in [`schedule`].
//!
//! ```text
//!  main world                         render world, per camera with DynamicAo
//!  ----------                         ----------------------------------------
//!  DynamicAo (settings/, each    ──►  view/: DynamicAoView + DynamicAoUniform,
//!  technique's settings.rs)           back-face and occlusion textures
//!                                        │
//!  Bevy prepass (front layer) ───────►  nd_buffer/  back faces: second ND-buffer layer
//!                                        │
//!                                        ▼
//!                                     image_space/ runs near_field/ | horizon/ | ray_march/
//!                                        │  (one pass, one shader per folder)
//!                                     temporal/ joins it with its reprojected history (opt-in)
//!  SphereOccluder ─► spheres/ refit ─►  spheres/  splat ───┐
//!  AoField ────────► fields/ bake ────►  fields/   grid boxes ├─► FarFieldOutputs (view/)
//!  VoxelAoVolume ──► voxels/ gather ──►  voxels/   voxelize, sample, upsample ┘   │
//!                                        │                                        │
//!                                        ▼                                        │
//!                                     filter/   blur (and upsampling)             │
//!                                        │                                        │
//!                                        ▼                                        ▼
//!                                     compose/  near ⊕ far → visibility in Bevy's SSAO texture
//!                                        │
//!                                        ▼
//!                                     Bevy PBR: ambient and indirect light × visibility
//! ```
//!
//! Every technique folder names its files by role: `mod.rs` (docs and plugin), `component.rs`
//! (what users put on an occluder), `settings.rs` (its part of [`DynamicAo`]), `systems.rs`
//! (main-world systems), `buffers.rs` (its data extracted and uploaded every frame),
//! `pipeline.rs` (pipelines and per-view bind groups), `node.rs` (its passes), `view.rs` (its
//! per-view state) and its `.wgsl`. The image-space techniques share their pipeline and node in
//! `image_space/`. The uniform every pass reads is `DynamicAoUniform`, in Rust (`view/uniform.rs`) and
//! WGSL (`shaders/uniform.wgsl`) alike, each field named after the setting it comes from.
//!
//! Shared code has no rendering in it: [`geometry`] (rest meshes, skinning and morphing,
//! triangles, BVH, closedness, hash) serves the techniques and [`reference`](mod@reference);
//! `src/shaders/` holds the WGSL every pass imports (ND-buffer reads, sampling, cap and proxy
//! occlusion, Wendland's kernel). Production code never imports `reference`.
//!
//! Where each paper's equations live (the CPU twin of each shader is in `reference/`; that of
//! `shaders/cap_occlusion.wgsl`, which the field baker uses too, in `geometry/cap.rs`):
//!
//! | paper | equation | file |
//! | --- | --- | --- |
//! | Shanmugam & Arikan 2007 | §4.1–4.2 ND-buffer, two layers | `shaders/nd_buffer.wgsl`, `nd_buffer/layer_normals.wgsl` |
//! | | eq. 2–3, occlusion by one sphere | `shaders/sphere_occlusion.wgsl` |
//! | | eq. 2–4, near field | `near_field/near_field.wgsl` |
//! | | §5.2 splatting, eq. 5 d_far | `spheres/splat.wgsl`, `spheres/component.rs` (`far_field_reach`) |
//! | | §5.3 refit | `spheres/refit.rs` |
//! | Malmer et al. 2005 | §3.1 baking | `fields/baker/mod.rs` |
//! | | §3.2–3.3 lookup, T_clip, blending | `fields/fields.wgsl`, `shaders/cap_occlusion.wgsl` (T_clip's axis corrections, not in the paper: `fields/baker/axes.rs`; the union of objects that fill one another's bounds, not in the paper: `fields/join.rs`) |
//! | | §3.4 border rescale, interior fill | `fields/baker/paper.rs` |
//! | Bavoil & Sainz 2008 | horizon-based AO | `horizon/horizon.wgsl` |
//! | | ray-marched AO | `ray_march/march.wgsl` |
//! | | cross-bilateral blur | `filter/blur.wgsl` (its weight on normals is not in the paper, nor is the fine-detail term, `shaders/fine_detail.wgsl`) |
//! | Reinbothe et al. 2009 | §5 voxelization | `voxels/voxelize.wgsl` |
//! | | §6 eq. 2–3, rays through the grid, Wendland's kernel | `voxels/voxel_ao.wgsl`, `shaders/math.wgsl` |
//! | | §7 eq. 5–7, joint bilateral upsampling | `shaders/joint_upsample.wgsl` (window and weights), `filter/upsample.wgsl`, `compose/compose.wgsl` (half-resolution splats) |
//!
//! [`reference`](mod@reference) evaluates the same formulas on the CPU and ray-traces ground truth; the tests,
//! the benchmarks and the `ao_capture` example use it.

#![warn(missing_docs)]

mod capabilities;
pub mod compose;
mod dispatch;
mod draw_pipeline;
pub mod fields;
pub mod filter;
pub mod geometry;
pub mod horizon;
mod image_space;
mod memory;
pub mod nd_buffer;
pub mod near_field;
pub mod ray_march;
pub mod readback;
pub mod reference;
pub mod schedule;
pub mod settings;
pub mod spheres;
pub mod temporal;
mod view;
pub mod voxels;

use bevy::app::{App, Plugin};
use bevy::render::GpuResourceAppExt;
use bevy::shader::load_shader_library;

pub use compose::{AoShown, DynamicAoStatus};
pub use memory::DynamicAoGpuMemory;
pub use settings::{
    AoBlur, AoPreset, AoTechnique, AoTemporal, DynamicAo, FarFieldBlend, FieldShading, HorizonMode,
    HorizonParams, NearFieldParams, RayMarchParams,
};

/// Everything a user of the crate usually needs.
pub mod prelude {
    pub use crate::DynamicAoPlugin;
    pub use crate::compose::{AoShown, DynamicAoStatus};
    pub use crate::fields::{AoField, AoFieldData};
    pub use crate::readback::AoReadback;
    pub use crate::settings::{
        AoBlur, AoPreset, AoTechnique, AoTemporal, DynamicAo, FarFieldBlend, FieldShading,
        HorizonMode, HorizonParams, NearFieldParams, RayMarchParams,
    };
    #[cfg(feature = "gizmos")]
    pub use crate::spheres::ShowOccluderSpheres;
    pub use crate::spheres::{OccluderSpheres, ProxyReach, ProxyShape, SphereOccluder};
    pub use crate::voxels::{
        NotVoxelOccluder, ShowOccupiedVoxels, VoxelAoVolume, VoxelFalloff, VoxelMarch,
    };
}

/// Adds dynamic ambient occlusion to every camera that has a [`DynamicAo`] component.
///
/// Needs Bevy's `bevy_pbr` rendering (it hands its result to the PBR lighting through the
/// binding Bevy uses for its own screen-space AO) and compute shaders with storage textures.
pub struct DynamicAoPlugin;

impl Plugin for DynamicAoPlugin {
    fn build(&self, app: &mut App) {
        load_shader_library!(app, "shaders/nd_buffer.wgsl");
        load_shader_library!(app, "shaders/sampling.wgsl");
        load_shader_library!(app, "shaders/math.wgsl");
        load_shader_library!(app, "shaders/history.wgsl");
        load_shader_library!(app, "shaders/uniform.wgsl");
        load_shader_library!(app, "shaders/image_space_bindings.wgsl");
        load_shader_library!(app, "shaders/sphere_occlusion.wgsl");
        load_shader_library!(app, "shaders/cap_occlusion.wgsl");
        load_shader_library!(app, "shaders/proxy_occlusion.wgsl");
        load_shader_library!(app, "shaders/union_join.wgsl");
        load_shader_library!(app, "shaders/joint_upsample.wgsl");
        load_shader_library!(app, "shaders/filter_output.wgsl");
        load_shader_library!(app, "shaders/fine_detail.wgsl");

        app.register_type::<DynamicAo>()
            .register_type::<readback::AoReadback>()
            .register_type::<compose::DynamicAoStatus>()
            .add_plugins((
                view::ViewPlugin,
                nd_buffer::NdBufferPlugin,
                near_field::NearFieldPlugin,
                horizon::HorizonPlugin,
                ray_march::RayMarchPlugin,
                spheres::SphereOccluderPlugin,
                fields::AoFieldPlugin,
                voxels::VoxelAoPlugin,
                image_space::ImageSpacePlugin,
                temporal::TemporalPlugin,
                filter::FilterPlugin,
                compose::ComposePlugin,
                readback::ReadbackPlugin,
            ));
    }

    fn finish(&self, app: &mut App) {
        memory::insert(app);
        schedule::configure(app);
        if let Some(render_app) = capabilities::render_app(app) {
            render_app.init_gpu_resource::<dispatch::SpanStart>();
        }
    }
}

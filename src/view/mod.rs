//! Per-camera state: main-world checks, extraction into the render world, per-view textures.
//!
//! This module holds what every view has whatever its techniques: the settings, the uniform,
//! the ND-buffer's back layer and the image-space occlusion. Each far-field technique keeps its
//! own per-view state in its folder and meets the rest of the plugin only through three
//! neutral things here: it says whether it has occluders ([`FarTermsPresent`]), it hands its
//! output to compose ([`FarFieldOutputs`]) and it says while its passes are still compiling
//! ([`PendingPasses`]).

use bevy::app::{App, Plugin, PostUpdate};
use bevy::ecs::prelude::*;
use bevy::ecs::system::SystemParam;
use bevy::image::ToExtents;
use bevy::math::UVec2;
use bevy::render::extract_component::ComponentUniforms;
use bevy::render::render_resource::BindingResource;
use bevy::render::view::ViewUniforms;
use bevy::render::{
    ExtractSchedule, Render, RenderSystems,
    camera::ExtractedCamera,
    extract_component::UniformComponentPlugin,
    render_resource::{TextureDescriptor, TextureDimension, TextureFormat, TextureUsages},
    renderer::RenderDevice,
    texture::{CachedTexture, TextureCache},
};

use crate::capabilities;
use crate::schedule::DynamicAoExtract;
use crate::settings::{AoTechnique, DynamicAo};

mod cameras;
mod layers;
mod readiness;
mod uniform;

pub(crate) use layers::{layer_bits, on_every_layer_of};
pub(crate) use readiness::{AoPassesReady, retried, still_compiling};
pub(crate) use uniform::DynamicAoUniform;

/// Format of the back-face normal layer: the same encoding as Bevy's normal prepass.
pub(crate) const NORMAL_FORMAT: TextureFormat = TextureFormat::Rgb10a2Unorm;
/// Format of the back-face depth layer: the same as Bevy's prepass depth.
pub(crate) const DEPTH_FORMAT: TextureFormat = TextureFormat::Depth32Float;
/// Format of the intermediate occlusion buffers (always usable as a storage texture).
pub(crate) const OCCLUSION_FORMAT: TextureFormat = TextureFormat::R32Float;
/// Format of the normals the upsampling writes for the blur: the front layer's, encoded as Bevy's
/// prepass encodes them (`n * 0.5 + 0.5`), in a format every adapter can write from a compute
/// pass.
pub(crate) const BLUR_NORMAL_FORMAT: TextureFormat = TextureFormat::Rgba16Float;
/// Format of two-channel occlusion buffers (the voxel term's: the near field's share and the
/// rest, see `FarFieldBlend`).
pub(crate) const OCCLUSION_PAIR_FORMAT: TextureFormat = TextureFormat::Rg32Float;
/// Format of the far-field visibility buffers: blendable on every adapter (32-bit float blending
/// is optional). Red: visibility left by the occluders the near field would count but cannot
/// see; green: by the rest (see `FarFieldBlend::CountOnce`); alpha (sphere occluders): the
/// largest single occlusion.
pub(crate) const FAR_OCCLUSION_FORMAT: TextureFormat = TextureFormat::Rgba16Float;

pub(crate) struct ViewPlugin;

impl Plugin for ViewPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(PostUpdate, cameras::check_cameras)
            .add_observer(cameras::remove_required_ssao)
            .add_plugins(UniformComponentPlugin::<DynamicAoUniform>::default());
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_resource::<FarTermsPresent>()
            .add_systems(
                ExtractSchedule,
                uniform::extract_views.in_set(DynamicAoExtract::Views),
            )
            .add_systems(
                Render,
                prepare_view_textures.in_set(RenderSystems::PrepareResources),
            );
    }
}

/// A far-field term: one kind of occluder proxy with its own pass, made by the technique folder
/// of the same name and joined by compose.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) enum FarTerm {
    /// Sphere (box) occluders (`spheres/`).
    Spheres,
    /// AO field occluders (`fields/`).
    Fields,
    /// Voxel volumes (`voxels/`).
    Voxels,
}

impl FarTerm {
    const COUNT: usize = 3;
}

/// Whether any occluder of each far-field term exists this frame: each technique's extraction
/// writes its own entry. Without occluders a term's pass, buffer clear and compose read are
/// skipped.
#[derive(Resource, Default)]
pub(crate) struct FarTermsPresent([bool; FarTerm::COUNT]);

impl FarTermsPresent {
    /// Records whether `term` has occluders this frame.
    pub fn set(&mut self, term: FarTerm, present: bool) {
        self.0[term as usize] = present;
    }
}

/// Render-world settings of a view that runs the plugin.
#[derive(Component, Clone, Debug)]
pub(crate) struct DynamicAoView {
    /// The camera's component as the user set it; each technique reads its own settings here.
    pub settings: DynamicAo,
    /// The back-face layer is drawn (its depth).
    pub back_layer: bool,
    /// The back-face layer's normals are drawn too: only the near field reads them. Without,
    /// the layer is depth only, which rasterizes without a fragment shader.
    pub back_normals: bool,
    /// Rigid meshes of many triangles draw the depth-only back-face layer from their coarse
    /// copies ([`crate::DynamicAo::coarse_back_faces`]).
    pub coarse_back_faces: bool,
    /// Blur half-width, pixels (0 = off).
    pub blur_radius: u32,
    /// Occlusion computed at half resolution and upsampled
    /// ([`crate::DynamicAo::half_resolution_at`] the viewport's size).
    pub half_resolution: bool,
    /// The sphere and field splats drawn at half resolution (compose upsamples them).
    pub far_half_resolution: bool,
    /// The image-space occlusion is accumulated over frames (see [`crate::AoTemporal`]).
    pub temporal: bool,
    /// The voxel term is accumulated over frames (see [`crate::AoTemporal`]).
    pub voxel_temporal: bool,
    /// The ray march, accumulated, marches one texel of two each frame
    /// ([`crate::RayMarchParams::checkerboard`]).
    pub checkerboard: bool,
    /// The far-field terms that take part, by [`FarTerm`].
    far_terms: [bool; FarTerm::COUNT],
}

impl DynamicAoView {
    /// The view's technique.
    pub fn technique(&self) -> AoTechnique {
        self.settings.technique
    }

    /// Whether `term` takes part on this view.
    pub fn has(&self, term: FarTerm) -> bool {
        self.far_terms[term as usize]
    }

    /// Whether our passes replace Bevy's SSAO on this view.
    pub fn replaces_bevy_ssao(&self) -> bool {
        self.technique() != AoTechnique::BevySsao
    }

    /// Whether the last filter pass (the blur's Y pass, or the upsampling where the blur is
    /// off) may write the visibility Bevy's PBR reads itself: an image-space technique with a
    /// filter pass and no far-field term, where compose would only copy the filtered occlusion.
    pub fn filter_is_last(&self) -> bool {
        self.technique().is_image_space()
            && !self.far_terms.contains(&true)
            && (self.blur_radius > 0 || self.half_resolution)
    }
}

/// Marks a view whose last filter pass writes the visibility Bevy's PBR reads
/// ([`DynamicAoView::filter_is_last`], once that pass's variant has compiled): compose skips it.
#[derive(Component)]
pub(crate) struct FilterWritesVisibility;

/// Takes a technique's per-view render state `B` (its bind groups, textures, histories) off the
/// views of cameras that no longer run the plugin: their `DynamicAo` was taken away, or they
/// stopped rendering. Extraction drops such a view's [`DynamicAoView`], but the components the
/// techniques inserted stay on the render entity from frame to frame; a pass that still found
/// them would go on running with the last frame's bind groups, after the textures behind them
/// went back to Bevy's texture cache. Each technique registers it for what it inserts.
pub(crate) fn drop_without_ao<B: Bundle>(
    mut commands: Commands,
    views: Query<Entity, (With<ExtractedCamera>, Without<DynamicAoView>)>,
) {
    for entity in &views {
        commands.entity(entity).remove::<B>();
    }
}

/// The far-field output of each term on a view, for compose: the technique that owns the term
/// makes and writes it while the term takes part. Renewed empty at every extraction.
#[derive(Component, Default)]
pub(crate) struct FarFieldOutputs([Option<CachedTexture>; FarTerm::COUNT]);

impl FarFieldOutputs {
    pub fn get(&self, term: FarTerm) -> Option<&CachedTexture> {
        self.0[term as usize].as_ref()
    }

    pub fn set(&mut self, term: FarTerm, texture: CachedTexture) {
        self.0[term as usize] = Some(texture);
    }
}

/// How many of a view's passes have not compiled yet: each technique adds its own (see
/// `DynamicAoPrepare::Readiness`); our passes take over from Bevy's SSAO at 0. Renewed at every
/// extraction.
#[derive(Component, Default)]
pub(crate) struct PendingPasses(u32);

impl PendingPasses {
    /// Counts one pass that has not compiled, unless `ready`.
    pub fn wait_for(&mut self, ready: bool) {
        self.0 += u32::from(!ready);
    }

    pub fn all_ready(&self) -> bool {
        self.0 == 0
    }
}

/// The two uniforms nearly every pass binds first: Bevy's view uniform and ours.
#[derive(SystemParam)]
pub(crate) struct ViewBindings<'w> {
    view_uniforms: Res<'w, ViewUniforms>,
    settings: Res<'w, ComponentUniforms<DynamicAoUniform>>,
}

impl ViewBindings<'_> {
    /// Both bindings, once both buffers exist this frame.
    pub fn get(&self) -> Option<(BindingResource<'_>, BindingResource<'_>)> {
        Some((
            self.view_uniforms.uniforms.binding()?,
            self.settings.binding()?,
        ))
    }
}

/// Per-view textures of the plugin, from Bevy's texture cache.
#[derive(Component)]
pub(crate) struct DynamicAoTextures {
    pub back_depth: CachedTexture,
    pub back_normal: CachedTexture,
    /// The image-space occlusion the filter reads: full size, or half size at half resolution.
    /// The technique pass writes it, or under temporal accumulation the temporal pass does.
    pub near_occlusion: CachedTexture,
    /// Under temporal accumulation, what the technique pass writes (the size of
    /// `near_occlusion`): this frame's value before it joins the history.
    pub raw_occlusion: Option<CachedTexture>,
    /// Full-size occlusion the blur and compose read: `near_occlusion` itself, or its joint
    /// bilateral upsampling at half resolution.
    pub full_occlusion: CachedTexture,
    /// Between the two passes of the blur.
    pub blur_scratch: CachedTexture,
    /// The front layer's normals as the blur weighs by them ([`BLUR_NORMAL_FORMAT`]), copied by
    /// the pass that reads them anyway: the upsampling at half resolution, the image-space
    /// technique at full resolution. On lavapipe the blur's passes, given the prepass's normal
    /// texture itself, were charged 12–15 ms more at 640×480 by the GPU timestamps around them,
    /// whatever they read; given this copy, nothing measurable (BENCHMARKS.md, "The blur weighs
    /// by normals").
    pub blur_normal: CachedTexture,
}

/// The size of a view's image in pixels, `None` while it has none.
pub(crate) fn view_size(camera: &ExtractedCamera) -> Option<UVec2> {
    camera
        .physical_viewport_size
        .filter(|size| size.x > 0 && size.y > 0)
}

/// Half of a view's size, rounded up: the size of half-resolution buffers.
pub(crate) fn half_size(size: UVec2) -> UVec2 {
    (size + 1) / 2
}

/// One per-view 2D texture from Bevy's texture cache (reused across frames while its
/// description stays the same).
pub(crate) fn view_texture(
    texture_cache: &mut TextureCache,
    render_device: &RenderDevice,
    label: &'static str,
    size: UVec2,
    format: TextureFormat,
    usage: TextureUsages,
) -> CachedTexture {
    texture_cache.get(
        render_device,
        TextureDescriptor {
            label: Some(label),
            size: size.to_extents(),
            mip_level_count: 1,
            sample_count: 1,
            dimension: TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        },
    )
}

/// The system that makes the visibility buffer of far-field term `term` (full size, or half size
/// where the view's splats run at half resolution; [`FAR_OCCLUSION_FORMAT`], drawn into) on every view it takes part in, and hands it to compose.
pub(crate) fn prepare_far_visibility(
    term: FarTerm,
    label: &'static str,
) -> impl FnMut(
    ResMut<TextureCache>,
    Res<RenderDevice>,
    Query<(&ExtractedCamera, &DynamicAoView, &mut FarFieldOutputs)>,
) {
    move |mut texture_cache, render_device, mut views| {
        for (camera, view, mut outputs) in &mut views {
            if let (true, Some(size)) = (view.has(term), view_size(camera)) {
                let size = if view.far_half_resolution {
                    half_size(size)
                } else {
                    size
                };
                let usage = TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING;
                let texture = view_texture(
                    &mut texture_cache,
                    &render_device,
                    label,
                    size,
                    FAR_OCCLUSION_FORMAT,
                    usage,
                );
                outputs.set(term, texture);
            }
        }
    }
}

fn prepare_view_textures(
    mut commands: Commands,
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    views: Query<(Entity, &ExtractedCamera, &DynamicAoView)>,
) {
    for (entity, camera, view) in &views {
        let Some(size) = view_size(camera) else {
            commands.entity(entity).remove::<DynamicAoTextures>();
            continue;
        };
        let mut texture = |label, size, format, usage| {
            view_texture(
                &mut texture_cache,
                &render_device,
                label,
                size,
                format,
                usage,
            )
        };
        let attachment = TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING;
        let storage = TextureUsages::STORAGE_BINDING | TextureUsages::TEXTURE_BINDING;
        let near_occlusion = if view.half_resolution {
            texture(
                "dynamic_ao_half_occlusion",
                half_size(size),
                OCCLUSION_FORMAT,
                storage,
            )
        } else {
            texture("dynamic_ao_near_occlusion", size, OCCLUSION_FORMAT, storage)
        };
        let raw_occlusion = view.temporal.then(|| {
            texture(
                "dynamic_ao_raw_occlusion",
                if view.half_resolution {
                    half_size(size)
                } else {
                    size
                },
                OCCLUSION_FORMAT,
                storage,
            )
        });
        let full_occlusion = if view.half_resolution {
            texture("dynamic_ao_full_occlusion", size, OCCLUSION_FORMAT, storage)
        } else {
            near_occlusion.clone()
        };
        let blur_normal = texture("dynamic_ao_blur_normal", size, BLUR_NORMAL_FORMAT, storage);
        commands.entity(entity).insert(DynamicAoTextures {
            back_depth: texture("dynamic_ao_back_depth", size, DEPTH_FORMAT, attachment),
            back_normal: texture("dynamic_ao_back_normal", size, NORMAL_FORMAT, attachment),
            near_occlusion,
            raw_occlusion,
            full_occlusion,
            blur_scratch: texture("dynamic_ao_blur_scratch", size, OCCLUSION_FORMAT, storage),
            blur_normal,
        });
    }
}

//! Per-camera state: main-world checks, extraction into the render world, per-view textures.
//!
//! This module holds what every view has whatever its techniques: the settings, the uniform,
//! the ND-buffer's back layer and the image-space occlusion. Each far-field technique keeps its
//! own per-view state in its folder and meets the rest of the plugin only through three
//! neutral things here: it says whether it has occluders ([`FarTermsPresent`]), it hands its
//! output to compose ([`FarFieldOutputs`]) and it says while its passes are still compiling
//! ([`PendingPasses`]).

use bevy::app::{App, Plugin, PostUpdate};
use bevy::camera::{Camera, Camera3d};
use bevy::ecs::prelude::*;
use bevy::image::ToExtents;
use bevy::log::warn;
use bevy::math::UVec2;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::platform::collections::HashSet;
use bevy::render::{
    Extract, ExtractSchedule, Render, RenderSystems,
    camera::ExtractedCamera,
    extract_component::UniformComponentPlugin,
    render_resource::{
        ShaderType, TextureDescriptor, TextureDimension, TextureFormat, TextureUsages,
    },
    renderer::RenderDevice,
    sync_world::RenderEntity,
    texture::{CachedTexture, TextureCache},
    view::Msaa,
};

use crate::capabilities;
use crate::schedule::DynamicAoExtract;
use crate::settings::{AoTechnique, DynamicAo, FarFieldBlend};

/// Format of the back-face normal layer: the same encoding as Bevy's normal prepass.
pub(crate) const NORMAL_FORMAT: TextureFormat = TextureFormat::Rgb10a2Unorm;
/// Format of the back-face depth layer: the same as Bevy's prepass depth.
pub(crate) const DEPTH_FORMAT: TextureFormat = TextureFormat::Depth32Float;
/// Format of the intermediate occlusion buffers (always usable as a storage texture).
pub(crate) const OCCLUSION_FORMAT: TextureFormat = TextureFormat::R32Float;
/// Format of the far-field visibility buffers: blendable on every adapter (32-bit float blending
/// is optional). Red: visibility left by the occluders the near field would count but cannot
/// see; green: by the rest (see `FarFieldBlend::CountOnce`); alpha (sphere occluders): the
/// largest single occlusion.
pub(crate) const FAR_OCCLUSION_FORMAT: TextureFormat = TextureFormat::Rgba16Float;

pub(crate) struct ViewPlugin;

impl Plugin for ViewPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(PostUpdate, check_cameras)
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
                extract_views.in_set(DynamicAoExtract::Views),
            )
            .add_systems(
                Render,
                prepare_view_textures.in_set(RenderSystems::PrepareResources),
            );
    }
}

/// Why a camera with [`DynamicAo`] renders without it.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
enum Unsupported {
    Msaa,
    EmptyViewport,
}

/// Marks a camera the plugin switched off because its viewport had no pixels: Bevy's renderer
/// rejects zero-size views (a validation error that stops the app), so the camera waits,
/// inactive, until its viewport has pixels again.
#[derive(Component)]
pub(crate) struct SuspendedForEmptyViewport;

/// Cameras the plugin cannot serve lose Bevy's SSAO component (whose pass would fail on them)
/// and get one warning; they get it back once the problem is gone.
fn check_cameras(
    mut commands: Commands,
    mut cameras: Query<
        (
            Entity,
            &mut Camera,
            &Msaa,
            Has<ScreenSpaceAmbientOcclusion>,
            Has<SuspendedForEmptyViewport>,
            Option<&Name>,
        ),
        With<DynamicAo>,
    >,
    mut warned: Local<HashSet<(Entity, Unsupported)>>,
) {
    for (entity, mut camera, msaa, has_ssao, suspended, name) in &mut cameras {
        let empty_viewport = camera
            .viewport
            .as_ref()
            .is_some_and(|v| v.physical_size.x == 0 || v.physical_size.y == 0);
        if empty_viewport && camera.is_active {
            camera.is_active = false;
            commands.entity(entity).insert(SuspendedForEmptyViewport);
        } else if !empty_viewport && suspended {
            camera.is_active = true;
            commands
                .entity(entity)
                .remove::<SuspendedForEmptyViewport>();
        }
        let problem = if *msaa != Msaa::Off {
            Some(Unsupported::Msaa)
        } else if empty_viewport {
            Some(Unsupported::EmptyViewport)
        } else {
            None
        };
        match problem {
            Some(problem) => {
                if warned.insert((entity, problem)) {
                    let label =
                        name.map_or_else(|| format!("{entity}"), |n| format!("'{n}' ({entity})"));
                    match problem {
                        Unsupported::Msaa => warn!(
                            "DynamicAo on camera {label} needs Msaa::Off (it is {msaa:?}); \
                             rendering this camera without ambient occlusion"
                        ),
                        Unsupported::EmptyViewport => warn!(
                            "camera {label} has a zero-size viewport, which Bevy's renderer \
                             rejects; DynamicAo deactivates the camera until the viewport has \
                             pixels"
                        ),
                    }
                }
                if has_ssao {
                    commands
                        .entity(entity)
                        .remove::<ScreenSpaceAmbientOcclusion>();
                }
            }
            None => {
                warned.retain(|(e, _)| *e != entity);
                if !has_ssao {
                    commands
                        .entity(entity)
                        .insert(ScreenSpaceAmbientOcclusion::default());
                }
            }
        }
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
    pub back_layer: bool,
    /// Blur half-width, pixels (0 = off).
    pub blur_radius: u32,
    /// Occlusion computed at half resolution and upsampled.
    pub half_resolution: bool,
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

/// The uniform every pass of a view reads; `DynamicAoUniform` in `shaders/uniform.wgsl`, field
/// for field. Each field is named after the [`DynamicAo`] setting it comes from.
#[derive(Component, ShaderType, Clone, Copy, Debug, Default)]
pub(crate) struct DynamicAoUniform {
    /// Reach of the image-space technique, metres: R, or the near-field radius where the far
    /// field counts the rest.
    pub image_space_radius: f32,
    pub intensity: f32,
    /// [`crate::NearFieldParams`]; `near_field_back_layer` is 1 when the back-face layer
    /// occludes.
    pub near_field_max_samples: u32,
    pub near_field_min_samples: u32,
    pub near_field_back_layer: u32,
    /// 1 when an image-space technique (near field, horizon or ray march) is on.
    pub image_space: u32,
    /// Blur half-width, pixels (0 = off).
    pub blur_radius: u32,
    /// Blur depth sharpness, no unit.
    pub blur_sharpness: f32,
    /// Horizon-based AO parameters (see [`crate::HorizonParams`]).
    pub horizon_directions: u32,
    pub horizon_steps: u32,
    pub horizon_angle_bias: f32,
    pub horizon_attenuation: f32,
    pub horizon_contrast: f32,
    pub horizon_mode: u32,
    /// Ray-marched reference parameters (see [`crate::RayMarchParams`]).
    pub ray_march_directions: u32,
    pub ray_march_elevations: u32,
    pub ray_march_steps: u32,
    /// 1 at full resolution, 2 at half resolution.
    pub resolution_scale: u32,
    /// 1 when sphere occluders take part.
    pub spheres: u32,
    /// 0: near + far, 1: max(near, far) (see [`crate::FarFieldBlend`]).
    pub far_field_blend: u32,
    /// 1 when AO field occluders take part.
    pub fields: u32,
    /// 1 when voxel volumes take part.
    pub voxels: u32,
    /// R ([`DynamicAo::radius`]), metres: every far-field term counts occluders within it.
    pub radius: f32,
    /// Under [`crate::FarFieldBlend::CountOnce`] with an image-space technique:
    /// [`DynamicAo::near_field_radius`], metres; far-field terms leave out the occluders within
    /// it that the ND-buffer holds. 0 where the far field counts every occluder.
    pub near_field_radius: f32,
    /// 1 when the back-face layer is drawn: the ND-buffer holds the first solid interval of each
    /// pixel, front layer to back layer, not only the front surface.
    pub seen_back_layer: u32,
}

fn extract_views(
    mut commands: Commands,
    cameras: Extract<
        Query<
            (
                RenderEntity,
                &Camera,
                &DynamicAo,
                &Msaa,
                Has<ScreenSpaceAmbientOcclusion>,
            ),
            With<Camera3d>,
        >,
    >,
    present: Res<FarTermsPresent>,
) {
    for (entity, camera, ao, msaa, has_ssao) in &cameras {
        let mut entity_commands = commands.entity(entity);
        if !camera.is_active || *msaa != Msaa::Off || !has_ssao {
            entity_commands.remove::<(
                DynamicAoView,
                DynamicAoUniform,
                FarFieldOutputs,
                PendingPasses,
            )>();
            continue;
        }
        let params = ao.near_field.sanitized();
        let blur = ao.blur.sanitized();
        let near_field = ao.technique == AoTechnique::NearField;
        let image_space =
            near_field || matches!(ao.technique, AoTechnique::Horizon | AoTechnique::RayMarch);
        let horizon = ao.horizon.sanitized();
        let rays = ao.ray_march.sanitized();
        // Bevy's own SSAO writes the AO texture itself, so nothing can be added to it.
        let term = |term: FarTerm, on: bool| {
            on && present.0[term as usize] && ao.technique != AoTechnique::BevySsao
        };
        let far_terms = [
            term(FarTerm::Spheres, ao.spheres),
            term(FarTerm::Fields, ao.fields),
            term(FarTerm::Voxels, ao.voxels),
        ];
        let [spheres, fields, voxels] = far_terms;
        // Under CountOnce the image-space technique counts what the ND-buffer shows within its
        // own reach, and the far field everything else within R.
        let radius = ao.effective_radius();
        let count_once = image_space
            && far_terms.contains(&true)
            && ao.far_field_blend == FarFieldBlend::CountOnce;
        let near_radius = if count_once {
            radius.min(ao.effective_near_field_radius())
        } else {
            radius
        };
        let back_layer = (near_field && params.back_layer) || ao.technique == AoTechnique::RayMarch;
        entity_commands.insert((
            DynamicAoView {
                settings: ao.clone(),
                back_layer,
                blur_radius: if image_space { blur.radius } else { 0 },
                half_resolution: image_space && ao.half_resolution,
                far_terms,
            },
            FarFieldOutputs::default(),
            PendingPasses::default(),
            DynamicAoUniform {
                image_space_radius: near_radius,
                intensity: ao.effective_intensity(),
                near_field_max_samples: params.max_samples,
                near_field_min_samples: params.min_samples,
                near_field_back_layer: u32::from(params.back_layer),
                image_space: u32::from(image_space),
                blur_radius: blur.radius,
                blur_sharpness: blur.sharpness,
                horizon_directions: horizon.directions,
                horizon_steps: horizon.steps,
                horizon_angle_bias: horizon.angle_bias,
                horizon_attenuation: horizon.attenuation,
                horizon_contrast: horizon.contrast,
                horizon_mode: horizon.mode.shader_index(),
                ray_march_directions: rays.directions,
                ray_march_elevations: rays.elevations,
                ray_march_steps: rays.steps,
                resolution_scale: if ao.half_resolution { 2 } else { 1 },
                spheres: u32::from(spheres),
                far_field_blend: ao.far_field_blend.shader_index(),
                fields: u32::from(fields),
                voxels: u32::from(voxels),
                radius,
                near_field_radius: if count_once { near_radius } else { 0.0 },
                seen_back_layer: u32::from(back_layer),
            },
        ));
    }
}

/// Per-view textures of the plugin, from Bevy's texture cache.
#[derive(Component)]
pub(crate) struct DynamicAoTextures {
    pub back_depth: CachedTexture,
    pub back_normal: CachedTexture,
    /// What the technique pass writes: full size, or half size at half resolution.
    pub near_occlusion: CachedTexture,
    /// Full-size occlusion the blur and compose read: `near_occlusion` itself, or its joint
    /// bilateral upsampling at half resolution.
    pub full_occlusion: CachedTexture,
    /// Between the two passes of the blur.
    pub blur_scratch: CachedTexture,
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

/// The system that makes the visibility buffer of far-field term `term` (full size,
/// [`FAR_OCCLUSION_FORMAT`], drawn into) on every view it takes part in, and hands it to compose.
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
        let full_occlusion = if view.half_resolution {
            texture("dynamic_ao_full_occlusion", size, OCCLUSION_FORMAT, storage)
        } else {
            near_occlusion.clone()
        };
        commands.entity(entity).insert(DynamicAoTextures {
            back_depth: texture("dynamic_ao_back_depth", size, DEPTH_FORMAT, attachment),
            back_normal: texture("dynamic_ao_back_normal", size, NORMAL_FORMAT, attachment),
            near_occlusion,
            full_occlusion,
            blur_scratch: texture("dynamic_ao_blur_scratch", size, OCCLUSION_FORMAT, storage),
        });
    }
}

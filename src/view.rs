//! Per-camera state: main-world checks, extraction into the render world, per-view textures.

use bevy::app::{App, Plugin, PostUpdate};
use bevy::camera::{Camera, Camera3d};
use bevy::ecs::prelude::*;
use bevy::image::ToExtents;
use bevy::log::warn;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::platform::collections::HashSet;
use bevy::render::{
    Extract, ExtractSchedule, Render, RenderApp, RenderSystems,
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

use crate::fields::ActiveAoField;
use crate::filter::OCCLUSION_PAIR_FORMAT;
use crate::settings::{AoTechnique, DynamicAo, FarFieldBlend};
use crate::spheres::OccluderSpheres;
use crate::voxels::VoxelGridInfo;

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
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .add_systems(ExtractSchedule, extract_views)
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

/// Render-world settings of a view that runs the plugin.
#[derive(Component, Clone, Debug)]
pub(crate) struct DynamicAoView {
    pub technique: AoTechnique,
    pub back_layer: bool,
    /// Blur half-width, pixels (0 = off).
    pub blur_radius: u32,
    /// Occlusion computed at half resolution and upsampled.
    pub half_resolution: bool,
    /// The far field of sphere occluders takes part.
    pub far_field: bool,
    /// AO field occluders take part.
    pub fields: bool,
    pub field_shading: crate::settings::FieldShading,
    /// Voxel volumes take part.
    pub voxels: bool,
    /// The voxel occlusion is blurred after upsampling.
    pub voxel_blur: bool,
    pub debug_view: bool,
}

impl DynamicAoView {
    /// Whether our passes replace Bevy's SSAO on this view.
    pub fn replaces_bevy_ssao(&self) -> bool {
        self.technique != AoTechnique::BevySsao
    }
}

/// The uniform every pass of a view reads.
#[derive(Component, ShaderType, Clone, Copy, Debug, Default)]
pub(crate) struct DynamicAoUniform {
    /// Reach of the image-space technique, metres: R, or the near-field radius where the far
    /// field counts the rest.
    pub radius: f32,
    pub intensity: f32,
    pub max_samples: u32,
    pub min_samples: u32,
    /// 1 when the back-face layer takes part.
    pub back_layer: u32,
    /// 1 when an image-space term (near-field or horizon) is on.
    pub near_field: u32,
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
    pub ray_directions: u32,
    pub ray_elevations: u32,
    pub ray_steps: u32,
    /// 1 at full resolution, 2 at half resolution.
    pub resolution_scale: u32,
    /// 1 when the far field of sphere occluders takes part.
    pub far_field: u32,
    /// 0: near + far, 1: max(near, far) (see [`crate::FarFieldBlend`]).
    pub far_field_blend: u32,
    /// 1 when AO field occluders take part.
    pub fields: u32,
    /// 1 when voxel volumes take part.
    pub voxels: u32,
    /// R, metres: every far-field term counts occluders within this distance.
    pub far_radius: f32,
    /// Under [`crate::FarFieldBlend::CountOnce`] with an image-space technique: the near field's
    /// reach, metres; far-field terms leave out the occluders within it that the ND-buffer holds.
    /// 0 where the far field counts every occluder.
    pub far_near_radius: f32,
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
    sphere_occluders: Extract<Query<(), With<OccluderSpheres>>>,
    field_occluders: Extract<Query<(), With<ActiveAoField>>>,
    voxel_volumes: Extract<Query<(), With<VoxelGridInfo>>>,
) {
    // Without occluders of a kind its pass, buffer clear and compose read are skipped.
    let any_spheres = !sphere_occluders.is_empty();
    let any_fields = !field_occluders.is_empty();
    let any_volumes = !voxel_volumes.is_empty();
    for (entity, camera, ao, msaa, has_ssao) in &cameras {
        let mut entity_commands = commands.entity(entity);
        if !camera.is_active || *msaa != Msaa::Off || !has_ssao {
            entity_commands.remove::<(DynamicAoView, DynamicAoUniform)>();
            continue;
        }
        let params = ao.quality.params();
        let blur = ao.blur.sanitized();
        let near_field = ao.technique == AoTechnique::NearField;
        let image_space =
            near_field || matches!(ao.technique, AoTechnique::Horizon | AoTechnique::RayMarch);
        let horizon = ao.horizon.sanitized();
        let rays = ao.ray_march.sanitized();
        // Bevy's own SSAO writes the AO texture itself, so nothing can be added to it.
        let far_field = ao.spheres && any_spheres && ao.technique != AoTechnique::BevySsao;
        let fields = ao.fields && any_fields && ao.technique != AoTechnique::BevySsao;
        let voxels = ao.voxels && any_volumes && ao.technique != AoTechnique::BevySsao;
        // Under CountOnce the image-space technique counts what the ND-buffer shows within its
        // own reach, and the far field everything else within R.
        let radius = ao.effective_radius();
        let count_once = image_space
            && (far_field || fields || voxels)
            && ao.far_field_blend == FarFieldBlend::CountOnce;
        let near_radius = if count_once {
            radius.min(ao.effective_near_field_radius())
        } else {
            radius
        };
        let back_layer = (near_field && params.back_layer) || ao.technique == AoTechnique::RayMarch;
        entity_commands.insert((
            DynamicAoView {
                technique: ao.technique,
                back_layer,
                blur_radius: if image_space { blur.radius } else { 0 },
                half_resolution: image_space && ao.half_resolution,
                far_field,
                fields,
                field_shading: ao.field_shading,
                voxels,
                voxel_blur: voxels && blur.radius > 0,
                debug_view: ao.debug_view,
            },
            DynamicAoUniform {
                radius: near_radius,
                intensity: ao.effective_intensity(),
                max_samples: params.max_samples,
                min_samples: params.min_samples,
                back_layer: u32::from(params.back_layer),
                near_field: u32::from(image_space),
                blur_radius: blur.radius,
                blur_sharpness: blur.sharpness,
                horizon_directions: horizon.directions,
                horizon_steps: horizon.steps,
                horizon_angle_bias: horizon.angle_bias,
                horizon_attenuation: horizon.attenuation,
                horizon_contrast: horizon.contrast,
                horizon_mode: horizon.mode.shader_index(),
                ray_directions: rays.directions,
                ray_elevations: rays.rays_per_direction,
                ray_steps: rays.steps,
                resolution_scale: if ao.half_resolution { 2 } else { 1 },
                far_field: u32::from(far_field),
                far_field_blend: ao.far_field_blend.shader_index(),
                fields: u32::from(fields),
                voxels: u32::from(voxels),
                far_radius: radius,
                far_near_radius: if count_once { near_radius } else { 0.0 },
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
    /// Product of the sphere occluders' visibilities, full size.
    pub sphere_visibility: CachedTexture,
    /// Product of the AO field occluders' visibilities, full size.
    pub field_visibility: CachedTexture,
    /// Voxel occlusion as sampled (half size), and upsampled and filtered (full size); only
    /// while voxel volumes take part.
    pub voxel_low: Option<CachedTexture>,
    pub voxel_occlusion: Option<CachedTexture>,
    /// Between the two passes of the voxel blur.
    pub voxel_scratch: Option<CachedTexture>,
}

fn prepare_view_textures(
    mut commands: Commands,
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    views: Query<(Entity, &ExtractedCamera, &DynamicAoView)>,
) {
    for (entity, camera, view) in &views {
        let Some(size) = camera
            .physical_viewport_size
            .filter(|size| size.x > 0 && size.y > 0)
        else {
            commands.entity(entity).remove::<DynamicAoTextures>();
            continue;
        };
        let full = size.to_extents();
        let mut texture = |label, size, format, usage| {
            texture_cache.get(
                &render_device,
                TextureDescriptor {
                    label: Some(label),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                },
            )
        };
        let attachment = TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING;
        let storage = TextureUsages::STORAGE_BINDING | TextureUsages::TEXTURE_BINDING;
        let near_occlusion = if view.half_resolution {
            texture(
                "dynamic_ao_half_occlusion",
                ((size + 1) / 2).to_extents(),
                OCCLUSION_FORMAT,
                storage,
            )
        } else {
            texture("dynamic_ao_near_occlusion", full, OCCLUSION_FORMAT, storage)
        };
        let full_occlusion = if view.half_resolution {
            texture("dynamic_ao_full_occlusion", full, OCCLUSION_FORMAT, storage)
        } else {
            near_occlusion.clone()
        };
        let half = ((size + 1) / 2).to_extents();
        // Voxel occlusion has two channels: the near field's share and the rest.
        let (voxel_low, voxel_occlusion, voxel_scratch) = if view.voxels {
            (
                Some(texture(
                    "dynamic_ao_voxel_low",
                    half,
                    OCCLUSION_PAIR_FORMAT,
                    storage,
                )),
                Some(texture(
                    "dynamic_ao_voxel_occlusion",
                    full,
                    OCCLUSION_PAIR_FORMAT,
                    storage,
                )),
                view.voxel_blur.then(|| {
                    texture(
                        "dynamic_ao_voxel_scratch",
                        full,
                        OCCLUSION_PAIR_FORMAT,
                        storage,
                    )
                }),
            )
        } else {
            (None, None, None)
        };
        commands.entity(entity).insert(DynamicAoTextures {
            back_depth: texture("dynamic_ao_back_depth", full, DEPTH_FORMAT, attachment),
            back_normal: texture("dynamic_ao_back_normal", full, NORMAL_FORMAT, attachment),
            near_occlusion,
            full_occlusion,
            blur_scratch: texture("dynamic_ao_blur_scratch", full, OCCLUSION_FORMAT, storage),
            sphere_visibility: texture(
                "dynamic_ao_sphere_visibility",
                full,
                FAR_OCCLUSION_FORMAT,
                attachment,
            ),
            field_visibility: texture(
                "dynamic_ao_field_visibility",
                full,
                FAR_OCCLUSION_FORMAT,
                attachment,
            ),
            voxel_low,
            voxel_occlusion,
            voxel_scratch,
        });
    }
}

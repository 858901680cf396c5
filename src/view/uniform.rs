//! Extraction of each camera's settings into its render-world view: the neutral
//! [`DynamicAoView`](super::DynamicAoView) and the uniform every pass reads.

use bevy::camera::{Camera, Camera3d, visibility::RenderLayers};
use bevy::ecs::prelude::*;
use bevy::math::UVec2;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::render::{
    Extract, extract_component::DynamicUniformIndex, render_resource::ShaderType,
    sync_world::RenderEntity, view::Msaa,
};

use crate::settings::{AoTechnique, DynamicAo, FarFieldBlend, SMALL_VIEWPORT_BLUR_RADIUS};

use super::layers::layer_bits;
use super::{DynamicAoView, FarFieldOutputs, FarTerm, FarTermsPresent, PendingPasses};

/// The uniform every pass of a view reads; `DynamicAoUniform` in `shaders/uniform.wgsl`, field
/// for field. Each field is named after the [`DynamicAo`] setting it comes from.
#[derive(Component, ShaderType, Clone, Copy, Debug, Default)]
pub(crate) struct DynamicAoUniform {
    /// Reach of the image-space technique, metres: R, or the near-field radius where the far
    /// field counts the rest.
    pub image_space_radius: f32,
    pub intensity: f32,
    /// [`crate::NearFieldParams`]; `near_field_back_layer` is 1 when the near field runs with
    /// the back-face layer, the one case that draws the layer's normals.
    pub near_field_max_samples: u32,
    pub near_field_min_samples: u32,
    pub near_field_back_layer: u32,
    /// 1 when an image-space technique (near field, horizon or ray march) is on.
    pub image_space: u32,
    /// Blur half-width, pixels (0 = off).
    pub blur_radius: u32,
    /// Blur depth sharpness, no unit.
    pub blur_sharpness: f32,
    /// Blur normal sharpness, no unit (see [`crate::AoBlur::normal_sharpness`]).
    pub blur_normal_sharpness: f32,
    /// Reach of the fine-detail term the blur's Y pass adds (all four sides, without temporal
    /// accumulation), pixels; 0 where it does not apply (see [`crate::AoBlur::detail_reach`]).
    pub blur_detail_reach: u32,
    /// Reach of the fine-detail term the ray march adds itself, one side a frame, under temporal
    /// accumulation, pixels; 0 elsewhere.
    pub march_detail_reach: u32,
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
    /// How far behind the back-face layer a step of the ray march still counts as blocked,
    /// metres ([`crate::RayMarchParams::thickness`] × the image-space radius).
    pub ray_march_thickness: f32,
    /// 1 when the ray march marches one texel of two each frame
    /// ([`crate::RayMarchParams::checkerboard`]).
    pub ray_march_checkerboard: u32,
    /// Pixels per texel of the sphere and field splats' buffers in each axis: 1, or 2 where they
    /// run at half resolution (compose upsamples them).
    pub far_resolution_scale: u32,
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
    /// The frame's place in the sample pattern's sequence (see [`crate::AoTemporal`]): under
    /// temporal accumulation the frames since the view's history began (counted by the temporal
    /// module, which starts it over with the history), 0 without.
    pub frame_index: u32,
    /// Frames the temporal history averages, 1 without accumulation: the near field sizes its
    /// sample spheres for the whole accumulated budget.
    pub temporal_frames: f32,
    /// Blur half-width of the voxel term, pixels (0 = off; [`crate::AoBlur::voxel_radius`]).
    pub voxel_blur_radius: u32,
    /// Where the camera's viewport starts in its render target, pixels.
    pub viewport_origin: UVec2,
    /// The camera's `RenderLayers` as bits (see [`layer_bits`]): far-field occluders on none of
    /// them cast nothing on this view.
    pub render_layers: UVec2,
}

/// The render-world components a view has while it runs the plugin; each technique drops its
/// own state on views without [`DynamicAoView`] (`view::drop_without_ao`). Bevy inserts the
/// uniform's index each frame a view has the uniform, and never takes it away.
type ViewState = (
    DynamicAoView,
    DynamicAoUniform,
    DynamicUniformIndex<DynamicAoUniform>,
    FarFieldOutputs,
    PendingPasses,
    super::DynamicAoTextures,
);

pub(super) fn extract_views(
    mut commands: Commands,
    cameras: Extract<
        Query<
            (
                RenderEntity,
                &Camera,
                &DynamicAo,
                &Msaa,
                Has<ScreenSpaceAmbientOcclusion>,
                Option<&RenderLayers>,
            ),
            With<Camera3d>,
        >,
    >,
    // Render-world views persist across frames: a camera whose `DynamicAo` was taken away must
    // lose its view state here, or our passes would go on with its last settings.
    without: Extract<Query<RenderEntity, (With<Camera3d>, Without<DynamicAo>)>>,
    present: Res<FarTermsPresent>,
) {
    for entity in &without {
        commands.entity(entity).remove::<ViewState>();
    }
    for (entity, camera, ao, msaa, has_ssao, layers) in &cameras {
        let mut entity_commands = commands.entity(entity);
        // An MSAA camera has no Bevy SSAO component in the main world; compose gives its view
        // one (see `compose::ssao_slot`).
        let msaa_served = *msaa != Msaa::Off && ao.works_with_msaa();
        if !camera.is_active || !(has_ssao || msaa_served) {
            entity_commands.remove::<ViewState>();
            continue;
        }
        let params = ao.near_field.sanitized();
        let mut blur = ao.blur.sanitized();
        let near_field = ao.technique == AoTechnique::NearField;
        let image_space = ao.technique.is_image_space();
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
        let temporal = image_space && ao.temporal.enabled;
        let voxel_temporal = voxels && ao.temporal.enabled;
        let voxel_blur_radius = blur.voxel_radius(voxel_temporal);
        // A viewport Bevy has not sized yet has no texture to run on; its size is checked again
        // where the textures are made.
        let viewport = camera.physical_viewport_size().unwrap_or_default();
        let half_resolution = ao.half_resolution_at(viewport);
        if temporal {
            blur.radius = blur.accumulated_radius;
            // A small viewport asked for half resolution runs at full resolution, where no
            // upsampling averages the texels around each pixel: the blur's smallest radius does.
            if ao.half_resolution && !half_resolution && blur.radius == 0 {
                blur.radius = SMALL_VIEWPORT_BLUR_RADIUS;
            }
        }
        // Accumulated, the ray march adds the fine-detail term itself, a side a frame; else the
        // blur's last pass adds all four sides.
        let detail_reach = if ao.technique == AoTechnique::RayMarch {
            blur.detail_reach
        } else {
            0
        };
        let (march_detail_reach, blur_detail_reach) = match temporal {
            true => (detail_reach, 0),
            false => (0, detail_reach),
        };
        let checkerboard = ao.marches_checkerboard();
        let back_normals = near_field && params.back_layer;
        let back_layer = back_normals || ao.technique == AoTechnique::RayMarch;
        entity_commands.insert((
            DynamicAoView {
                settings: ao.clone(),
                back_layer,
                back_normals,
                coarse_back_faces: back_layer && !back_normals && ao.coarse_back_faces,
                blur_radius: if image_space { blur.radius } else { 0 },
                half_resolution: image_space && half_resolution,
                far_half_resolution: half_resolution,
                temporal,
                voxel_temporal,
                checkerboard,
                far_terms,
            },
            FarFieldOutputs::default(),
            PendingPasses::default(),
            DynamicAoUniform {
                image_space_radius: near_radius,
                intensity: ao.effective_intensity(),
                near_field_max_samples: params.max_samples,
                near_field_min_samples: params.min_samples,
                near_field_back_layer: u32::from(back_normals),
                image_space: u32::from(image_space),
                blur_radius: blur.radius,
                blur_sharpness: blur.sharpness,
                blur_normal_sharpness: blur.normal_sharpness,
                blur_detail_reach,
                march_detail_reach,
                horizon_directions: horizon.directions,
                horizon_steps: horizon.steps,
                horizon_angle_bias: horizon.angle_bias,
                horizon_attenuation: horizon.attenuation,
                horizon_contrast: horizon.contrast,
                horizon_mode: horizon.mode.shader_index(),
                ray_march_directions: rays.directions,
                ray_march_elevations: rays.elevations,
                ray_march_steps: rays.steps,
                ray_march_thickness: rays.thickness * near_radius,
                ray_march_checkerboard: u32::from(checkerboard),
                far_resolution_scale: if half_resolution { 2 } else { 1 },
                spheres: u32::from(spheres),
                far_field_blend: ao.far_field_blend.shader_index(),
                fields: u32::from(fields),
                voxels: u32::from(voxels),
                radius,
                near_field_radius: if count_once { near_radius } else { 0.0 },
                seen_back_layer: u32::from(back_layer),
                frame_index: u32::from(temporal || voxel_temporal),
                temporal_frames: if temporal {
                    ao.temporal.frames() as f32
                } else {
                    1.0
                },
                voxel_blur_radius,
                viewport_origin: camera
                    .viewport
                    .as_ref()
                    .map_or(UVec2::ZERO, |viewport| viewport.physical_position),
                render_layers: layer_bits(layers),
            },
        ));
    }
}

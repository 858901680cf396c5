//! The pipeline and bind groups of the read-back copy.

use crate::nd_buffer::FrontLayer;
use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::log::warn_once;
use bevy::pbr::ScreenSpaceAmbientOcclusionResources;
use bevy::render::{
    camera::ExtractedCamera,
    extract_component::ComponentUniforms,
    render_asset::RenderAssets,
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::RenderDevice,
    texture::GpuImage,
};
use bevy::shader::ShaderDefVal;
use bevy::utils::default;

use super::AoReadback;
use crate::compose::{ParkedSsao, visibility_texture};
use crate::view::{DynamicAoTextures, DynamicAoUniform};

#[derive(Resource)]
pub(crate) struct ReadbackPipeline {
    layout: BindGroupLayoutDescriptor,
    /// Copies the view's AO as it is.
    pub(super) pipeline: CachedComputePipelineId,
    /// Writes −1 for the AO: on frames where nothing wrote the view's AO texture.
    pub(super) not_written: CachedComputePipelineId,
}

impl FromWorld for ReadbackPipeline {
    fn from_world(world: &mut World) -> Self {
        let float = || texture_2d(TextureSampleType::Float { filterable: false });
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_readback_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    float(),
                    texture_depth_2d(),
                    float(),
                    texture_depth_2d(),
                    float(),
                    texture_storage_2d(TextureFormat::R32Float, StorageTextureAccess::WriteOnly),
                    texture_storage_2d(TextureFormat::Rgba32Float, StorageTextureAccess::WriteOnly),
                    texture_storage_2d(TextureFormat::Rgba32Float, StorageTextureAccess::WriteOnly),
                    uniform_buffer::<DynamicAoUniform>(true),
                ),
            ),
        );
        let shader = load_embedded_asset!(world, "readback.wgsl");
        let cache = world.resource::<PipelineCache>();
        let queue = |label: &'static str, shader_defs: Vec<ShaderDefVal>| {
            cache.queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(label.into()),
                layout: vec![layout.clone()],
                shader: shader.clone(),
                shader_defs,
                ..default()
            })
        };
        let pipeline = queue("dynamic_ao_readback_pipeline", vec![]);
        let not_written = queue(
            "dynamic_ao_readback_not_written_pipeline",
            vec!["AO_NOT_WRITTEN".into()],
        );
        Self {
            layout,
            pipeline,
            not_written,
        }
    }
}

#[derive(Component)]
pub(crate) struct ReadbackBindGroup(pub(super) BindGroup);

pub(crate) fn prepare_readback_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<ReadbackPipeline>,
    pipeline_cache: Res<PipelineCache>,
    images: Res<RenderAssets<GpuImage>>,
    views: Query<(
        Entity,
        &AoReadback,
        &DynamicAoTextures,
        FrontLayer,
        (
            Option<&ScreenSpaceAmbientOcclusionResources>,
            Option<&ParkedSsao>,
        ),
        &ExtractedCamera,
    )>,
    settings: Res<ComponentUniforms<DynamicAoUniform>>,
) {
    let Some(settings) = settings.binding() else {
        return;
    };
    for (entity, readback, textures, prepass, (resources, parked), camera) in &views {
        let Some(ssao) = visibility_texture(resources, parked) else {
            continue;
        };
        let (Some(visibility), Some(front), Some(back)) = (
            images.get(&readback.visibility),
            images.get(&readback.front),
            images.get(&readback.back),
        ) else {
            continue;
        };
        let (Some(depth), Some(normal), Some(size)) = (
            prepass.depth(),
            prepass.normal(),
            camera.physical_viewport_size,
        ) else {
            continue;
        };
        if [visibility, front, back]
            .iter()
            .any(|image| image.size_2d() != size)
        {
            warn_once!("AoReadback images must have the camera's viewport size ({size}); skipping");
            continue;
        }
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_readback_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::sequential((
                &ssao.default_view,
                depth,
                normal,
                &textures.back_depth.default_view,
                &textures.back_normal.default_view,
                &visibility.texture_view,
                &front.texture_view,
                &back.texture_view,
                settings.clone(),
            )),
        );
        commands
            .entity(entity)
            .insert(ReadbackBindGroup(bind_group));
    }
}

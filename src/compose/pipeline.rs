//! Pipeline and bind groups of the compose pass.

use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::pbr::ScreenSpaceAmbientOcclusionResources;
use bevy::render::{
    extract_component::ComponentUniforms,
    render_resource::{
        binding_types::{texture_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::{RenderAdapter, RenderDevice},
};
use bevy::utils::default;

use super::{ParkedSsao, visibility_texture};
use crate::view::{DynamicAoTextures, DynamicAoUniform, DynamicAoView, FarFieldOutputs, FarTerm};

#[derive(Resource)]
pub(crate) struct ComposePipeline {
    pub layout: BindGroupLayoutDescriptor,
    pub pipeline: CachedComputePipelineId,
}

/// The format Bevy gives its SSAO texture: R16Float where the adapter can store to it.
pub(crate) fn bevy_ssao_format(adapter: &RenderAdapter) -> TextureFormat {
    if adapter
        .get_texture_format_features(TextureFormat::R16Float)
        .allowed_usages
        .contains(TextureUsages::STORAGE_BINDING)
    {
        TextureFormat::R16Float
    } else {
        TextureFormat::R32Float
    }
}

impl FromWorld for ComposePipeline {
    fn from_world(world: &mut World) -> Self {
        let format = bevy_ssao_format(world.resource::<RenderAdapter>());
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_compose_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    uniform_buffer::<DynamicAoUniform>(true),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_storage_2d(format, StorageTextureAccess::WriteOnly),
                ),
            ),
        );
        let mut shader_defs = Vec::new();
        if format == TextureFormat::R16Float {
            shader_defs.push("VISIBILITY_R16FLOAT".into());
        }
        let pipeline =
            world
                .resource::<PipelineCache>()
                .queue_compute_pipeline(ComputePipelineDescriptor {
                    label: Some("dynamic_ao_compose_pipeline".into()),
                    layout: vec![layout.clone()],
                    shader: load_embedded_asset!(world, "compose.wgsl"),
                    shader_defs,
                    ..default()
                });
        Self { layout, pipeline }
    }
}

#[derive(Component)]
pub(crate) struct ComposeBindGroup(pub BindGroup);

pub(crate) fn prepare_compose_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<ComposePipeline>,
    pipeline_cache: Res<PipelineCache>,
    settings: Res<ComponentUniforms<DynamicAoUniform>>,
    views: Query<
        (
            Entity,
            &DynamicAoTextures,
            &FarFieldOutputs,
            Option<&ScreenSpaceAmbientOcclusionResources>,
            Option<&ParkedSsao>,
        ),
        With<DynamicAoView>,
    >,
) {
    let Some(settings_binding) = settings.binding() else {
        return;
    };
    for (entity, textures, outputs, resources, parked) in &views {
        let Some(visibility) = visibility_texture(resources, parked) else {
            commands.entity(entity).remove::<ComposeBindGroup>();
            continue;
        };
        // Compose reads a term's binding only while the term takes part; otherwise any float
        // texture of the view fits.
        let far = |term| {
            &outputs
                .get(term)
                .unwrap_or(&textures.full_occlusion)
                .default_view
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_compose_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::sequential((
                settings_binding.clone(),
                &textures.full_occlusion.default_view,
                far(FarTerm::Spheres),
                far(FarTerm::Fields),
                far(FarTerm::Voxels),
                &visibility.default_view,
            )),
        );
        commands.entity(entity).insert(ComposeBindGroup(bind_group));
    }
}

//! Pipeline and bind groups of the compose pass.

use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::pbr::ScreenSpaceAmbientOcclusionResources;
use bevy::render::{
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::{RenderAdapter, RenderDevice},
    view::ViewUniform,
};
use bevy::utils::default;

use super::{ParkedSsao, visibility_texture};
use crate::nd_buffer::FrontLayer;
use crate::view::{
    DynamicAoTextures, DynamicAoUniform, DynamicAoView, FarFieldOutputs, FarTerm, ViewBindings,
};

#[derive(Resource)]
pub(crate) struct ComposePipeline {
    pub layout: BindGroupLayoutDescriptor,
    /// Every term's buffer at the view's size.
    pub pipeline: CachedComputePipelineId,
    /// The sphere and field splats at half resolution, upsampled on the way.
    pub upsampling: CachedComputePipelineId,
}

impl ComposePipeline {
    /// The variant `view` needs.
    pub fn for_view(&self, view: &DynamicAoView) -> CachedComputePipelineId {
        let splats = view.has(FarTerm::Spheres) || view.has(FarTerm::Fields);
        if view.far_half_resolution && splats {
            self.upsampling
        } else {
            self.pipeline
        }
    }

    /// Whether both variants have compiled.
    pub fn ready(&self, cache: &PipelineCache) -> bool {
        [self.pipeline, self.upsampling]
            .iter()
            .all(|id| cache.get_compute_pipeline(*id).is_some())
    }
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
                    // The view and the front layer, to upsample half-resolution splats.
                    uniform_buffer::<ViewUniform>(true),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                ),
            ),
        );
        let shader = load_embedded_asset!(world, "compose.wgsl");
        let queue = |label: &str, upsample: bool| {
            let mut shader_defs = Vec::new();
            if format == TextureFormat::R16Float {
                shader_defs.push("VISIBILITY_R16FLOAT".into());
            }
            if upsample {
                shader_defs.push("UPSAMPLE_SPLATS".into());
            }
            world
                .resource::<PipelineCache>()
                .queue_compute_pipeline(ComputePipelineDescriptor {
                    label: Some(label.to_string().into()),
                    layout: vec![layout.clone()],
                    shader: shader.clone(),
                    shader_defs,
                    ..default()
                })
        };
        let pipeline = queue("dynamic_ao_compose_pipeline", false);
        let upsampling = queue("dynamic_ao_compose_upsampling_pipeline", true);
        Self {
            layout,
            pipeline,
            upsampling,
        }
    }
}

#[derive(Component)]
pub(crate) struct ComposeBindGroup(pub BindGroup);

pub(crate) fn prepare_compose_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<ComposePipeline>,
    pipeline_cache: Res<PipelineCache>,
    bindings: ViewBindings,
    views: Query<
        (
            Entity,
            &DynamicAoTextures,
            &FarFieldOutputs,
            Option<&ScreenSpaceAmbientOcclusionResources>,
            Option<&ParkedSsao>,
            FrontLayer,
        ),
        With<DynamicAoView>,
    >,
) {
    let Some((view_binding, settings_binding)) = bindings.get() else {
        return;
    };
    for (entity, textures, outputs, resources, parked, prepass) in &views {
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
                view_binding.clone(),
                // Read only where a splat ran at half resolution, which needs the front layer.
                prepass.depth().unwrap_or(&textures.back_depth.default_view),
                prepass
                    .normal()
                    .unwrap_or(&textures.full_occlusion.default_view),
            )),
        );
        commands.entity(entity).insert(ComposeBindGroup(bind_group));
    }
}

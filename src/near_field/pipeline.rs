//! Pipeline and bind groups of the near-field pass.

use bevy::asset::load_embedded_asset;
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::ecs::prelude::*;
use bevy::render::{
    extract_component::ComponentUniforms,
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::RenderDevice,
    view::{ViewUniform, ViewUniforms},
};
use bevy::utils::default;

use crate::view::{DynamicAoTextures, DynamicAoUniform, DynamicAoView, OCCLUSION_FORMAT};

#[derive(Resource)]
pub(crate) struct NearFieldPipeline {
    pub layout: BindGroupLayoutDescriptor,
    pub pipeline: CachedComputePipelineId,
}

impl FromWorld for NearFieldPipeline {
    fn from_world(world: &mut World) -> Self {
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_near_field_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    uniform_buffer::<ViewUniform>(true),
                    uniform_buffer::<DynamicAoUniform>(true),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_storage_2d(OCCLUSION_FORMAT, StorageTextureAccess::WriteOnly),
                ),
            ),
        );
        let pipeline =
            world
                .resource::<PipelineCache>()
                .queue_compute_pipeline(ComputePipelineDescriptor {
                    label: Some("dynamic_ao_near_field_pipeline".into()),
                    layout: vec![layout.clone()],
                    shader: load_embedded_asset!(world, "near_field.wgsl"),
                    ..default()
                });
        Self { layout, pipeline }
    }
}

#[derive(Component)]
pub(crate) struct NearFieldBindGroup(pub BindGroup);

pub(crate) fn prepare_near_field_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<NearFieldPipeline>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    settings: Res<ComponentUniforms<DynamicAoUniform>>,
    views: Query<(Entity, &DynamicAoTextures, &ViewPrepassTextures), With<DynamicAoView>>,
) {
    let (Some(view_binding), Some(settings_binding)) =
        (view_uniforms.uniforms.binding(), settings.binding())
    else {
        return;
    };
    for (entity, textures, prepass) in &views {
        let (Some(front_depth), Some(front_normal)) = (prepass.depth_view(), prepass.normal_view())
        else {
            continue;
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_near_field_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::sequential((
                view_binding.clone(),
                settings_binding.clone(),
                front_depth,
                front_normal,
                &textures.back_depth.default_view,
                &textures.back_normal.default_view,
                &textures.near_occlusion.default_view,
            )),
        );
        commands
            .entity(entity)
            .insert(NearFieldBindGroup(bind_group));
    }
}

//! Pipeline and bind groups of the ray-marched pass.

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

use crate::settings::AoTechnique;
use crate::view::{DynamicAoTextures, DynamicAoUniform, DynamicAoView, OCCLUSION_FORMAT};

#[derive(Resource)]
pub(crate) struct RayMarchPipeline {
    layout: BindGroupLayoutDescriptor,
    pub pipeline: CachedComputePipelineId,
}

impl FromWorld for RayMarchPipeline {
    fn from_world(world: &mut World) -> Self {
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_ray_march_layout",
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
                    label: Some("dynamic_ao_ray_march_pipeline".into()),
                    layout: vec![layout.clone()],
                    shader: load_embedded_asset!(world, "ray_march.wgsl"),
                    ..default()
                });
        Self { layout, pipeline }
    }
}

#[derive(Component)]
pub(crate) struct RayMarchBindGroup(pub BindGroup);

pub(crate) fn prepare_ray_march_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<RayMarchPipeline>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    settings: Res<ComponentUniforms<DynamicAoUniform>>,
    views: Query<(
        Entity,
        &DynamicAoTextures,
        &ViewPrepassTextures,
        &DynamicAoView,
    )>,
) {
    let (Some(view_binding), Some(settings_binding)) =
        (view_uniforms.uniforms.binding(), settings.binding())
    else {
        return;
    };
    for (entity, textures, prepass, view) in &views {
        let (Some(depth), Some(normal), AoTechnique::RayMarch) =
            (prepass.depth_view(), prepass.normal_view(), view.technique)
        else {
            commands.entity(entity).remove::<RayMarchBindGroup>();
            continue;
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_ray_march_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::sequential((
                view_binding.clone(),
                settings_binding.clone(),
                depth,
                normal,
                &textures.back_depth.default_view,
                &textures.back_normal.default_view,
                &textures.near_occlusion.default_view,
            )),
        );
        commands
            .entity(entity)
            .insert(RayMarchBindGroup(bind_group));
    }
}

//! Pipelines and bind groups of the blur.

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
pub(crate) struct BlurPipelines {
    pub layout: BindGroupLayoutDescriptor,
    pub x: CachedComputePipelineId,
    pub y: CachedComputePipelineId,
    pub upsample_layout: BindGroupLayoutDescriptor,
    pub upsample: CachedComputePipelineId,
}

impl FromWorld for BlurPipelines {
    fn from_world(world: &mut World) -> Self {
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_blur_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    uniform_buffer::<ViewUniform>(true),
                    uniform_buffer::<DynamicAoUniform>(true),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_storage_2d(OCCLUSION_FORMAT, StorageTextureAccess::WriteOnly),
                ),
            ),
        );
        let shader = load_embedded_asset!(world, "blur.wgsl");
        let cache = world.resource::<PipelineCache>();
        let pipeline = |label: &'static str, entry: &'static str| {
            cache.queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(label.into()),
                layout: vec![layout.clone()],
                shader: shader.clone(),
                entry_point: Some(entry.into()),
                ..default()
            })
        };
        let x = pipeline("dynamic_ao_blur_x_pipeline", "blur_x");
        let y = pipeline("dynamic_ao_blur_y_pipeline", "blur_y");
        let upsample_layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_upsample_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    uniform_buffer::<ViewUniform>(true),
                    uniform_buffer::<DynamicAoUniform>(true),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_storage_2d(OCCLUSION_FORMAT, StorageTextureAccess::WriteOnly),
                ),
            ),
        );
        let upsample = cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some("dynamic_ao_upsample_pipeline".into()),
            layout: vec![upsample_layout.clone()],
            shader: load_embedded_asset!(world, "upsample.wgsl"),
            ..default()
        });
        Self {
            layout,
            x,
            y,
            upsample_layout,
            upsample,
        }
    }
}

/// X pass: occlusion → scratch; Y pass: scratch → occlusion.
#[derive(Component)]
pub(crate) struct BlurBindGroups {
    pub x: BindGroup,
    pub y: BindGroup,
}

/// Half-size occlusion → full-size occlusion.
#[derive(Component)]
pub(crate) struct UpsampleBindGroup(pub BindGroup);

pub(crate) fn prepare_blur_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipelines: Res<BlurPipelines>,
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
    let layout = pipeline_cache.get_bind_group_layout(&pipelines.layout);
    let upsample_layout = pipeline_cache.get_bind_group_layout(&pipelines.upsample_layout);
    for (entity, textures, prepass, view) in &views {
        match (
            prepass.depth_view(),
            prepass.normal_view(),
            view.half_resolution,
        ) {
            (Some(depth), Some(normal), true) => {
                let bind_group = render_device.create_bind_group(
                    "dynamic_ao_upsample_bind_group",
                    &upsample_layout,
                    &BindGroupEntries::sequential((
                        view_binding.clone(),
                        settings_binding.clone(),
                        depth,
                        normal,
                        &textures.near_occlusion.default_view,
                        &textures.full_occlusion.default_view,
                    )),
                );
                commands
                    .entity(entity)
                    .insert(UpsampleBindGroup(bind_group));
            }
            _ => {
                commands.entity(entity).remove::<UpsampleBindGroup>();
            }
        }
        let Some(depth) = prepass.depth_view().filter(|_| view.blur_radius > 0) else {
            commands.entity(entity).remove::<BlurBindGroups>();
            continue;
        };
        let bind_group = |label, input: &TextureView, output: &TextureView| {
            render_device.create_bind_group(
                label,
                &layout,
                &BindGroupEntries::sequential((
                    view_binding.clone(),
                    settings_binding.clone(),
                    depth,
                    input,
                    output,
                )),
            )
        };
        let occlusion = &textures.full_occlusion.default_view;
        let scratch = &textures.blur_scratch.default_view;
        commands.entity(entity).insert(BlurBindGroups {
            x: bind_group("dynamic_ao_blur_x_bind_group", occlusion, scratch),
            y: bind_group("dynamic_ao_blur_y_bind_group", scratch, occlusion),
        });
    }
}

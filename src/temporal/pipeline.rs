//! The temporal pass's pipeline and each view's bind group.

use bevy::asset::load_embedded_asset;
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::ecs::prelude::*;
use bevy::render::{
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::RenderDevice,
    view::ViewUniform,
};
use bevy::utils::default;

use super::view::{TemporalHistory, TemporalUniform};
use crate::view::{DynamicAoTextures, DynamicAoUniform, OCCLUSION_FORMAT, ViewBindings};

/// The accumulation pipeline.
#[derive(Resource)]
pub(crate) struct TemporalPipeline {
    layout: BindGroupLayoutDescriptor,
    pub pipeline: CachedComputePipelineId,
}

impl FromWorld for TemporalPipeline {
    fn from_world(world: &mut World) -> Self {
        let float = || texture_2d(TextureSampleType::Float { filterable: false });
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_temporal_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    uniform_buffer::<ViewUniform>(true),
                    uniform_buffer::<DynamicAoUniform>(true),
                    uniform_buffer::<TemporalUniform>(false),
                    float(),
                    texture_depth_2d(),
                    float(),
                    float(),
                    texture_2d(TextureSampleType::Uint),
                    texture_storage_2d(TextureFormat::Rgba32Uint, StorageTextureAccess::WriteOnly),
                    texture_storage_2d(OCCLUSION_FORMAT, StorageTextureAccess::WriteOnly),
                ),
            ),
        );
        let shader = load_embedded_asset!(world, "temporal.wgsl");
        let pipeline =
            world
                .resource::<PipelineCache>()
                .queue_compute_pipeline(ComputePipelineDescriptor {
                    label: Some("dynamic_ao_temporal_pipeline".into()),
                    layout: vec![layout.clone()],
                    shader,
                    entry_point: Some("accumulate".into()),
                    ..default()
                });
        Self { layout, pipeline }
    }
}

#[derive(Component)]
pub(crate) struct TemporalBindGroup(pub(super) BindGroup);

pub(crate) fn prepare_temporal_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<TemporalPipeline>,
    pipeline_cache: Res<PipelineCache>,
    bindings: ViewBindings,
    views: Query<(
        Entity,
        &DynamicAoTextures,
        &ViewPrepassTextures,
        &TemporalHistory,
    )>,
) {
    let Some((view_binding, settings_binding)) = bindings.get() else {
        return;
    };
    for (entity, textures, prepass, history) in &views {
        let (Some(raw), Some(depth), Some(normal), Some(temporal)) = (
            textures.raw_occlusion.as_ref(),
            prepass.depth_view(),
            prepass.normal_view(),
            history.uniform.binding(),
        ) else {
            commands.entity(entity).remove::<TemporalBindGroup>();
            continue;
        };
        // Without motion vectors the history is dropped (see `prepare_history`), so any float
        // texture stands in for them.
        let motion = prepass.motion_vectors_view().unwrap_or(&raw.default_view);
        let (read, write) = history.views();
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_temporal_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::sequential((
                view_binding.clone(),
                settings_binding.clone(),
                temporal,
                &raw.default_view,
                depth,
                normal,
                motion,
                read,
                write,
                &textures.near_occlusion.default_view,
            )),
        );
        commands
            .entity(entity)
            .insert(TemporalBindGroup(bind_group));
    }
}

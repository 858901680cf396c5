//! Pipeline and bind groups of the debug view.

use bevy::asset::{Handle, load_embedded_asset};
use bevy::core_pipeline::FullscreenShader;
use bevy::ecs::prelude::*;
use bevy::pbr::ScreenSpaceAmbientOcclusionResources;
use bevy::render::{
    render_resource::{binding_types::texture_2d, *},
    renderer::RenderDevice,
    view::ViewTarget,
};
use bevy::shader::Shader;

use super::{ParkedSsao, visibility_texture};
use crate::draw_pipeline::overlay_pipeline;
use crate::view::DynamicAoView;

#[derive(Resource)]
pub(crate) struct DebugViewPipeline {
    layout: BindGroupLayoutDescriptor,
    fullscreen: FullscreenShader,
    shader: Handle<Shader>,
}

impl FromWorld for DebugViewPipeline {
    fn from_world(world: &mut World) -> Self {
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_debug_view_layout",
            &BindGroupLayoutEntries::single(
                ShaderStages::FRAGMENT,
                texture_2d(TextureSampleType::Float { filterable: false }),
            ),
        );
        Self {
            layout,
            fullscreen: world.resource::<FullscreenShader>().clone(),
            shader: load_embedded_asset!(world, "debug_view.wgsl"),
        }
    }
}

impl SpecializedRenderPipeline for DebugViewPipeline {
    /// The format of the view's main texture.
    type Key = TextureFormat;

    fn specialize(&self, format: Self::Key) -> RenderPipelineDescriptor {
        overlay_pipeline(
            "dynamic_ao_debug_view_pipeline",
            &self.layout,
            &self.fullscreen,
            &self.shader,
            format,
            None,
        )
    }
}

#[derive(Component)]
pub(crate) struct DebugViewPipelineId(pub CachedRenderPipelineId);

#[derive(Component)]
pub(crate) struct DebugViewBindGroup(pub BindGroup);

pub(crate) fn prepare_debug_view_pipelines(
    mut commands: Commands,
    pipeline_cache: Res<PipelineCache>,
    mut pipelines: ResMut<SpecializedRenderPipelines<DebugViewPipeline>>,
    pipeline: Res<DebugViewPipeline>,
    views: Query<(Entity, &DynamicAoView, &ViewTarget)>,
) {
    for (entity, view, target) in &views {
        if view.settings.debug_view {
            let id = pipelines.specialize(&pipeline_cache, &pipeline, target.main_texture_format());
            commands.entity(entity).insert(DebugViewPipelineId(id));
        } else {
            commands.entity(entity).remove::<DebugViewPipelineId>();
        }
    }
}

pub(crate) fn prepare_debug_view_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<DebugViewPipeline>,
    pipeline_cache: Res<PipelineCache>,
    views: Query<
        (
            Entity,
            Option<&ScreenSpaceAmbientOcclusionResources>,
            Option<&ParkedSsao>,
        ),
        With<DebugViewPipelineId>,
    >,
) {
    for (entity, resources, parked) in &views {
        let Some(visibility) = visibility_texture(resources, parked) else {
            commands.entity(entity).remove::<DebugViewBindGroup>();
            continue;
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_debug_view_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::single(&visibility.default_view),
        );
        commands
            .entity(entity)
            .insert(DebugViewBindGroup(bind_group));
    }
}

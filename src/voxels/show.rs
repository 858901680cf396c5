//! The occupied-voxel debug view: a full-screen pass over the lit image.

use crate::nd_buffer::FrontLayer;
use bevy::asset::{Handle, load_embedded_asset};
use bevy::core_pipeline::FullscreenShader;
use bevy::ecs::prelude::*;
use bevy::render::{
    camera::ExtractedCamera,
    extract_component::DynamicUniformIndex,
    render_resource::{
        binding_types::{storage_buffer_read_only_sized, texture_depth_2d, uniform_buffer},
        *,
    },
    renderer::{RenderContext, RenderDevice, ViewQuery},
    view::{ViewTarget, ViewUniform, ViewUniformOffset},
};
use bevy::shader::Shader;

use super::buffers::{VoxelBuffers, VoxelParams};
use crate::draw_pipeline::overlay_pipeline;
use crate::view::{DynamicAoUniform, DynamicAoView, FarTerm, ViewBindings};

#[derive(Resource)]
pub(crate) struct ShowVoxelsPipeline {
    layout: BindGroupLayoutDescriptor,
    fullscreen: FullscreenShader,
    shader: Handle<Shader>,
}

impl FromWorld for ShowVoxelsPipeline {
    fn from_world(world: &mut World) -> Self {
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_show_voxels_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::FRAGMENT,
                (
                    uniform_buffer::<ViewUniform>(true),
                    texture_depth_2d(),
                    storage_buffer_read_only_sized(false, None),
                    storage_buffer_read_only_sized(false, None),
                    uniform_buffer::<VoxelParams>(false),
                    uniform_buffer::<DynamicAoUniform>(true),
                ),
            ),
        );
        Self {
            layout,
            fullscreen: world.resource::<FullscreenShader>().clone(),
            shader: load_embedded_asset!(world, "show_voxels.wgsl"),
        }
    }
}

impl SpecializedRenderPipeline for ShowVoxelsPipeline {
    /// The format of the view's main texture.
    type Key = TextureFormat;

    fn specialize(&self, format: Self::Key) -> RenderPipelineDescriptor {
        overlay_pipeline(
            "dynamic_ao_show_voxels_pipeline",
            &self.layout,
            &self.fullscreen,
            &self.shader,
            format,
            Some(BlendState::ALPHA_BLENDING),
        )
    }
}

/// The pipeline and bind group of a view that draws occupied voxels this frame.
#[derive(Component)]
pub(crate) struct ShowVoxels {
    pipeline: CachedRenderPipelineId,
    bind_group: BindGroup,
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn prepare_show_voxels(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<ShowVoxelsPipeline>,
    pipeline_cache: Res<PipelineCache>,
    mut pipelines: ResMut<SpecializedRenderPipelines<ShowVoxelsPipeline>>,
    buffers: Res<VoxelBuffers>,
    bindings: ViewBindings,
    views: Query<(Entity, &DynamicAoView, &ViewTarget, FrontLayer)>,
) {
    let shown = buffers.any_shown();
    for (entity, view, target, prepass) in &views {
        let (
            true,
            true,
            Some(depth),
            Some((view_binding, settings)),
            Some((volumes, grid, params)),
        ) = (
            shown,
            view.has(FarTerm::Voxels),
            prepass.depth(),
            bindings.get(),
            buffers.bindings(),
        )
        else {
            commands.entity(entity).remove::<ShowVoxels>();
            continue;
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_show_voxels_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::sequential((view_binding, depth, volumes, grid, params, settings)),
        );
        let id = pipelines.specialize(&pipeline_cache, &pipeline, target.main_texture_format());
        commands.entity(entity).insert(ShowVoxels {
            pipeline: id,
            bind_group,
        });
    }
}

pub(crate) fn show_voxels_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &ViewTarget,
        &ShowVoxels,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipeline_cache: Res<PipelineCache>,
    mut ctx: RenderContext,
) {
    let (camera, target, show, view_offset, settings_index) = view.into_inner();
    let Some(pipeline) = pipeline_cache.get_render_pipeline(show.pipeline) else {
        return;
    };
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("dynamic_ao_show_voxels"),
        color_attachments: &[Some(target.get_unsampled_color_attachment())],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    if let Some(viewport) = camera.viewport.as_ref() {
        pass.set_camera_viewport(viewport);
    }
    pass.set_render_pipeline(pipeline);
    pass.set_bind_group(
        0,
        &show.bind_group,
        &[view_offset.offset, settings_index.index()],
    );
    pass.draw(0..3, 0..1);
}

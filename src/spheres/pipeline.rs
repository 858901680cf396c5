//! The splat pass's billboard pipeline and its per-view bind groups.

use crate::nd_buffer::FrontLayer;
use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::render::{
    render_resource::{
        binding_types::{
            storage_buffer_read_only_sized, texture_2d, texture_depth_2d, uniform_buffer,
        },
        *,
    },
    renderer::RenderDevice,
    view::ViewUniform,
};
use bevy::utils::default;

use super::buffers::SphereBuffer;
use crate::draw_pipeline::{LARGEST_OCCLUSION, MULTIPLY_VISIBILITY};
use crate::view::{
    DynamicAoTextures, DynamicAoUniform, DynamicAoView, FAR_OCCLUSION_FORMAT, FarTerm, ViewBindings,
};

/// The billboard pipeline: instanced quads, multiplying the far-field visibility buffer by
/// 1 − each proxy's occlusion.
#[derive(Resource)]
pub(crate) struct SplatPipeline {
    layout: BindGroupLayoutDescriptor,
    pub pipeline: CachedRenderPipelineId,
}

impl FromWorld for SplatPipeline {
    fn from_world(world: &mut World) -> Self {
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_splat_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::VERTEX_FRAGMENT,
                (
                    uniform_buffer::<ViewUniform>(true),
                    storage_buffer_read_only_sized(false, None),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_depth_2d(),
                    uniform_buffer::<DynamicAoUniform>(true),
                ),
            ),
        );
        let shader = load_embedded_asset!(world, "splat.wgsl");
        let pipeline =
            world
                .resource::<PipelineCache>()
                .queue_render_pipeline(RenderPipelineDescriptor {
                    label: Some("dynamic_ao_splat_pipeline".into()),
                    layout: vec![layout.clone()],
                    vertex: VertexState {
                        shader: shader.clone(),
                        ..default()
                    },
                    fragment: Some(FragmentState {
                        shader,
                        targets: vec![Some(ColorTargetState {
                            format: FAR_OCCLUSION_FORMAT,
                            blend: Some(BlendState {
                                color: MULTIPLY_VISIBILITY,
                                alpha: LARGEST_OCCLUSION,
                            }),
                            write_mask: ColorWrites::ALL,
                        })],
                        ..default()
                    }),
                    ..default()
                });
        Self { layout, pipeline }
    }
}

#[derive(Component)]
pub(crate) struct SplatBindGroup(pub BindGroup);

pub(crate) fn prepare_splat_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<SplatPipeline>,
    pipeline_cache: Res<PipelineCache>,
    bindings: ViewBindings,
    spheres: Res<SphereBuffer>,
    views: Query<(Entity, &DynamicAoView, &DynamicAoTextures, FrontLayer)>,
) {
    let (Some((view_binding, settings_binding)), Some(sphere_binding)) =
        (bindings.get(), spheres.buffer.binding())
    else {
        return;
    };
    for (entity, view, textures, prepass) in &views {
        let (true, Some(depth), Some(normal)) = (
            view.has(FarTerm::Spheres),
            prepass.depth(),
            prepass.normal(),
        ) else {
            commands.entity(entity).remove::<SplatBindGroup>();
            continue;
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_splat_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::sequential((
                view_binding.clone(),
                sphere_binding.clone(),
                depth,
                normal,
                &textures.back_depth.default_view,
                settings_binding.clone(),
            )),
        );
        commands.entity(entity).insert(SplatBindGroup(bind_group));
    }
}

//! The box pipelines of the AO field pass and their per-view bind groups.

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

use super::buffers::FieldBuffers;
use crate::draw_pipeline::{LARGEST_OCCLUSION, MULTIPLY_VISIBILITY};
use crate::settings::FieldShading;
use crate::view::{
    DynamicAoTextures, DynamicAoUniform, DynamicAoView, FAR_OCCLUSION_FORMAT, FarTerm, ViewBindings,
};

/// The box pipelines: occlusion only (§3.2) and cone (§3.3.1).
#[derive(Resource)]
pub(crate) struct FieldPipelines {
    layout: BindGroupLayoutDescriptor,
    occlusion_only: CachedRenderPipelineId,
    cone: CachedRenderPipelineId,
}

impl FieldPipelines {
    /// The pipeline that shades fields as `shading` says.
    pub fn for_shading(&self, shading: FieldShading) -> CachedRenderPipelineId {
        match shading {
            FieldShading::Cone => self.cone,
            FieldShading::OcclusionOnly => self.occlusion_only,
        }
    }
}

impl FromWorld for FieldPipelines {
    fn from_world(world: &mut World) -> Self {
        let storage = || storage_buffer_read_only_sized(false, None);
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_fields_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::VERTEX_FRAGMENT,
                (
                    uniform_buffer::<ViewUniform>(true),
                    storage(),
                    storage(),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_depth_2d(),
                    uniform_buffer::<DynamicAoUniform>(true),
                ),
            ),
        );
        let shader = load_embedded_asset!(world, "fields.wgsl");
        let cache = world.resource::<PipelineCache>();
        let [occlusion_only, cone] = [Vec::new(), vec!["CONE".into()]].map(|shader_defs| {
            cache.queue_render_pipeline(RenderPipelineDescriptor {
                label: Some("dynamic_ao_fields_pipeline".into()),
                layout: vec![layout.clone()],
                vertex: VertexState {
                    shader: shader.clone(),
                    shader_defs: shader_defs.clone(),
                    ..default()
                },
                fragment: Some(FragmentState {
                    shader: shader.clone(),
                    shader_defs,
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
                // The back faces of each grid box: each pixel once, even from inside the box.
                primitive: PrimitiveState {
                    cull_mode: Some(Face::Front),
                    ..default()
                },
                ..default()
            })
        });
        Self {
            layout,
            occlusion_only,
            cone,
        }
    }
}

#[derive(Component)]
pub(crate) struct FieldBindGroup(pub BindGroup);

pub(crate) fn prepare_field_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipelines: Res<FieldPipelines>,
    pipeline_cache: Res<PipelineCache>,
    bindings: ViewBindings,
    buffers: Res<FieldBuffers>,
    views: Query<(Entity, &DynamicAoView, &DynamicAoTextures, FrontLayer)>,
) {
    let (Some((view_binding, settings_binding)), Some(instances), Some(cells)) = (
        bindings.get(),
        buffers.instances.binding(),
        buffers.cells.binding(),
    ) else {
        return;
    };
    for (entity, view, textures, prepass) in &views {
        let (true, Some(depth), Some(normal)) =
            (view.has(FarTerm::Fields), prepass.depth(), prepass.normal())
        else {
            commands.entity(entity).remove::<FieldBindGroup>();
            continue;
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_fields_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipelines.layout),
            &BindGroupEntries::sequential((
                view_binding.clone(),
                instances.clone(),
                cells.clone(),
                depth,
                normal,
                &textures.back_depth.default_view,
                settings_binding.clone(),
            )),
        );
        commands.entity(entity).insert(FieldBindGroup(bind_group));
    }
}

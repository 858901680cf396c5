//! The coarse back faces' pipeline, this frame's instances packed per view, and their draw into
//! the back-face layer's pass.

use core::ops::Range;

use bevy::asset::{AssetId, load_embedded_asset};
use bevy::ecs::prelude::*;
use bevy::ecs::system::SystemParam;
use bevy::math::Vec4;
use bevy::mesh::{Mesh, VertexBufferLayout};
use bevy::platform::collections::HashMap;
use bevy::render::{
    render_phase::TrackedRenderPass,
    render_resource::{binding_types::uniform_buffer, *},
    renderer::{RenderDevice, RenderQueue},
    sync_world::MainEntity,
    view::{RetainedViewEntity, ViewUniform, ViewUniformOffset, ViewUniforms},
};
use bevy::utils::default;

use super::{CoarseInstance, CoarseInstances, CoarseMeshes};
use crate::memory::DynamicAoGpuMemory;
use crate::view::DEPTH_FORMAT;

/// The pipeline of the coarse back faces (`coarse_back_depth.wgsl`), whose one bind group is the
/// view.
#[derive(Resource)]
pub(crate) struct CoarseBackPipeline {
    layout: BindGroupLayoutDescriptor,
    id: CachedRenderPipelineId,
}

impl FromWorld for CoarseBackPipeline {
    fn from_world(world: &mut World) -> Self {
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_coarse_back_layout",
            &BindGroupLayoutEntries::single(
                ShaderStages::VERTEX,
                uniform_buffer::<ViewUniform>(true),
            ),
        );
        let shader = load_embedded_asset!(world, "coarse_back_depth.wgsl");
        let instance = VertexBufferLayout::from_vertex_formats(
            VertexStepMode::Instance,
            [VertexFormat::Float32x4; 3],
        )
        .offset_locations_by(1);
        let id =
            world
                .resource::<PipelineCache>()
                .queue_render_pipeline(RenderPipelineDescriptor {
                    label: Some("dynamic_ao_coarse_back_pipeline".into()),
                    layout: vec![layout.clone()],
                    vertex: VertexState {
                        shader,
                        entry_point: Some("vertex".into()),
                        shader_defs: Vec::new(),
                        buffers: vec![
                            VertexBufferLayout::from_vertex_formats(
                                VertexStepMode::Vertex,
                                [VertexFormat::Float32x3],
                            ),
                            instance,
                        ],
                    },
                    // Culled by the winding on screen, as Bevy culls the front layer's faces: Bevy
                    // 0.19 turns no culling around for a mirroring transform (its prepass then holds
                    // the far side of such a mesh), and the layer is what the prepass did not draw.
                    primitive: PrimitiveState {
                        topology: PrimitiveTopology::TriangleList,
                        front_face: FrontFace::Ccw,
                        cull_mode: Some(Face::Front),
                        ..default()
                    },
                    // As the mesh pipeline's back-face draw (`pipeline.rs`): reverse-Z, nearest wins.
                    depth_stencil: Some(DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(CompareFunction::GreaterEqual),
                        stencil: default(),
                        bias: default(),
                    }),
                    ..default()
                });
        Self { layout, id }
    }
}

/// One draw of a view: a coarse mesh over a range of this frame's instance buffer.
struct CoarseDraw {
    mesh: AssetId<Mesh>,
    instances: Range<u32>,
}

/// This frame's coarse back faces: the instances each view queued, then packed into one buffer
/// with each view's draws, and the view bind group they are drawn with.
#[derive(Resource)]
pub(crate) struct CoarseDraws {
    queued: HashMap<RetainedViewEntity, Vec<CoarseInstance>>,
    draws: HashMap<RetainedViewEntity, Vec<CoarseDraw>>,
    instances: RawBufferVec<[Vec4; 3]>,
    bind_group: Option<BindGroup>,
}

impl Default for CoarseDraws {
    fn default() -> Self {
        Self {
            queued: HashMap::default(),
            draws: HashMap::default(),
            instances: RawBufferVec::new(BufferUsages::VERTEX),
            bind_group: None,
        }
    }
}

/// What the back-face queue needs to send a mesh to the coarse draw instead of its phase.
#[derive(SystemParam)]
pub(crate) struct CoarseQueue<'w> {
    instances: Res<'w, CoarseInstances>,
    meshes: Res<'w, CoarseMeshes>,
    draws: ResMut<'w, CoarseDraws>,
    pipeline: Res<'w, CoarseBackPipeline>,
}

impl CoarseQueue<'_> {
    /// Starts `view`'s queue for this frame.
    pub fn begin(&mut self, view: RetainedViewEntity) {
        self.draws.queued.entry(view).or_default().clear();
    }

    /// Queues `entity` for `view`'s coarse draw and returns true where it has a coarse copy
    /// whose pipeline has compiled; else the caller draws it through its phase.
    pub fn take(
        &mut self,
        view: RetainedViewEntity,
        entity: MainEntity,
        cache: &PipelineCache,
    ) -> bool {
        let Some(instance) = self.instances.get(entity).copied() else {
            return false;
        };
        if self.meshes.get(instance.mesh).is_none()
            || cache.get_render_pipeline(self.pipeline.id).is_none()
        {
            return false;
        }
        self.draws.queued.entry(view).or_default().push(instance);
        true
    }

    /// Forgets the queues of views gone (those not in `live`).
    pub fn retain(&mut self, live: impl Fn(&RetainedViewEntity) -> bool) {
        self.draws.queued.retain(|view, _| live(view));
    }
}

/// Packs every view's queued instances into the instance buffer, grouped into one draw per mesh,
/// and binds the view uniform.
pub(crate) fn prepare_coarse_back_faces(
    mut draws: ResMut<CoarseDraws>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    pipeline: Res<CoarseBackPipeline>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    meshes: Res<CoarseMeshes>,
    memory: Res<DynamicAoGpuMemory>,
) {
    let draws = draws.as_mut();
    draws.instances.clear();
    draws.draws.clear();
    for (view, queued) in &mut draws.queued {
        queued.sort_unstable_by_key(|i| i.mesh);
        let mut list: Vec<CoarseDraw> = Vec::new();
        for instance in queued.iter() {
            let index = draws.instances.push(instance.rows) as u32;
            match list.last_mut() {
                Some(last) if last.mesh == instance.mesh => {
                    last.instances.end = index + 1;
                }
                _ => list.push(CoarseDraw {
                    mesh: instance.mesh,
                    instances: index..index + 1,
                }),
            }
        }
        if !list.is_empty() {
            draws.draws.insert(*view, list);
        }
    }
    draws.bind_group = None;
    if !draws.instances.is_empty() {
        draws.instances.write_buffer(&device, &queue);
    }
    let instances = draws.instances.buffer().map_or(0, |b| b.size());
    memory.report("back faces", meshes.bytes() + instances);
    if draws.instances.is_empty() {
        return;
    }
    if let Some(binding) = view_uniforms.uniforms.binding() {
        draws.bind_group = Some(device.create_bind_group(
            "dynamic_ao_coarse_back_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipeline.layout),
            &BindGroupEntries::single(binding),
        ));
    }
}

/// What the back-face pass draws the coarse copies with.
#[derive(SystemParam)]
pub(crate) struct CoarseBackFaces<'w> {
    draws: Res<'w, CoarseDraws>,
    meshes: Res<'w, CoarseMeshes>,
    pipeline: Res<'w, CoarseBackPipeline>,
    cache: Res<'w, PipelineCache>,
}

impl CoarseBackFaces<'_> {
    /// Draws `view`'s coarse back faces into the back-face layer's open `pass`.
    pub fn draw<'a>(
        &'a self,
        pass: &mut TrackedRenderPass<'a>,
        view: RetainedViewEntity,
        view_offset: &ViewUniformOffset,
    ) {
        let (Some(list), Some(bind_group), Some(instances), Some(pipeline)) = (
            self.draws.draws.get(&view),
            self.draws.bind_group.as_ref(),
            self.draws.instances.buffer(),
            self.cache.get_render_pipeline(self.pipeline.id),
        ) else {
            return;
        };
        pass.set_render_pipeline(pipeline);
        pass.set_bind_group(0, bind_group, &[view_offset.offset]);
        pass.set_vertex_buffer(1, instances.slice(..));
        for draw in list {
            let Some(mesh) = self.meshes.get(draw.mesh) else {
                continue;
            };
            pass.set_vertex_buffer(0, mesh.positions.slice(..));
            pass.set_index_buffer(mesh.indices.slice(..), IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.index_count, 0, draw.instances.clone());
        }
    }
}

//! The back-face pipeline (Bevy's mesh pipeline with front-face culling, and our fragment
//! shader where the layer's normals are drawn) and the system that queues every visible mesh
//! into the phase.

use bevy::asset::{AssetId, Handle, load_embedded_asset};
use bevy::ecs::prelude::*;
use bevy::log::{error, warn};
use bevy::mesh::{Mesh, Mesh3d, MeshVertexBufferLayoutRef, PrimitiveTopology};
use bevy::pbr::{
    MeshPipeline, MeshPipelineKey, RenderMaterialInstances, RenderMeshInstanceFlags,
    RenderMeshInstances, ViewKeyCache,
};
use bevy::platform::collections::HashSet;
use bevy::render::{
    mesh::RenderMesh,
    render_asset::RenderAssets,
    render_phase::{DrawFunctions, PhaseItemExtraIndex, ViewSortedRenderPhases},
    render_resource::{
        ColorTargetState, ColorWrites, CompareFunction, Face, MultisampleState, PipelineCache,
        RenderPipelineDescriptor, SpecializedMeshPipeline, SpecializedMeshPipelineError,
        SpecializedMeshPipelines,
    },
    view::{ExtractedView, RenderVisibleEntities},
};
use bevy::shader::Shader;

use super::phase::{BackFace3d, DrawBackFaces};
use crate::view::{DEPTH_FORMAT, DynamicAoView, NORMAL_FORMAT};

/// Bevy's mesh pipeline, drawing back faces into the second ND-buffer layer.
#[derive(Resource)]
pub(crate) struct BackFacePipeline {
    mesh_pipeline: MeshPipeline,
    shader: Handle<Shader>,
}

pub(crate) fn init_back_face_pipeline(
    mut commands: Commands,
    mesh_pipeline: Res<MeshPipeline>,
    asset_server: Res<bevy::asset::AssetServer>,
) {
    commands.insert_resource(BackFacePipeline {
        mesh_pipeline: mesh_pipeline.clone(),
        shader: load_embedded_asset!(asset_server.as_ref(), "back_faces.wgsl"),
    });
}

/// What a back-face pipeline is specialized on: Bevy's mesh key, and whether it draws the
/// layer's normals.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) struct BackFaceKey {
    pub mesh: MeshPipelineKey,
    /// Only the near field reads the layer's normals; every other reader wants its depth, which
    /// a pipeline without a fragment stage draws: on lavapipe the pass took 3.5–4.1 ms with
    /// normals and 1.7–2.5 ms without, in alternating runs of the `gpu_passes` benchmark's scene
    /// at 640×480.
    pub normals: bool,
}

impl SpecializedMeshPipeline for BackFacePipeline {
    type Key = BackFaceKey;

    fn specialize(
        &self,
        key: Self::Key,
        layout: &MeshVertexBufferLayoutRef,
    ) -> Result<RenderPipelineDescriptor, SpecializedMeshPipelineError> {
        // Starting from Bevy's own descriptor keeps the vertex stage identical to the front
        // layer's: same skinning, morph targets, instance data and bind group layouts.
        let mut descriptor = self.mesh_pipeline.specialize(key.mesh, layout)?;
        descriptor.label = Some("dynamic_ao_back_face_pipeline".into());
        if key.normals {
            let fragment = descriptor
                .fragment
                .as_mut()
                .expect("the mesh pipeline always has a fragment stage");
            fragment.shader = self.shader.clone();
            fragment.entry_point = Some("fragment".into());
            fragment.targets = vec![Some(ColorTargetState {
                format: NORMAL_FORMAT,
                blend: None,
                write_mask: ColorWrites::ALL,
            })];
        } else {
            descriptor.fragment = None;
        }
        let key = key.mesh;
        descriptor.primitive.cull_mode = Some(if key.contains(MeshPipelineKey::INVERT_CULLING) {
            Face::Back
        } else {
            Face::Front
        });
        if let Some(depth) = descriptor.depth_stencil.as_mut() {
            depth.format = DEPTH_FORMAT;
            depth.depth_write_enabled = Some(true);
            // Reverse-Z: the nearest back face wins.
            depth.depth_compare = Some(CompareFunction::GreaterEqual);
        }
        // Our layer is single-sampled whatever the camera uses.
        descriptor.multisample = MultisampleState::default();
        Ok(descriptor)
    }
}

pub(crate) fn queue_back_faces(
    draw_functions: Res<DrawFunctions<BackFace3d>>,
    mut pipelines: ResMut<SpecializedMeshPipelines<BackFacePipeline>>,
    pipeline_cache: Res<PipelineCache>,
    back_face_pipeline: Res<BackFacePipeline>,
    render_meshes: Res<RenderAssets<RenderMesh>>,
    render_mesh_instances: Res<RenderMeshInstances>,
    view_key_cache: Res<ViewKeyCache>,
    mut phases: ResMut<ViewSortedRenderPhases<BackFace3d>>,
    views: Query<(&ExtractedView, &RenderVisibleEntities, &DynamicAoView)>,
    materials: Res<RenderMaterialInstances>,
    mut warned: Local<HashSet<AssetId<Mesh>>>,
) {
    let draw_function = draw_functions.read().id::<DrawBackFaces>();
    for (view, visible_entities, ao_view) in &views {
        let Some(phase) = phases.get_mut(&view.retained_view_entity) else {
            continue;
        };
        phase.clear();
        if !ao_view.back_layer {
            continue;
        }
        let Some(view_key) = view_key_cache.get(&view.retained_view_entity) else {
            continue;
        };
        let Some(visible) = visible_entities.get::<Mesh3d>() else {
            continue;
        };
        for (render_entity, main_entity) in visible.iter_visible() {
            // Bevy's prepass, the front layer, draws only meshes with a material; so does the
            // back layer.
            if !materials.instances.contains_key(main_entity) {
                continue;
            }
            let Some(instance) = render_mesh_instances.render_mesh_queue_data(*main_entity) else {
                continue;
            };
            let mesh_id = instance.mesh_asset_id();
            let Some(mesh) = render_meshes.get(mesh_id) else {
                continue;
            };
            if !matches!(
                mesh.primitive_topology(),
                PrimitiveTopology::TriangleList | PrimitiveTopology::TriangleStrip
            ) {
                continue;
            }
            if ao_view.back_normals
                && !mesh.layout.0.contains(Mesh::ATTRIBUTE_NORMAL)
                && warned.insert(mesh_id)
            {
                warn!(
                    "mesh {mesh_id} has no normals: dynamic AO uses its face normals for the \
                     back-face layer (add normals with Mesh::compute_normals for smooth results)"
                );
            }
            let mut key = *view_key | MeshPipelineKey::from_bits_retain(mesh.key_bits.bits());
            // `SetMeshBindGroup` binds the motion-vector variant of the mesh bind group on
            // views with a motion-vector prepass; the layout must match it.
            if view_key.contains(MeshPipelineKey::MOTION_VECTOR_PREPASS) {
                if instance
                    .flags()
                    .contains(RenderMeshInstanceFlags::HAS_PREVIOUS_SKIN)
                {
                    key |= MeshPipelineKey::HAS_PREVIOUS_SKIN;
                }
                if instance
                    .flags()
                    .contains(RenderMeshInstanceFlags::HAS_PREVIOUS_MORPH)
                {
                    key |= MeshPipelineKey::HAS_PREVIOUS_MORPH;
                }
            }
            if instance.lightmap_slab_index().is_some() {
                key |= MeshPipelineKey::LIGHTMAPPED;
            }
            let key = BackFaceKey {
                mesh: key,
                normals: ao_view.back_normals,
            };
            let pipeline =
                match pipelines.specialize(&pipeline_cache, &back_face_pipeline, key, &mesh.layout)
                {
                    Ok(id) => id,
                    Err(err) => {
                        if warned.insert(mesh_id) {
                            error!(
                                "dynamic AO cannot draw the back faces of mesh {mesh_id}: {err}"
                            );
                        }
                        continue;
                    }
                };
            phase.add_retained(BackFace3d {
                // Render-world mesh instances carry no world-space centre to sort by; the
                // layer is depth-tested, so order only affects overdraw.
                distance: 0.0,
                entity: (*render_entity, *main_entity),
                pipeline,
                draw_function,
                batch_range: 0..1,
                extra_index: PhaseItemExtraIndex::None,
                indexed: mesh.indexed(),
            });
        }
    }
}

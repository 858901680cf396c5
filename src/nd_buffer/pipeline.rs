//! The pipeline of the layers this crate draws with Bevy's mesh pipeline (the back faces, with
//! our fragment shader where the layer's normals are drawn; on MSAA cameras the front faces'
//! depth at pixel centres) and the system that queues every visible mesh into their phases.

use core::any::TypeId;

use bevy::asset::{AssetId, Handle, UntypedAssetId, load_embedded_asset};
use bevy::ecs::prelude::*;
use bevy::log::{error, warn};
use bevy::material::RenderPhaseType;
use bevy::mesh::{Mesh, Mesh3d, MeshVertexBufferLayoutRef, PrimitiveTopology};
use bevy::pbr::{
    MeshPipeline, MeshPipelineKey, PreparedMaterial, RenderMaterialInstances,
    RenderMeshInstanceFlags, RenderMeshInstances, StandardMaterial, StandardMaterialKey,
    ViewKeyCache,
};
use bevy::platform::collections::HashSet;
use bevy::render::{
    erased_render_asset::ErasedRenderAssets,
    mesh::RenderMesh,
    render_asset::RenderAssets,
    render_phase::{DrawFunctions, ViewSortedRenderPhases},
    render_resource::{
        ColorTargetState, ColorWrites, CompareFunction, Face, MultisampleState, PipelineCache,
        RenderPipelineDescriptor, SpecializedMeshPipeline, SpecializedMeshPipelineError,
        SpecializedMeshPipelines,
    },
    view::{ExtractedView, Msaa, RenderVisibleEntities},
};
use bevy::shader::Shader;

use super::coarse::CoarseQueue;
use super::front_layer::DEPTH_GRADIENT_FORMAT;
use super::phase::{BackFace3d, CentreSample3d, DrawLayerMeshes, NdLayer3d};
use crate::settings::AoTechnique;
use crate::view::{DEPTH_FORMAT, DynamicAoView, NORMAL_FORMAT};

/// Bevy's mesh pipeline, drawing back faces into the second ND-buffer layer and, on MSAA cameras,
/// the front faces' single-sampled depth.
#[derive(Resource)]
pub(crate) struct BackFacePipeline {
    mesh_pipeline: MeshPipeline,
    /// The fragment stage of the layers with normals.
    shader: Handle<Shader>,
    /// The vertex stage of the back faces' depth alone.
    depth_shader: Handle<Shader>,
}

pub(crate) fn init_back_face_pipeline(
    mut commands: Commands,
    mesh_pipeline: Res<MeshPipeline>,
    asset_server: Res<bevy::asset::AssetServer>,
) {
    commands.insert_resource(BackFacePipeline {
        mesh_pipeline: mesh_pipeline.clone(),
        shader: load_embedded_asset!(asset_server.as_ref(), "layer_normals.wgsl"),
        depth_shader: load_embedded_asset!(asset_server.as_ref(), "back_depth.wgsl"),
    });
}

/// What a layer pipeline is specialized on: Bevy's mesh key, and what it draws.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) struct LayerKey {
    pub mesh: MeshPipelineKey,
    pub draw: LayerDraw,
}

/// What a layer pipeline draws.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) enum LayerDraw {
    /// The back faces' depth, without a fragment stage: every reader of the back layer but the
    /// near field wants only its depth, and on lavapipe the pass took 3.5–4.1 ms with normals
    /// and 1.7–2.5 ms without, in alternating runs of the `gpu_passes` benchmark's scene at
    /// 640×480. Its vertex stage computes the position alone (`back_depth.wgsl`): with Bevy's
    /// mesh vertex shader the pass took 5.4–7.5 ms on a 60,000-triangle ring and 2.1–2.5 on
    /// DamagedHelmet, with its own 5.5–6.1 and 1.8–2.1 (alternating `ao_capture --timings`).
    BackDepth,
    /// The back faces' depth and normals, for the near field.
    BackNormals,
    /// The depth and normals at pixel centres of the meshes Bevy's prepass draws (MSAA cameras),
    /// culled as their material culls them there. `masked`: an alpha-masked material, whose
    /// discarded fragments only its shader knows, so that this draw may show it where the
    /// prepass does not (marked in the normal's alpha).
    Centre { cull: CentreCull, masked: bool },
}

/// Which faces the centre sample culls: those Bevy's prepass culls for the mesh's material.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) enum CentreCull {
    /// Back faces (front faces where culling is inverted): the mesh pipeline's choice, and every
    /// material's but a `StandardMaterial` that says otherwise.
    Back,
    /// Front faces (back faces where culling is inverted).
    Front,
    /// None: a double-sided `StandardMaterial`.
    None,
}

impl CentreCull {
    /// The cull mode of the material `asset` of a mesh: a `StandardMaterial`'s own, else the
    /// mesh pipeline's.
    fn of(asset: UntypedAssetId, material: &PreparedMaterial) -> Self {
        if asset.type_id() != TypeId::of::<StandardMaterial>() {
            return Self::Back;
        }
        // A `StandardMaterial`'s key is its bind group data (`StandardMaterial::specialize`).
        let key = material
            .properties
            .material_key
            .to_key::<StandardMaterialKey>();
        match (
            key.contains(StandardMaterialKey::CULL_FRONT),
            key.contains(StandardMaterialKey::CULL_BACK),
        ) {
            (true, false) => Self::Front,
            (false, true) => Self::Back,
            _ => Self::None,
        }
    }
}

impl SpecializedMeshPipeline for BackFacePipeline {
    type Key = LayerKey;

    fn specialize(
        &self,
        key: Self::Key,
        layout: &MeshVertexBufferLayoutRef,
    ) -> Result<RenderPipelineDescriptor, SpecializedMeshPipelineError> {
        // Starting from Bevy's own descriptor keeps the vertex stage identical to the front
        // layer's: same skinning, morph targets, instance data and bind group layouts. The
        // depth-only draw swaps in a vertex shader that computes the position alone (through
        // the same functions) under the same shader defs and vertex layout.
        let mut descriptor = self.mesh_pipeline.specialize(key.mesh, layout)?;
        descriptor.label = Some(match key.draw {
            LayerDraw::Centre { .. } => "dynamic_ao_centre_sample_pipeline".into(),
            _ => "dynamic_ao_back_face_pipeline".into(),
        });
        if key.draw != LayerDraw::BackDepth {
            let fragment = descriptor
                .fragment
                .as_mut()
                .expect("the mesh pipeline always has a fragment stage");
            fragment.shader = self.shader.clone();
            fragment.entry_point = Some("fragment".into());
            let target = |format| {
                Some(ColorTargetState {
                    format,
                    blend: None,
                    write_mask: ColorWrites::ALL,
                })
            };
            fragment.targets = vec![target(NORMAL_FORMAT)];
            if let LayerDraw::Centre { masked, .. } = key.draw {
                fragment.shader_defs.push("FRONT_FACES".into());
                if masked {
                    fragment.shader_defs.push("ALPHA_MASKED".into());
                }
                fragment.targets.push(target(DEPTH_GRADIENT_FORMAT));
            }
        } else {
            descriptor.fragment = None;
            descriptor.vertex.shader = self.depth_shader.clone();
            descriptor.vertex.entry_point = Some("vertex".into());
        }
        let cull_front = match key.draw {
            LayerDraw::BackDepth | LayerDraw::BackNormals => Some(true),
            LayerDraw::Centre { cull, .. } => match cull {
                CentreCull::Back => Some(false),
                CentreCull::Front => Some(true),
                CentreCull::None => None,
            },
        };
        let inverted = key.mesh.contains(MeshPipelineKey::INVERT_CULLING);
        descriptor.primitive.cull_mode = cull_front.map(|front| {
            if front != inverted {
                Face::Front
            } else {
                Face::Back
            }
        });
        if let Some(depth) = descriptor.depth_stencil.as_mut() {
            depth.format = DEPTH_FORMAT;
            depth.depth_write_enabled = Some(true);
            // Reverse-Z: the nearest face wins.
            depth.depth_compare = Some(CompareFunction::GreaterEqual);
        }
        // Our layer is single-sampled whatever the camera uses.
        descriptor.multisample = MultisampleState::default();
        Ok(descriptor)
    }
}

/// Queues every visible mesh with a material into the back-face phase of each view that reads
/// the back layer (or, where it has a coarse copy, into the coarse draw: `coarse`), and into the
/// centre-depth phase of each MSAA view.
pub(crate) fn queue_layers(
    draw_functions: Res<DrawFunctions<BackFace3d>>,
    centre_draw_functions: Res<DrawFunctions<CentreSample3d>>,
    mut pipelines: ResMut<SpecializedMeshPipelines<BackFacePipeline>>,
    pipeline_cache: Res<PipelineCache>,
    back_face_pipeline: Res<BackFacePipeline>,
    render_meshes: Res<RenderAssets<RenderMesh>>,
    render_mesh_instances: Res<RenderMeshInstances>,
    view_key_cache: Res<ViewKeyCache>,
    mut phases: ResMut<ViewSortedRenderPhases<BackFace3d>>,
    mut centre_phases: ResMut<ViewSortedRenderPhases<CentreSample3d>>,
    views: Query<(
        &ExtractedView,
        &RenderVisibleEntities,
        &DynamicAoView,
        &Msaa,
    )>,
    materials: Res<RenderMaterialInstances>,
    prepared_materials: Res<ErasedRenderAssets<PreparedMaterial>>,
    mut warned: Local<HashSet<AssetId<Mesh>>>,
    mut coarse: CoarseQueue,
) {
    let draw_function = draw_functions.read().id::<DrawLayerMeshes>();
    let centre_draw_function = centre_draw_functions.read().id::<DrawLayerMeshes>();
    coarse.retain(|view| phases.contains_key(view));
    for (view, visible_entities, ao_view, msaa) in &views {
        coarse.begin(view.retained_view_entity);
        let (Some(phase), Some(centre_phase)) = (
            phases.get_mut(&view.retained_view_entity),
            centre_phases.get_mut(&view.retained_view_entity),
        ) else {
            continue;
        };
        phase.clear();
        centre_phase.clear();
        let back = ao_view.back_layer.then_some(if ao_view.back_normals {
            LayerDraw::BackNormals
        } else {
            LayerDraw::BackDepth
        });
        // Under Bevy's own SSAO none of our passes reads the front layer.
        let centre = msaa.samples() > 1 && ao_view.technique() != AoTechnique::BevySsao;
        if back.is_none() && !centre {
            continue;
        }
        let Some(view_key) = view_key_cache.get(&view.retained_view_entity) else {
            continue;
        };
        let Some(visible) = visible_entities.get::<Mesh3d>() else {
            continue;
        };
        for (render_entity, main_entity) in visible.iter_visible() {
            // Bevy's prepass, the front layer, draws only meshes with a material; so do our
            // layers.
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
            if back == Some(LayerDraw::BackNormals)
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
            let mut specialize = |draw| {
                let key = LayerKey { mesh: key, draw };
                match pipelines.specialize(&pipeline_cache, &back_face_pipeline, key, &mesh.layout)
                {
                    Ok(id) => Some(id),
                    Err(err) => {
                        if warned.insert(mesh_id) {
                            error!("dynamic AO cannot draw mesh {mesh_id} into its layers: {err}");
                        }
                        None
                    }
                }
            };
            let entity = (*render_entity, *main_entity);
            // The centre sample stands for Bevy's prepass, which draws opaque and alpha-masked
            // materials (blended and transmissive ones are in neither).
            let centre_draw = || {
                let instance = materials.instances.get(main_entity)?;
                let material = prepared_materials.get(instance.asset_id)?;
                let masked = match material.properties.render_phase_type {
                    RenderPhaseType::Opaque => false,
                    RenderPhaseType::AlphaMask => true,
                    RenderPhaseType::Transmissive | RenderPhaseType::Transparent => return None,
                };
                material
                    .properties
                    .prepass_enabled
                    .then(|| LayerDraw::Centre {
                        cull: CentreCull::of(instance.asset_id, material),
                        masked,
                    })
            };
            let coarse_drawn = back == Some(LayerDraw::BackDepth)
                && ao_view.coarse_back_faces
                && coarse.take(view.retained_view_entity, *main_entity, &pipeline_cache);
            if !coarse_drawn && let Some(pipeline) = back.and_then(&mut specialize) {
                phase.add_retained(NdLayer3d::new(
                    entity,
                    pipeline,
                    draw_function,
                    mesh.indexed(),
                ));
            }
            if centre
                && let Some(draw) = centre_draw()
                && let Some(pipeline) = specialize(draw)
            {
                centre_phase.add_retained(NdLayer3d::new(
                    entity,
                    pipeline,
                    centre_draw_function,
                    mesh.indexed(),
                ));
            }
        }
    }
}

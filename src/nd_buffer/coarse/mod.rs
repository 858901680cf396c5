//! The back-face layer of meshes of many triangles, drawn from a coarse copy.
//!
//! Where the layer is depth only (every technique but the near field), a rigid mesh of more than
//! [`COARSE_BACK_FACES_ABOVE`] triangles is drawn into it from a copy with a quarter of them or
//! fewer, clustered on a grid of about twice its mean edge (`geometry::simplify`), instead of
//! through Bevy's mesh pipeline. On a CPU rasterizer the layer's cost follows the triangles, not
//! the pixels: on a 60,000-triangle model it took about a fifth of the default's GPU time
//! (BENCHMARKS.md, "Coarse back faces"). The layer only bounds the solid behind the front
//! layer, and every reader of it already counts a step within `RayMarchParams::thickness` × R
//! behind it as blocked, a margin wider than the cells on models of that size.
//!
//! Skinned and morph-target meshes, meshes whose vertex data lives only in the render world and
//! cameras with [`DynamicAo::coarse_back_faces`] off keep Bevy's mesh pipeline. A mesh's copy is
//! made once, when a camera first needs it, and dropped when its asset changes.

mod draw;

use bevy::asset::{AssetEvent, AssetId, Assets};
use bevy::camera::visibility::ViewVisibility;
use bevy::ecs::prelude::*;
use bevy::log::debug;
use bevy::math::{Affine3A, Vec4};
use bevy::mesh::{Mesh, Mesh3d};
use bevy::platform::collections::HashMap;
use bevy::render::{
    Extract,
    render_resource::{Buffer, BufferInitDescriptor, BufferUsages},
    renderer::RenderDevice,
    sync_world::MainEntity,
};
use bevy::transform::components::GlobalTransform;

pub(crate) use draw::{
    CoarseBackFaces, CoarseBackPipeline, CoarseDraws, CoarseQueue, prepare_coarse_back_faces,
};

use crate::geometry::rest_mesh::RestMesh;
use crate::geometry::simplify::simplify;
use crate::settings::DynamicAo;

/// Meshes of more triangles than this draw the back-face layer from a coarse copy where
/// [`DynamicAo::coarse_back_faces`] is on. Below it the layer costs little on any rasterizer.
pub const COARSE_BACK_FACES_ABOVE: usize = 8_192;

/// A mesh's coarse copy on the GPU: positions (mesh space, `Float32x3`) and `u32` indices.
pub(crate) struct CoarseMesh {
    pub positions: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
}

/// Coarse copies by mesh asset: `None` for a mesh drawn through Bevy's pipeline (few
/// triangles, skinned or morphed, no CPU data, or nothing left after clustering).
#[derive(Resource, Default)]
pub(crate) struct CoarseMeshes(HashMap<AssetId<Mesh>, Option<CoarseMesh>>);

impl CoarseMeshes {
    pub fn get(&self, id: AssetId<Mesh>) -> Option<&CoarseMesh> {
        self.0.get(&id)?.as_ref()
    }

    /// GPU memory the copies hold, bytes.
    pub fn bytes(&self) -> u64 {
        self.0
            .values()
            .flatten()
            .map(|m| m.positions.size() + m.indices.size())
            .sum()
    }
}

/// One visible entity whose mesh has a coarse copy: this frame's transform.
#[derive(Clone, Copy)]
pub(crate) struct CoarseInstance {
    pub mesh: AssetId<Mesh>,
    /// Rows of the world-from-local affine transform (what the vertex stage reads).
    pub rows: [Vec4; 3],
}

impl CoarseInstance {
    fn new(mesh: AssetId<Mesh>, transform: Affine3A) -> Option<Self> {
        let m = transform.matrix3;
        let t = transform.translation;
        let rows = [
            Vec4::new(m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x),
            Vec4::new(m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y),
            Vec4::new(m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z),
        ];
        rows.iter()
            .all(|r| r.is_finite())
            .then_some(Self { mesh, rows })
    }
}

/// This frame's [`CoarseInstance`]s, by main-world entity.
#[derive(Resource, Default)]
pub(crate) struct CoarseInstances(HashMap<MainEntity, CoarseInstance>);

impl CoarseInstances {
    pub fn get(&self, entity: MainEntity) -> Option<&CoarseInstance> {
        self.0.get(&entity)
    }
}

/// The coarse copy of `mesh`, uploaded, or `None` where the mesh keeps Bevy's pipeline.
fn coarse_copy(mesh: &Mesh, device: &RenderDevice) -> Option<CoarseMesh> {
    // Counted before anything is copied: most meshes stop here.
    let corners = match mesh.try_indices_option() {
        Ok(Some(indices)) => indices.len(),
        Ok(None) => mesh.count_vertices(),
        Err(_) => return None,
    };
    if corners / 3 <= COARSE_BACK_FACES_ABOVE
        || mesh.contains_attribute(Mesh::ATTRIBUTE_JOINT_INDEX)
        || mesh.try_has_morph_targets().unwrap_or(true)
    {
        return None;
    }
    let rest = RestMesh::from_mesh(mesh).ok()?;
    let simplified = simplify(&rest.positions, &rest.triangles, rest.triangles.len() / 4)?;
    debug!(
        "dynamic AO: the back-face layer draws a mesh of {} triangles from a copy of {} \
         (cells of {} m)",
        rest.triangles.len(),
        simplified.triangles.len(),
        simplified.cell
    );
    let positions: Vec<[f32; 3]> = simplified.positions.iter().map(|p| p.to_array()).collect();
    let indices: Vec<u32> = simplified.triangles.iter().flatten().copied().collect();
    Some(CoarseMesh {
        positions: device.create_buffer_with_data(&BufferInitDescriptor {
            label: Some("dynamic_ao_coarse_back_positions"),
            contents: bytemuck::cast_slice(&positions),
            usage: BufferUsages::VERTEX,
        }),
        indices: device.create_buffer_with_data(&BufferInitDescriptor {
            label: Some("dynamic_ao_coarse_back_indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: BufferUsages::INDEX,
        }),
        index_count: indices.len() as u32,
    })
}

/// Makes the coarse copies visible meshes need, drops those of changed meshes, and notes this
/// frame's transform of every visible entity that has one. Nothing where no camera wants them.
pub(crate) fn extract_coarse_back_faces(
    cameras: Extract<Query<&DynamicAo>>,
    entities: Extract<Query<(Entity, &Mesh3d, &GlobalTransform, &ViewVisibility)>>,
    meshes: Extract<Res<Assets<Mesh>>>,
    mut events: Extract<MessageReader<AssetEvent<Mesh>>>,
    device: Res<RenderDevice>,
    mut coarse: ResMut<CoarseMeshes>,
    mut instances: ResMut<CoarseInstances>,
) {
    for event in events.read() {
        if let AssetEvent::Modified { id }
        | AssetEvent::Removed { id }
        | AssetEvent::Unused { id } = event
        {
            coarse.0.remove(id);
        }
    }
    instances.0.clear();
    if !cameras.iter().any(|ao| ao.coarse_back_faces) {
        return;
    }
    for (entity, mesh, transform, visibility) in &entities {
        if !visibility.get() {
            continue;
        }
        let id = mesh.id();
        if !coarse.0.contains_key(&id) {
            // Not yet loaded: asked again next frame.
            let Some(mesh) = meshes.get(id) else {
                continue;
            };
            coarse.0.insert(id, coarse_copy(mesh, &device));
        }
        if coarse.get(id).is_some()
            && let Some(instance) = CoarseInstance::new(id, transform.affine())
        {
            instances.0.insert(entity.into(), instance);
        }
    }
}

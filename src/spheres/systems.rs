//! Main-world systems: clustering each mesh once (cached, off the main thread for large meshes)
//! and refitting its spheres every frame after animation and transform propagation.

use std::sync::Arc;

use bevy::asset::{AssetEvent, AssetId, Assets};
use bevy::camera::visibility::InheritedVisibility;
use bevy::ecs::prelude::*;
use bevy::log::warn;
use bevy::math::Affine3A;
use bevy::mesh::morph::{MeshMorphWeights, MorphWeights};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::mesh::{Mesh, Mesh3d};
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::{Children, GlobalTransform, Name};
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};

use super::component::{OccluderSpheres, ProxyShape, SphereOccluder};
use super::fit::fit_boxes;
use super::lloyd::{ClusteredMesh, cluster};
use super::refit::refit;
use crate::geometry::closed::encloses_volume;
use crate::geometry::deform::{Pose, mesh_morph_weights, skin_joints};
use crate::geometry::rest_mesh::{RestMesh, RestMeshError};

/// Meshes with more vertices than this are clustered on the async compute pool, so loading a
/// large character never stalls a frame; smaller ones are clustered at once.
pub const ASYNC_CLUSTERING_VERTICES: usize = 2048;

/// A mesh clustered for one sphere count.
pub(crate) struct FittedMesh {
    pub mesh: RestMesh,
    pub clustered: ClusteredMesh,
    /// Vertices that carry surface area: the most clusters this mesh can have.
    pub clusterable_vertices: usize,
    /// The mesh encloses a volume and has more than one proxy: its proxies stand one behind
    /// another as a receiver sees them (the near and far sides of a ring), as a character's do.
    pub solid_parts: bool,
}

type FitResult = Result<Arc<FittedMesh>, RestMeshError>;

type FitKey = (AssetId<Mesh>, u32, ProxyShape);

/// Fitting results per (mesh asset, proxy count, shape), and the fits still running.
#[derive(Resource, Default)]
pub(crate) struct SphereCache {
    ready: HashMap<FitKey, FitResult>,
    pending: HashMap<FitKey, Task<FitResult>>,
}

impl SphereCache {
    /// The fit of `id` with at most `count` proxies of `shape`: started if new, `None` while it
    /// runs.
    fn get(
        &mut self,
        id: AssetId<Mesh>,
        count: u32,
        shape: ProxyShape,
        meshes: &Assets<Mesh>,
    ) -> Option<FitResult> {
        let key = (id, count, shape);
        if let Some(result) = self.ready.get(&key) {
            return Some(result.clone());
        }
        if let Some(task) = self.pending.get_mut(&key) {
            let result = check_ready(task)?;
            self.pending.remove(&key);
            self.ready.insert(key, result.clone());
            return Some(result);
        }
        let mesh = meshes.get(id)?;
        let rest = match RestMesh::from_mesh(mesh) {
            Ok(rest) => rest,
            Err(error) => {
                self.ready.insert(key, Err(error.clone()));
                return Some(Err(error));
            }
        };
        if rest.positions.len() > ASYNC_CLUSTERING_VERTICES {
            let task =
                AsyncComputeTaskPool::get().spawn(async move { Ok(fit(rest, count, shape)) });
            self.pending.insert(key, task);
            return None;
        }
        let result: FitResult = Ok(fit(rest, count, shape));
        self.ready.insert(key, result.clone());
        Some(result)
    }

    /// Forgets every clustering of a mesh whose asset changed or went away.
    fn forget(&mut self, id: AssetId<Mesh>) {
        self.ready.retain(|(mesh, ..), _| *mesh != id);
        self.pending.retain(|(mesh, ..), _| *mesh != id);
    }
}

fn fit(mesh: RestMesh, count: u32, shape: ProxyShape) -> Arc<FittedMesh> {
    let clustered = match shape {
        ProxyShape::Boxes => fit_boxes(&mesh, count),
        ProxyShape::Spheres => cluster(&mesh, count),
    };
    let clusterable_vertices = mesh.areas.iter().filter(|a| **a > 0.0).count();
    let solid_parts = clustered.spheres.len() > 1
        && encloses_volume(
            mesh.triangles
                .iter()
                .map(|t| t.map(|i| mesh.positions[i as usize])),
        );
    Arc::new(FittedMesh {
        mesh,
        clustered,
        clusterable_vertices,
        solid_parts,
    })
}

pub(crate) fn forget_changed_meshes(
    mut events: MessageReader<AssetEvent<Mesh>>,
    mut cache: ResMut<SphereCache>,
) {
    for event in events.read() {
        match event {
            AssetEvent::Modified { id }
            | AssetEvent::Removed { id }
            | AssetEvent::Unused { id } => cache.forget(*id),
            _ => {}
        }
    }
}

/// A problem reported once per mesh entity.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) enum Problem {
    Unusable,
    FewVertices,
    SkinWithoutJointData,
    MissingJoint,
    NonFinite,
    /// The component's own settings are out of range (said for the entity that carries it).
    Settings,
}

type MeshQuery<'w, 's> = Query<
    'w,
    's,
    (
        &'static Mesh3d,
        &'static GlobalTransform,
        Option<&'static SkinnedMesh>,
        Option<&'static MeshMorphWeights>,
        Option<&'static InheritedVisibility>,
        Option<&'static mut OccluderSpheres>,
        Option<&'static Name>,
    ),
>;

/// Every mesh under a [`SphereOccluder`] gets its spheres for this frame.
pub(crate) fn refit_spheres(
    mut commands: Commands,
    occluders: Query<(Entity, &SphereOccluder, Option<&Name>)>,
    children: Query<&Children>,
    mut mesh_entities: MeshQuery,
    transforms: Query<&GlobalTransform>,
    morph_weights: Query<&MorphWeights>,
    with_spheres: Query<Entity, With<OccluderSpheres>>,
    meshes: Res<Assets<Mesh>>,
    inverse_bindposes: Res<Assets<SkinnedMeshInverseBindposes>>,
    mut cache: ResMut<SphereCache>,
    mut warned: Local<HashSet<(Entity, Problem)>>,
    mut joints: Local<Vec<Affine3A>>,
) {
    // A mesh's own occluder wins over one on an ancestor.
    let mut targets: HashMap<Entity, SphereOccluder> = HashMap::default();
    for (root, set, name) in &occluders {
        let occluder = set.sanitized();
        if occluder != *set && warned.insert((root, Problem::Settings)) {
            let label = name.map_or_else(|| format!("{root}"), |n| format!("'{n}' ({root})"));
            warn!(
                "SphereOccluder on {label}: {set:?} is out of range (count 1..={}, ε in (0, 1)); \
                 using {occluder:?}",
                SphereOccluder::MAX_COUNT
            );
        }
        targets.insert(root, occluder);
        for entity in children.iter_descendants(root) {
            if !occluders.contains(entity) {
                targets.entry(entity).or_insert(occluder);
            }
        }
    }
    for entity in &with_spheres {
        if !targets.contains_key(&entity) || !mesh_entities.contains(entity) {
            commands.entity(entity).remove::<OccluderSpheres>();
        }
    }

    for (&entity, occluder) in &targets {
        let Ok((mesh3d, transform, skinned, morphs, visibility, spheres, name)) =
            mesh_entities.get_mut(entity)
        else {
            continue;
        };
        let mut warn_once = |problem: Problem, message: &dyn Fn() -> String| {
            if warned.insert((entity, problem)) {
                let label =
                    name.map_or_else(|| format!("{entity}"), |n| format!("'{n}' ({entity})"));
                warn!("SphereOccluder: mesh {label} {}", message());
            }
        };
        let mut out = OccluderSpheres {
            spheres: Vec::new(),
            reach: occluder.reach,
            articulated: skinned.is_some(),
        };
        let fitted = match cache.get(mesh3d.id(), occluder.count, occluder.shape, &meshes) {
            Some(Ok(fitted)) => Some(fitted),
            Some(Err(error)) => {
                warn_once(Problem::Unusable, &|| {
                    format!("casts no far-field occlusion: {error}")
                });
                None
            }
            None => None,
        };
        if let Some(fitted) = fitted
            && visibility.is_none_or(|v| v.get())
        {
            out.articulated |= fitted.solid_parts;
            if occluder.shape == ProxyShape::Spheres
                && fitted.clusterable_vertices < occluder.count as usize
            {
                warn_once(Problem::FewVertices, &|| {
                    format!(
                        "asks for {} spheres but has only {} usable vertices; it gets {}",
                        occluder.count,
                        fitted.clusterable_vertices,
                        fitted.clustered.spheres.len()
                    )
                });
            }
            joints.clear();
            if let Some(skinned) = skinned {
                if fitted.mesh.skin.is_none() {
                    warn_once(Problem::SkinWithoutJointData, &|| {
                        "has a SkinnedMesh but no joint index/weight attributes (Bevy's renderer \
                         rejects such a mesh while it is visible); its spheres follow its \
                         transform"
                            .to_string()
                    });
                } else if !skin_joints(skinned, &inverse_bindposes, &transforms, &mut joints) {
                    warn_once(Problem::MissingJoint, &|| {
                        "has a joint entity that does not exist; that joint counts as the \
                         identity"
                            .to_string()
                    });
                }
            }
            let weights = mesh_morph_weights(morphs, &morph_weights);
            let pose = Pose {
                world_from_mesh: transform.affine(),
                joints: &joints,
                morph_weights: weights,
            };
            let dropped = refit(&fitted.mesh, &fitted.clustered, &pose, &mut out.spheres);
            if dropped > 0 {
                warn_once(Problem::NonFinite, &|| {
                    format!(
                        "has a non-finite transform, joint or morph weight; {dropped} of its \
                         spheres are left out while it lasts"
                    )
                });
            }
        }
        match spheres {
            Some(mut spheres) => *spheres = out,
            None => {
                commands.entity(entity).insert(out);
            }
        }
    }
}

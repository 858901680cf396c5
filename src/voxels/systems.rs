//! Main world, every frame after animation and transform propagation: the triangles of every
//! visible mesh that reaches into a volume, moved into that volume's grid space for the
//! voxelization pass.
//!
//! Skinning and morphing run here on the CPU (the same deformation the sphere occluders refit
//! with, linear in vertices) rather than in the voxelization shader: Bevy keeps its skinned
//! vertices inside its own vertex shader, and the CPU copy lets rigid meshes outside every
//! volume be culled by their bounding box before a single vertex is touched.

use std::sync::Arc;

use bevy::asset::{AssetId, Assets};
use bevy::camera::visibility::{InheritedVisibility, RenderLayers};
use bevy::core_pipeline::prepass::MotionVectorPrepass;
use bevy::ecs::prelude::*;
use bevy::ecs::system::SystemParam;
use bevy::log::warn;
use bevy::math::{Affine3A, Vec3, Vec3A};
use bevy::mesh::morph::{MeshMorphWeights, MorphWeights};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::mesh::{Mesh, Mesh3d};
use bevy::platform::collections::HashSet;
use bevy::prelude::{GlobalTransform, Name};

use super::component::{
    NotVoxelOccluder, ShowOccupiedVoxels, VoxelAoVolume, VoxelGridInfo, VoxelVolumeError,
    brick_words, grid_words,
};
use super::grid_data::{GpuVolume, GridTriangle, VoxelFrame};
use super::mesh_cache::{VoxelMesh, VoxelMeshCache};
use crate::geometry::deform::{Deformer, Pose, mesh_morph_weights, skin_joints};
use crate::geometry::rest_mesh::{RestMesh, RestMeshError};
use crate::settings::{AoTechnique, DynamicAo};
use crate::view::{layer_bits, on_every_layer_of};

/// What a warning is about; each entity is warned about each problem once.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) enum Problem {
    Volume,
    Clamped,
    Mesh,
    MissingJoint,
}

/// Warns once per entity and problem; `{label}` in a message becomes the entity's name and id.
struct Warnings<'a>(&'a mut HashSet<(Entity, Problem)>);

impl Warnings<'_> {
    fn warn(&mut self, entity: Entity, name: Option<&Name>, problem: Problem, message: &str) {
        if self.0.insert((entity, problem)) {
            let label = name.map_or_else(|| format!("{entity}"), |n| format!("'{n}' ({entity})"));
            warn!("{}", message.replace("{label}", &label));
        }
    }
}

type VolumeQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static VoxelAoVolume,
        &'static GlobalTransform,
        Has<ShowOccupiedVoxels>,
        Option<&'static Name>,
        Option<&'static RenderLayers>,
    ),
>;

type MeshQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static Mesh3d,
        &'static GlobalTransform,
        Option<&'static SkinnedMesh>,
        Option<&'static MeshMorphWeights>,
        Option<&'static InheritedVisibility>,
        Option<&'static Name>,
        Option<&'static RenderLayers>,
    ),
    Without<NotVoxelOccluder>,
>;

/// What posing a mesh reads besides its own components.
#[derive(SystemParam)]
pub(crate) struct PoseSources<'w, 's> {
    meshes: Res<'w, Assets<Mesh>>,
    inverse_bindposes: Res<'w, Assets<SkinnedMeshInverseBindposes>>,
    transforms: Query<'w, 's, &'static GlobalTransform>,
    morph_weights: Query<'w, 's, &'static MorphWeights>,
}

/// What the gather keeps from frame to frame: the warnings given, and buffers it reuses.
#[derive(Default)]
pub(crate) struct GatherState {
    warned: HashSet<(Entity, Problem)>,
    joints: Vec<Affine3A>,
    world_positions: Vec<Vec3A>,
}

/// A volume whose component was removed is no longer in use.
pub(crate) fn forget_removed_volumes(
    mut commands: Commands,
    orphans: Query<Entity, (With<VoxelGridInfo>, Without<VoxelAoVolume>)>,
) {
    for entity in &orphans {
        commands.entity(entity).remove::<VoxelGridInfo>();
    }
}

/// A volume in use this frame: its grid slot and its world-space bounds.
struct ActiveVolume {
    entity: Entity,
    /// Meshes on every one of these layers are voxelized into it.
    layers: Option<RenderLayers>,
    info: VoxelGridInfo,
    grid_from_world: Affine3A,
    resolution: f32,
    min: Vec3A,
    max: Vec3A,
}

impl ActiveVolume {
    fn overlaps(&self, min: Vec3A, max: Vec3A) -> bool {
        min.cmple(self.max).all() && max.cmpge(self.min).all()
    }
}

/// Builds [`VoxelFrame`] and the [`VoxelGridInfo`] of every volume.
pub(crate) fn gather_triangles(
    mut commands: Commands,
    volumes: VolumeQuery,
    meshes_query: MeshQuery,
    sources: PoseSources,
    mut cache: ResMut<VoxelMeshCache>,
    mut frame: ResMut<VoxelFrame>,
    mut state: Local<GatherState>,
) {
    let frame = &mut *frame;
    frame.volumes.clear();
    frame.triangles.clear();
    let GatherState {
        warned,
        joints,
        world_positions,
    } = &mut *state;
    let mut warnings = Warnings(warned);
    let (active, grid_words) =
        place_volumes(&mut commands, &volumes, &mut frame.volumes, &mut warnings);
    if active.is_empty() {
        return;
    }

    let mut counts = vec![0u32; active.len()];
    for (entity, mesh3d, transform, skinned, morphs, visibility, name, layers) in &meshes_query {
        if !visibility.is_none_or(|v| v.get()) {
            continue;
        }
        // A mesh still loading is tried again next frame.
        let Some(mesh) = cached_mesh(&mut cache, &sources.meshes, mesh3d.id()) else {
            continue;
        };
        let mesh = match mesh {
            Ok(mesh) => mesh,
            Err(error) => {
                let message = format!("VoxelAoVolume: mesh {{label}} is not voxelized: {error}");
                warnings.warn(entity, name, Problem::Mesh, &message);
                continue;
            }
        };
        joints.clear();
        if let Some(skinned) = skinned
            && mesh.rest.skin.is_some()
            && !skin_joints(
                skinned,
                &sources.inverse_bindposes,
                &sources.transforms,
                joints,
            )
        {
            warnings.warn(
                entity,
                name,
                Problem::MissingJoint,
                "VoxelAoVolume: mesh {label} has a joint entity that does not exist; that joint \
                 counts as the identity",
            );
        }
        let pose = Pose {
            world_from_mesh: transform.affine(),
            joints,
            morph_weights: mesh_morph_weights(morphs, &sources.morph_weights),
        };
        let Some((world_min, world_max)) = pose_mesh(&mesh, &pose, &active, world_positions) else {
            continue;
        };
        for (index, volume) in active.iter().enumerate() {
            // Every view that samples the volume must be one that draws the mesh.
            if !volume.overlaps(world_min, world_max)
                || !on_every_layer_of(layers, volume.layers.as_ref())
            {
                continue;
            }
            let before = frame.triangles.len();
            push_grid_triangles(
                &mesh.rest.triangles,
                world_positions,
                volume,
                index as u32,
                mesh.closed,
                &mut frame.triangles,
            );
            counts[index] += (frame.triangles.len() - before) as u32;
        }
    }
    for (volume, count) in active.iter().zip(counts) {
        let info = VoxelGridInfo {
            triangles: count,
            // The interior bits of every grid follow the surface bits of all of them.
            solid_offset: grid_words + volume.info.offset,
            ..volume.info
        };
        commands.entity(volume.entity).insert(info);
    }
}

/// Gives every valid volume its slot in the grid buffer, in entity order so that grid offsets
/// do not depend on query order, and warns about the others. Returns the volumes in use and the
/// words their surface grids take.
fn place_volumes(
    commands: &mut Commands,
    volumes: &VolumeQuery,
    gpu_volumes: &mut Vec<GpuVolume>,
    warnings: &mut Warnings,
) -> (Vec<ActiveVolume>, u32) {
    let mut sorted: Vec<_> = volumes.iter().collect();
    sorted.sort_by_key(|(entity, ..)| *entity);
    let mut active = Vec::new();
    let mut offset = 0u32;
    let mut brick_offset = 0u32;
    for (entity, volume, transform, show, name, layers) in sorted {
        let placed = volume.sanitized().and_then(|(volume, fixes)| {
            GpuVolume::new(&volume, transform.affine(), (offset, brick_offset), show)
                .map(|gpu| (volume, fixes, gpu))
                .ok_or(VoxelVolumeError::BadTransform)
        });
        let (volume, fixes, (mut gpu, grid_from_world, rays)) = match placed {
            Ok(placed) => placed,
            Err(error) => {
                let message = format!("VoxelAoVolume {{label}} casts no occlusion: {error}");
                warnings.warn(entity, name, Problem::Volume, &message);
                commands.entity(entity).remove::<VoxelGridInfo>();
                continue;
            }
        };
        if !fixes.is_empty() {
            let message = format!("VoxelAoVolume {{label}}: {}", fixes.join("; "));
            warnings.warn(entity, name, Problem::Clamped, &message);
        }
        let n = volume.resolution as f32;
        let (min, max) = box_bounds(grid_from_world.inverse(), Vec3::ZERO, Vec3::splat(n));
        gpu.layers = layer_bits(layers).to_array();
        active.push(ActiveVolume {
            entity,
            layers: layers.cloned(),
            info: VoxelGridInfo {
                grid_from_world,
                resolution: volume.resolution,
                offset,
                solid_offset: 0,
                triangles: 0,
                rays,
            },
            grid_from_world,
            resolution: n,
            min,
            max,
        });
        gpu_volumes.push(gpu);
        offset += grid_words(volume.resolution);
        brick_offset += brick_words(volume.resolution);
    }
    (active, offset)
}

/// The mesh `id` as voxelization needs it, copied out of its asset the first time; `None` while
/// the asset is still loading.
fn cached_mesh(
    cache: &mut VoxelMeshCache,
    meshes: &Assets<Mesh>,
    id: AssetId<Mesh>,
) -> Option<Result<Arc<VoxelMesh>, RestMeshError>> {
    if !cache.meshes.contains_key(&id) {
        let copied =
            RestMesh::from_mesh(meshes.get(id)?).map(|rest| Arc::new(VoxelMesh::new(rest)));
        cache.meshes.insert(id, copied);
    }
    Some(cache.meshes[&id].clone())
}

/// Moves the mesh's vertices into world space for this pose and returns their bounds, or `None`
/// for a rigid mesh whose bounding box reaches into no volume (its vertices are not touched).
fn pose_mesh(
    mesh: &VoxelMesh,
    pose: &Pose,
    active: &[ActiveVolume],
    world_positions: &mut Vec<Vec3A>,
) -> Option<(Vec3A, Vec3A)> {
    let rest = &mesh.rest;
    world_positions.clear();
    if Deformer::is_rigid(rest, pose) {
        let (min, max) = box_bounds(pose.world_from_mesh, mesh.lo, mesh.hi);
        if !active.iter().any(|v| v.overlaps(min, max)) {
            return None;
        }
        world_positions.extend(
            rest.positions
                .iter()
                .map(|p| pose.world_from_mesh.transform_point3a((*p).into())),
        );
        return Some((min, max));
    }
    let deformer = Deformer::new(rest, pose);
    world_positions.extend((0..rest.positions.len()).map(|v| deformer.point(v)));
    let (mut min, mut max) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
    for p in world_positions.iter() {
        min = min.min(*p);
        max = max.max(*p);
    }
    Some((min, max))
}

/// World-space bounds of the box `lo..hi` placed by `world_from_box`.
fn box_bounds(world_from_box: Affine3A, lo: Vec3, hi: Vec3) -> (Vec3A, Vec3A) {
    let (mut min, mut max) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
    for corner in 0..8 {
        let p = Vec3::new(
            if corner & 1 == 0 { lo.x } else { hi.x },
            if corner & 2 == 0 { lo.y } else { hi.y },
            if corner & 4 == 0 { lo.z } else { hi.z },
        );
        let p = world_from_box.transform_point3a(p.into());
        min = min.min(p);
        max = max.max(p);
    }
    (min, max)
}

/// Appends the finite triangles of one mesh that reach into `volume`, in its grid space, marked
/// when the mesh is closed.
fn push_grid_triangles(
    triangles: &[[u32; 3]],
    world_positions: &[Vec3A],
    volume: &ActiveVolume,
    volume_index: u32,
    closed: bool,
    out: &mut Vec<GridTriangle>,
) {
    let n = volume.resolution;
    let tag = f32::from_bits(volume_index);
    let closed_flag = if closed { 1.0 } else { 0.0 };
    for tri in triangles {
        let [a, b, c] = tri.map(|i| {
            volume
                .grid_from_world
                .transform_point3a(world_positions[i as usize])
        });
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            continue;
        }
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        // A closed mesh's triangles below the grid still count for the parity of the cells
        // above them.
        let below_counts = closed && hi.z < 0.0;
        if hi.x < 0.0 || hi.y < 0.0 || (hi.z < 0.0 && !below_counts) || lo.max_element() > n {
            continue;
        }
        out.push(GridTriangle {
            a: [a.x, a.y, a.z, tag],
            b: [b.x, b.y, b.z, closed_flag],
            c: [c.x, c.y, c.z, 0.0],
        });
    }
}

/// Cameras that accumulate the voxel term need Bevy's motion vectors, while any volume exists.
pub(crate) fn require_motion_vectors(
    mut commands: Commands,
    cameras: Query<(Entity, &DynamicAo), Without<MotionVectorPrepass>>,
    volumes: Query<(), With<VoxelAoVolume>>,
) {
    if volumes.is_empty() {
        return;
    }
    for (entity, ao) in &cameras {
        // Bevy's SSAO takes no far-field term.
        if ao.temporal.enabled && ao.voxels && ao.technique != AoTechnique::BevySsao {
            commands.entity(entity).insert(MotionVectorPrepass);
        }
    }
}

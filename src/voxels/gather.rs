//! Main world, every frame after animation and transform propagation: the triangles of every
//! visible mesh that reaches into a volume, moved into that volume's grid space for the
//! voxelization pass.
//!
//! Skinning and morphing run here on the CPU (the same deformation the sphere occluders refit
//! with, linear in vertices) rather than in the voxelization shader: Bevy keeps its skinned
//! vertices inside its own vertex shader, and the CPU copy lets rigid meshes outside every
//! volume be culled by their bounding box before a single vertex is touched.

use std::sync::Arc;

use bevy::asset::{AssetEvent, AssetId, Assets};
use bevy::camera::visibility::InheritedVisibility;
use bevy::ecs::prelude::*;
use bevy::log::warn;
use bevy::math::{Affine3A, Vec3, Vec3A};
use bevy::mesh::morph::{MeshMorphWeights, MorphWeights};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::mesh::{Mesh, Mesh3d};
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::{GlobalTransform, Name};
use bytemuck::{Pod, Zeroable};

use super::component::{
    NotVoxelOccluder, ShowOccupiedVoxels, VoxelAoVolume, VoxelFalloff, VoxelGridInfo, VoxelRays,
    grid_words,
};
use crate::geometry::closed::is_closed;
use crate::geometry::deform::{Deformer, Pose};
use crate::geometry::deform::{mesh_morph_weights, skin_joints};
use crate::geometry::rest_mesh::{RestMesh, RestMeshError};

/// One triangle in the grid space of one volume; `a[3]` holds the volume's index (as bits).
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GridTriangle {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
}

/// One volume as the shaders read it (`VoxelVolume` in `voxel_grid.wgsl`).
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuVolume {
    /// Rows of the world → grid affine map.
    pub grid_from_world: [[f32; 4]; 3],
    /// First word of the grid in the grid buffer.
    pub offset: u32,
    /// Cells per axis; 0 marks an unused slot.
    pub resolution: u32,
    pub rays: u32,
    /// Evenly spaced tests per ray; 0: every cell the ray crosses.
    pub steps: u32,
    /// cos of the cone half-angle the rays fill.
    pub cos_spread: f32,
    /// Metres; 0: the camera's radius.
    pub d_max: f32,
    /// How far rays start off the surface, metres: one voxel diagonal, so a ray never tests
    /// the voxels its own surface occupies.
    pub bias: f32,
    /// Size of the world-space cells the ray jitter is constant over, metres.
    pub noise_cell: f32,
    /// World-space size of one cell along each grid axis, metres.
    pub cell: [f32; 3],
    /// Bit 0: the occupied voxels are drawn (`ShowOccupiedVoxels`); bit 1: hits count without
    /// falloff (`VoxelFalloff::None`).
    pub flags: u32,
}

impl GpuVolume {
    /// The shader-side description of `volume` (already sanitized) placed by `world_from_volume`,
    /// with its grid → world map, or `None` when that transform leaves no volume.
    pub(crate) fn new(
        volume: &VoxelAoVolume,
        world_from_volume: Affine3A,
        offset: u32,
        show: bool,
    ) -> Option<(Self, Affine3A, VoxelRays)> {
        let n = volume.resolution as f32;
        // Grid cell (x, y, z) spans [x, x + 1]³; the box spans [−h, h] in the entity's space.
        let volume_from_grid = Affine3A::from_scale_rotation_translation(
            volume.half_extents * 2.0 / n,
            bevy::math::Quat::IDENTITY,
            -volume.half_extents,
        );
        let world_from_grid = world_from_volume * volume_from_grid;
        let det = world_from_grid.matrix3.determinant();
        if !world_from_grid.is_finite() || !det.is_finite() || det.abs() < 1e-12 {
            return None;
        }
        let grid_from_world = world_from_grid.inverse();
        let rays = VoxelRays::new(volume, grid_from_world);
        Some((
            Self {
                grid_from_world: Affine3ARows::from(grid_from_world).0,
                offset,
                resolution: volume.resolution,
                rays: rays.rays,
                steps: match rays.march {
                    super::VoxelMarch::Cells => 0,
                    super::VoxelMarch::Steps(steps) => steps,
                },
                cos_spread: rays.cos_spread,
                d_max: rays.d_max.unwrap_or(0.0),
                bias: rays.bias,
                noise_cell: rays.noise_cell,
                cell: rays.cell.to_array(),
                flags: u32::from(show) | (u32::from(rays.falloff == VoxelFalloff::None) << 1),
            },
            grid_from_world,
            rays,
        ))
    }
}

/// An affine map as three rows `[m0, m1, m2, t]`, the layout the shaders multiply with.
struct Affine3ARows([[f32; 4]; 3]);

impl From<Affine3A> for Affine3ARows {
    fn from(a: Affine3A) -> Self {
        let m = bevy::math::Mat3::from(a.matrix3).transpose();
        let t = a.translation;
        Self([
            [m.x_axis.x, m.x_axis.y, m.x_axis.z, t.x],
            [m.y_axis.x, m.y_axis.y, m.y_axis.z, t.y],
            [m.z_axis.x, m.z_axis.y, m.z_axis.z, t.z],
        ])
    }
}

/// What the render world receives each frame.
#[derive(Resource, Default)]
pub(crate) struct VoxelFrame {
    pub volumes: Vec<GpuVolume>,
    pub triangles: Vec<GridTriangle>,
}

/// A mesh as voxelization needs it, copied out of its asset once.
pub(crate) struct VoxelMesh {
    rest: RestMesh,
    /// Rest-pose bounds, mesh space.
    lo: Vec3,
    hi: Vec3,
    /// Every edge (with coinciding vertices welded) is shared by exactly two triangles, so the
    /// mesh encloses a volume and its interior can be filled.
    closed: bool,
}

impl VoxelMesh {
    fn new(rest: RestMesh) -> Self {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for p in &rest.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let closed = is_closed(
            rest.triangles
                .iter()
                .map(|t| t.map(|i| rest.positions[i as usize])),
        );
        Self {
            rest,
            lo,
            hi,
            closed,
        }
    }
}

/// Meshes copied out of their assets once.
#[derive(Resource, Default)]
pub(crate) struct VoxelMeshCache {
    meshes: HashMap<AssetId<Mesh>, Result<Arc<VoxelMesh>, RestMeshError>>,
}

pub(crate) fn forget_changed_meshes(
    mut cache: ResMut<VoxelMeshCache>,
    mut events: MessageReader<AssetEvent<Mesh>>,
) {
    for event in events.read() {
        if let AssetEvent::Modified { id } | AssetEvent::Removed { id } = event {
            cache.meshes.remove(id);
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) enum Problem {
    Volume,
    Clamped,
    Mesh,
    MissingJoint,
}

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
    ),
    Without<NotVoxelOccluder>,
>;

/// A volume in use this frame: its grid slot and its world-space bounds.
struct ActiveVolume {
    entity: Entity,
    info: VoxelGridInfo,
    grid_from_world: Affine3A,
    resolution: f32,
    min: Vec3A,
    max: Vec3A,
}

/// Builds [`VoxelFrame`] and the [`VoxelGridInfo`] of every volume.
#[allow(clippy::too_many_arguments)]
pub(crate) fn gather_triangles(
    mut commands: Commands,
    volumes: Query<(
        Entity,
        &VoxelAoVolume,
        &GlobalTransform,
        Has<ShowOccupiedVoxels>,
        Option<&Name>,
    )>,
    meshes_query: MeshQuery,
    orphans: Query<Entity, (With<VoxelGridInfo>, Without<VoxelAoVolume>)>,
    transforms: Query<&GlobalTransform>,
    morph_weights: Query<&MorphWeights>,
    meshes: Res<Assets<Mesh>>,
    inverse_bindposes: Res<Assets<SkinnedMeshInverseBindposes>>,
    mut cache: ResMut<VoxelMeshCache>,
    mut frame: ResMut<VoxelFrame>,
    mut warned: Local<HashSet<(Entity, Problem)>>,
    mut joints: Local<Vec<Affine3A>>,
    mut world_positions: Local<Vec<Vec3A>>,
) {
    frame.volumes.clear();
    frame.triangles.clear();
    // A volume whose component was removed is no longer in use.
    for entity in &orphans {
        commands.entity(entity).remove::<VoxelGridInfo>();
    }
    let mut warn_once = |entity: Entity, name: Option<&Name>, problem: Problem, message: String| {
        if warned.insert((entity, problem)) {
            let label = name.map_or_else(|| format!("{entity}"), |n| format!("'{n}' ({entity})"));
            warn!("{message}", message = message.replace("{label}", &label));
        }
    };

    // Volumes in entity order, so grid offsets do not depend on query order.
    let mut sorted: Vec<_> = volumes.iter().collect();
    sorted.sort_by_key(|(entity, ..)| *entity);
    let mut active = Vec::new();
    let mut offset = 0u32;
    for (entity, volume, transform, show, name) in sorted {
        let placed = volume.sanitized().and_then(|(volume, fixes)| {
            GpuVolume::new(&volume, transform.affine(), offset, show)
                .map(|gpu| (volume, fixes, gpu))
                .ok_or(super::VoxelVolumeError::BadTransform)
        });
        let (volume, fixes, (gpu, grid_from_world, rays)) = match placed {
            Ok(placed) => placed,
            Err(error) => {
                warn_once(
                    entity,
                    name,
                    Problem::Volume,
                    format!("VoxelAoVolume {{label}} casts no occlusion: {error}"),
                );
                commands.entity(entity).remove::<VoxelGridInfo>();
                continue;
            }
        };
        if !fixes.is_empty() {
            warn_once(
                entity,
                name,
                Problem::Clamped,
                format!("VoxelAoVolume {{label}}: {}", fixes.join("; ")),
            );
        }
        let world_from_grid = grid_from_world.inverse();
        let n = volume.resolution as f32;
        let (mut min, mut max) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for corner in 0..8 {
            let g = Vec3A::new(
                if corner & 1 == 0 { 0.0 } else { n },
                if corner & 2 == 0 { 0.0 } else { n },
                if corner & 4 == 0 { 0.0 } else { n },
            );
            let p = world_from_grid.transform_point3a(g);
            min = min.min(p);
            max = max.max(p);
        }
        active.push(ActiveVolume {
            entity,
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
        frame.volumes.push(gpu);
        offset += grid_words(volume.resolution);
    }
    if active.is_empty() {
        return;
    }

    let mut counts = vec![0u32; active.len()];
    for (entity, mesh3d, transform, skinned, morphs, visibility, name) in &meshes_query {
        if !visibility.is_none_or(|v| v.get()) {
            continue;
        }
        let id = mesh3d.id();
        if !cache.meshes.contains_key(&id) {
            // A mesh still loading is tried again next frame.
            let Some(mesh) = meshes.get(id) else {
                continue;
            };
            let copied = RestMesh::from_mesh(mesh).map(|rest| Arc::new(VoxelMesh::new(rest)));
            cache.meshes.insert(id, copied);
        }
        let rest = match &cache.meshes[&id] {
            Ok(rest) => rest.clone(),
            Err(error) => {
                warn_once(
                    entity,
                    name,
                    Problem::Mesh,
                    format!("VoxelAoVolume: mesh {{label}} is not voxelized: {error}"),
                );
                continue;
            }
        };
        let (closed, lo, hi) = (rest.closed, rest.lo, rest.hi);
        let rest = &rest.rest;

        joints.clear();
        if let Some(skinned) = skinned
            && rest.skin.is_some()
            && !skin_joints(skinned, &inverse_bindposes, &transforms, &mut joints)
        {
            warn_once(
                entity,
                name,
                Problem::MissingJoint,
                "VoxelAoVolume: mesh {label} has a joint entity that does not exist; that joint \
                 counts as the identity"
                    .to_string(),
            );
        }
        let pose = Pose {
            world_from_mesh: transform.affine(),
            joints: &joints,
            morph_weights: mesh_morph_weights(morphs, &morph_weights),
        };
        let rigid = Deformer::is_rigid(rest, &pose);
        let (mut world_min, mut world_max) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        if rigid {
            for corner in 0..8 {
                let p = Vec3::new(
                    if corner & 1 == 0 { lo.x } else { hi.x },
                    if corner & 2 == 0 { lo.y } else { hi.y },
                    if corner & 4 == 0 { lo.z } else { hi.z },
                );
                let p = pose.world_from_mesh.transform_point3a(p.into());
                world_min = world_min.min(p);
                world_max = world_max.max(p);
            }
        }
        let overlaps = |v: &ActiveVolume, min: Vec3A, max: Vec3A| {
            min.cmple(v.max).all() && max.cmpge(v.min).all()
        };
        if rigid && !active.iter().any(|v| overlaps(v, world_min, world_max)) {
            continue;
        }
        world_positions.clear();
        if rigid {
            world_positions.extend(
                rest.positions
                    .iter()
                    .map(|p| pose.world_from_mesh.transform_point3a((*p).into())),
            );
        } else {
            let deformer = Deformer::new(rest, &pose);
            world_positions.extend((0..rest.positions.len()).map(|v| deformer.point(v)));
            for p in world_positions.iter() {
                world_min = world_min.min(*p);
                world_max = world_max.max(*p);
            }
        }
        for (index, volume) in active.iter().enumerate() {
            if !overlaps(volume, world_min, world_max) {
                continue;
            }
            let before = frame.triangles.len();
            push_grid_triangles(
                &rest.triangles,
                &world_positions,
                volume,
                index as u32,
                closed,
                &mut frame.triangles,
            );
            counts[index] += (frame.triangles.len() - before) as u32;
        }
    }
    for (volume, count) in active.iter().zip(counts) {
        let info = VoxelGridInfo {
            triangles: count,
            solid_offset: offset + volume.info.offset,
            ..volume.info
        };
        commands.entity(volume.entity).insert(info);
    }
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

//! Meshes as voxelization needs them (rest pose, bounds, closedness), copied out of their assets
//! once and forgotten when the asset changes.

use std::sync::Arc;

use bevy::asset::{AssetEvent, AssetId};
use bevy::ecs::prelude::*;
use bevy::math::Vec3;
use bevy::mesh::Mesh;
use bevy::platform::collections::HashMap;

use crate::geometry::closed::is_closed;
use crate::geometry::rest_mesh::{RestMesh, RestMeshError};

/// A mesh as voxelization needs it, copied out of its asset once.
pub(crate) struct VoxelMesh {
    pub rest: RestMesh,
    /// Rest-pose bounds, mesh space.
    pub lo: Vec3,
    pub hi: Vec3,
    /// Every edge (with coinciding vertices welded) is shared by exactly two triangles, so the
    /// mesh encloses a volume and its interior can be filled.
    pub closed: bool,
}

impl VoxelMesh {
    pub fn new(rest: RestMesh) -> Self {
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
    pub meshes: HashMap<AssetId<Mesh>, Result<Arc<VoxelMesh>, RestMeshError>>,
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

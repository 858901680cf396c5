//! The triangles a Bevy world draws this frame, in world space and in their current pose: skinned
//! and morphed meshes deformed on the CPU as Bevy's vertex shader deforms them. Ground truth for
//! whole scenes (glTF files with animated characters) traces these.

use bevy::camera::visibility::InheritedVisibility;
use bevy::ecs::prelude::*;
use bevy::ecs::system::SystemState;
use bevy::math::{Affine3A, Vec3};
use bevy::mesh::morph::{MeshMorphWeights, MorphWeights};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::mesh::{Mesh, Mesh3d};
use bevy::prelude::{Assets, Children, GlobalTransform};

use crate::geometry::deform::{Deformer, Pose};
use crate::geometry::deform::{mesh_morph_weights, skin_joints};
use crate::geometry::rest_mesh::RestMesh;
use crate::geometry::triangles::{Triangle, TriangleScene};

type Meshes<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static Mesh3d,
        &'static GlobalTransform,
        Option<&'static SkinnedMesh>,
        Option<&'static MeshMorphWeights>,
        Option<&'static InheritedVisibility>,
    ),
>;

/// Every entity below `root` in the hierarchy, `root` included: a spawned scene's, for
/// [`posed_triangles_of`].
pub fn descendants(world: &World, root: Entity) -> Vec<Entity> {
    let mut out = vec![root];
    let mut i = 0;
    while i < out.len() {
        if let Some(children) = world.get::<Children>(out[i]) {
            out.extend(children.iter());
        }
        i += 1;
    }
    out
}

/// Every visible mesh of `world` as world-space triangles in its current pose (run it after
/// `PostUpdate`, when transforms have propagated). Meshes of points or lines, or whose
/// data lives only in the render world, add nothing; their count is in
/// [`TriangleScene::skipped`] together with degenerate triangles.
pub fn posed_triangles(world: &mut World) -> TriangleScene {
    posed_triangles_of(world, |_| true)
}

/// Like [`posed_triangles`], for the meshes whose entity `keep` accepts.
pub fn posed_triangles_of(world: &mut World, keep: impl Fn(Entity) -> bool) -> TriangleScene {
    let mut state: SystemState<(
        Meshes,
        Query<&GlobalTransform>,
        Query<&MorphWeights>,
        Res<Assets<Mesh>>,
        Res<Assets<SkinnedMeshInverseBindposes>>,
    )> = SystemState::new(world);
    let mut scene = TriangleScene::default();
    // Without mesh assets (a world without rendering) there is nothing to pose.
    let Ok((meshes, transforms, morph_weights, assets, bindposes)) = state.get(world) else {
        return scene;
    };
    let mut joints: Vec<Affine3A> = Vec::new();
    for (entity, mesh3d, transform, skinned, morphs, visibility) in &meshes {
        if !keep(entity) || !visibility.is_none_or(|v| v.get()) {
            continue;
        }
        let Some(rest) = assets
            .get(mesh3d.id())
            .and_then(|m| RestMesh::from_mesh(m).ok())
        else {
            scene.skipped += 1;
            continue;
        };
        joints.clear();
        if let Some(skinned) = skinned
            && rest.skin.is_some()
        {
            skin_joints(skinned, &bindposes, &transforms, &mut joints);
        }
        let pose = Pose {
            world_from_mesh: transform.affine(),
            joints: &joints,
            morph_weights: mesh_morph_weights(morphs, &morph_weights),
        };
        let deformer = Deformer::new(&rest, &pose);
        let positions: Vec<Vec3> = (0..rest.positions.len())
            .map(|v| deformer.point(v).into())
            .collect();
        let normals: Vec<Vec3> = (0..rest.positions.len())
            .map(|v| deformer.normal(v).into())
            .collect();
        for t in &rest.triangles {
            let vertices = t.map(|i| positions[i as usize]);
            let corner_normals = t.map(|i| normals[i as usize]);
            let triangle = Triangle {
                vertices,
                normals: corner_normals
                    .iter()
                    .all(|n| n.is_finite() && *n != Vec3::ZERO)
                    .then_some(corner_normals),
            };
            if vertices.iter().all(|v| v.is_finite())
                && triangle.face_normal().length_squared() > f32::MIN_POSITIVE
            {
                scene.triangles.push(triangle);
            } else {
                scene.skipped += 1;
            }
        }
    }
    scene
}

//! Deforming a rest mesh into world space for one pose, as Bevy's vertex shader does: morph
//! targets first, then linear blend skinning. Sphere refitting, AO field baking, voxelization and
//! the CPU reference all pose meshes through this one module.

use bevy::asset::Assets;
use bevy::ecs::prelude::*;
use bevy::math::{Affine3A, Mat3A, Vec3A};
use bevy::mesh::morph::{MeshMorphWeights, MorphWeights};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::prelude::GlobalTransform;

use super::rest_mesh::{RestMesh, VertexSkin};

/// The pose of one mesh this frame.
#[derive(Clone, Copy, Debug)]
pub struct Pose<'a> {
    /// Mesh space to world space; what a mesh without skin follows.
    pub world_from_mesh: Affine3A,
    /// Per joint of the skin: the joint's world transform × its inverse bind pose. Empty for a
    /// mesh without skin. Like Bevy's skinning, a skinned mesh ignores `world_from_mesh`.
    pub joints: &'a [Affine3A],
    /// Morph target weights (missing ones count as 0).
    pub morph_weights: &'a [f32],
}

/// Deforms the vertices of a rest mesh into world space for one pose: morph targets first, then
/// linear blend skinning, as Bevy's vertex shader does.
pub struct Deformer<'a> {
    mesh: &'a RestMesh,
    pose: &'a Pose<'a>,
    skin: Option<&'a [VertexSkin]>,
    morph_weights: Vec<(usize, f32)>,
}

impl<'a> Deformer<'a> {
    /// Prepares the deformation of `mesh` in `pose`.
    pub fn new(mesh: &'a RestMesh, pose: &'a Pose<'a>) -> Self {
        Self {
            mesh,
            pose,
            skin: mesh.skin.as_deref().filter(|_| !pose.joints.is_empty()),
            morph_weights: pose
                .morph_weights
                .iter()
                .take(mesh.morph_targets)
                .copied()
                .enumerate()
                .filter(|(_, w)| *w != 0.0)
                .collect(),
        }
    }

    /// Whether `pose` moves `mesh` as a rigid body (no skin, no active morph target), so its
    /// world-space vertices are `world_from_mesh` applied to the rest positions.
    pub fn is_rigid(mesh: &RestMesh, pose: &Pose) -> bool {
        let skinned = mesh.skin.is_some() && !pose.joints.is_empty();
        let morphing = mesh.morph_targets > 0 && pose.morph_weights.iter().any(|w| *w != 0.0);
        !skinned && !morphing
    }

    /// World-space position of vertex `v`.
    pub fn point(&self, v: usize) -> Vec3A {
        let mesh = self.mesh;
        let mut p = Vec3A::from(mesh.positions[v]);
        let vertex_count = mesh.positions.len();
        for &(target, weight) in &self.morph_weights {
            p += Vec3A::from(mesh.morph_positions[target * vertex_count + v]) * weight;
        }
        match self.skin {
            Some(_) => self
                .joints_of(v)
                .map(|(joint, weight)| joint.transform_point3a(p) * weight)
                .sum(),
            None => self.pose.world_from_mesh.transform_point3a(p),
        }
    }

    /// The joints that move skinned vertex `v` with their (positive) weights; a joint index past
    /// the pose's joints stands still.
    fn joints_of(&self, v: usize) -> impl Iterator<Item = (&Affine3A, f32)> {
        let skin = self.skin.map(|skin| &skin[v]);
        (0..4).filter_map(move |k| {
            let s = skin?;
            (s.weights[k] > 0.0).then(|| {
                let joint = self
                    .pose
                    .joints
                    .get(s.joints[k] as usize)
                    .unwrap_or(&Affine3A::IDENTITY);
                (joint, s.weights[k])
            })
        })
    }

    /// World-space unit normal of vertex `v` (zero where the mesh gives none): the rest normal
    /// turned by the inverse transpose of the blended skin matrix, or of `world_from_mesh`.
    /// Morph targets do not move normals here.
    pub fn normal(&self, v: usize) -> Vec3A {
        let Some(&n) = self.mesh.normals.get(v) else {
            return Vec3A::ZERO;
        };
        let linear = match self.skin {
            Some(_) => self
                .joints_of(v)
                .fold(Mat3A::ZERO, |m, (joint, weight)| m + joint.matrix3 * weight),
            None => self.pose.world_from_mesh.matrix3,
        };
        (linear.inverse().transpose() * Vec3A::from(n)).normalize_or_zero()
    }
}

/// Fills `out` with the skinning matrices of `skinned` (each joint's world transform × its
/// inverse bind pose), as Bevy's skinning uses them. Returns false when a joint entity is
/// missing (it counts as the identity). Leaves `out` empty while the bind poses are loading.
pub fn skin_joints(
    skinned: &SkinnedMesh,
    inverse_bindposes: &Assets<SkinnedMeshInverseBindposes>,
    transforms: &Query<&GlobalTransform>,
    out: &mut Vec<Affine3A>,
) -> bool {
    out.clear();
    let Some(bindposes) = inverse_bindposes.get(&skinned.inverse_bindposes) else {
        return true;
    };
    let mut all_found = true;
    for (i, joint) in skinned.joints.iter().enumerate() {
        let world = transforms.get(*joint).map(|t| t.affine());
        all_found &= world.is_ok();
        let bindpose = bindposes.get(i).copied().unwrap_or_default();
        out.push(world.unwrap_or_default() * Affine3A::from_mat4(bindpose));
    }
    all_found
}

/// The morph target weights a mesh is drawn with this frame.
pub fn mesh_morph_weights<'a>(
    morphs: Option<&'a MeshMorphWeights>,
    owners: &'a Query<&MorphWeights>,
) -> &'a [f32] {
    match morphs {
        Some(MeshMorphWeights::Value { weights }) => weights,
        Some(MeshMorphWeights::Reference(owner)) => {
            owners.get(*owner).map(|w| w.weights()).unwrap_or_default()
        }
        None => &[],
    }
}

//! The rest-pose data of a mesh that sphere fitting needs, copied out of a Bevy [`Mesh`] once.

use bevy::math::Vec3;
use bevy::mesh::{Mesh, PrimitiveTopology, VertexAttributeValues};

use super::triangles::triangle_corners;

/// Why a mesh cannot carry spheres.
#[derive(Clone, Debug, PartialEq)]
pub enum RestMeshError {
    /// Only triangles (lists and strips) are clustered.
    NotTriangles(PrimitiveTopology),
    /// The mesh has no `Float32x3` positions.
    NoPositions,
    /// The mesh has no vertex that is part of a non-degenerate, finite triangle.
    NoTriangles,
    /// The mesh's data lives only in the render world (`RenderAssetUsages` without
    /// `MAIN_WORLD`), so the CPU cannot read its vertices.
    NotInMainWorld,
}

impl std::fmt::Display for RestMeshError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotTriangles(topology) => {
                write!(
                    f,
                    "its topology is {topology:?}; only triangle lists and strips are supported"
                )
            }
            Self::NoPositions => write!(f, "it has no Float32x3 vertex positions"),
            Self::NoTriangles => write!(f, "it has no non-degenerate, finite triangle"),
            Self::NotInMainWorld => write!(
                f,
                "its vertex data was moved to the render world (RenderAssetUsages without \
                 MAIN_WORLD), so the CPU cannot read it"
            ),
        }
    }
}

impl std::error::Error for RestMeshError {}

/// Skin data of one vertex: four joint indices (into `SkinnedMesh::joints`) and their weights.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexSkin {
    /// Joint indices.
    pub joints: [u16; 4],
    /// Weights, summing to 1.
    pub weights: [f32; 4],
}

/// Rest-pose vertices of a mesh in the mesh's own space.
#[derive(Clone, Debug, Default)]
pub struct RestMesh {
    /// Positions, mesh space, metres.
    pub positions: Vec<Vec3>,
    /// Unit normals (from the mesh, or area-weighted face normals where it has none).
    pub normals: Vec<Vec3>,
    /// Surface area each vertex stands for: a third of the area of every triangle that uses it
    /// (0 for vertices no triangle uses), m².
    pub areas: Vec<f32>,
    /// Triangles as vertex indices; degenerate and non-finite ones are left out.
    pub triangles: Vec<[u32; 3]>,
    /// Joints and weights per vertex, when the mesh is skinned.
    pub skin: Option<Vec<VertexSkin>>,
    /// Morph target position offsets, `targets × vertices`, target-major.
    pub morph_positions: Vec<Vec3>,
    /// How many morph targets `morph_positions` holds.
    pub morph_targets: usize,
}

impl RestMesh {
    /// Copies what sphere fitting needs out of `mesh`.
    pub fn from_mesh(mesh: &Mesh) -> Result<Self, RestMeshError> {
        let topology = mesh.primitive_topology();
        let positions = match mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION) {
            Err(_) => return Err(RestMeshError::NotInMainWorld),
            Ok(Some(VertexAttributeValues::Float32x3(p))) => p,
            Ok(_) => return Err(RestMeshError::NoPositions),
        };
        let positions: Vec<Vec3> = positions.iter().map(|&p| Vec3::from(p)).collect();
        let indices: Vec<usize> = match mesh.try_indices_option() {
            Err(_) => return Err(RestMeshError::NotInMainWorld),
            Ok(Some(indices)) => indices.iter().collect(),
            Ok(None) => (0..positions.len()).collect(),
        };
        let indices =
            triangle_corners(topology, indices).ok_or(RestMeshError::NotTriangles(topology))?;
        let normals = match mesh.try_attribute_option(Mesh::ATTRIBUTE_NORMAL) {
            Ok(Some(VertexAttributeValues::Float32x3(n))) if n.len() == positions.len() => Some(
                n.iter()
                    .map(|&n| Vec3::from(n).normalize_or_zero())
                    .collect::<Vec<_>>(),
            ),
            _ => None,
        };
        let skin = Self::skin(mesh, positions.len());
        let (morph_positions, morph_targets) = Self::morphs(mesh, positions.len());
        Self::new(
            positions,
            normals,
            &indices,
            skin,
            morph_positions,
            morph_targets,
        )
    }

    /// Builds the rest mesh from raw arrays. `normals`, when given, must match `positions`;
    /// without them, area-weighted face normals are used.
    pub fn new(
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        indices: &[usize],
        skin: Option<Vec<VertexSkin>>,
        morph_positions: Vec<Vec3>,
        morph_targets: usize,
    ) -> Result<Self, RestMeshError> {
        let count = positions.len();
        let mut areas = vec![0.0; count];
        let mut face_normals = vec![Vec3::ZERO; count];
        let mut triangles = Vec::with_capacity(indices.len() / 3);
        for tri in indices.chunks_exact(3) {
            if tri.iter().any(|&i| i >= count) {
                continue;
            }
            let [a, b, c] = [0, 1, 2].map(|k| positions[tri[k]]);
            let cross = (b - a).cross(c - a);
            let area = 0.5 * cross.length();
            if !area.is_finite() || area <= f32::MIN_POSITIVE {
                continue;
            }
            for &i in tri {
                areas[i] += area / 3.0;
                face_normals[i] += cross;
            }
            triangles.push([tri[0] as u32, tri[1] as u32, tri[2] as u32]);
        }
        if triangles.is_empty() {
            return Err(RestMeshError::NoTriangles);
        }
        let normals = normals
            .filter(|n| n.len() == count)
            .unwrap_or_else(|| face_normals.iter().map(|n| n.normalize_or_zero()).collect());
        let skin = skin.filter(|s| s.len() == count);
        let morph_targets = if morph_positions.len() == morph_targets * count {
            morph_targets
        } else {
            0
        };
        Ok(Self {
            positions,
            normals,
            areas,
            triangles,
            skin,
            morph_positions: if morph_targets > 0 {
                morph_positions
            } else {
                Vec::new()
            },
            morph_targets,
        })
    }

    /// Joints and normalized weights per vertex; `None` without both skin attributes.
    fn skin(mesh: &Mesh, count: usize) -> Option<Vec<VertexSkin>> {
        let joints = match mesh.try_attribute_option(Mesh::ATTRIBUTE_JOINT_INDEX) {
            Ok(Some(VertexAttributeValues::Uint16x4(j))) => j,
            _ => return None,
        };
        let weights = match mesh.try_attribute_option(Mesh::ATTRIBUTE_JOINT_WEIGHT) {
            Ok(Some(VertexAttributeValues::Float32x4(w))) => w,
            _ => return None,
        };
        if joints.len() != count || weights.len() != count {
            return None;
        }
        Some(
            joints
                .iter()
                .zip(weights)
                .map(|(&joints, &weights)| {
                    let weights = weights.map(|w| if w.is_finite() { w.max(0.0) } else { 0.0 });
                    let sum: f32 = weights.iter().sum();
                    VertexSkin {
                        joints,
                        // Like Bevy's skinning shader, a vertex without weight follows joint 0.
                        weights: if sum > 0.0 {
                            weights.map(|w| w / sum)
                        } else {
                            [1.0, 0.0, 0.0, 0.0]
                        },
                    }
                })
                .collect(),
        )
    }

    fn morphs(mesh: &Mesh, count: usize) -> (Vec<Vec3>, usize) {
        match mesh.try_morph_targets() {
            Ok(targets) if count > 0 && targets.len() % count == 0 => (
                targets.iter().map(|t| t.position).collect(),
                targets.len() / count,
            ),
            _ => (Vec::new(), 0),
        }
    }
}

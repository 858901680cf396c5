//! Triangles of Bevy meshes in world space, for the ray tracer.

use bevy::math::{Affine3A, Vec3};
use bevy::mesh::{Mesh, PrimitiveTopology, VertexAttributeValues};

/// One world-space triangle with optional per-vertex normals.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// World-space corners, counter-clockwise seen from the front.
    pub vertices: [Vec3; 3],
    /// Unit vertex normals, when the mesh has them.
    pub normals: Option<[Vec3; 3]>,
}

impl Triangle {
    /// Unnormalized geometric normal (counter-clockwise winding).
    pub fn face_normal(&self) -> Vec3 {
        let [a, b, c] = self.vertices;
        (b - a).cross(c - a)
    }
}

/// A triangle soup.
#[derive(Clone, Debug, Default)]
pub struct TriangleScene {
    /// The triangles kept.
    pub triangles: Vec<Triangle>,
    /// Triangles dropped because they were degenerate or not finite.
    pub skipped: usize,
}

/// The axis-aligned bounds (min, max) of `triangles`; (+∞, −∞) when there are none.
pub fn triangle_bounds(triangles: &[Triangle]) -> (Vec3, Vec3) {
    triangles
        .iter()
        .flat_map(|t| t.vertices)
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

impl TriangleScene {
    /// The axis-aligned bounds (min, max) of the triangles kept; (+∞, −∞) when there are none.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        triangle_bounds(&self.triangles)
    }

    /// Adds the triangles of `mesh` placed by `world_from_local`. Meshes that are not
    /// triangle lists, lack positions or keep their data only in the render world add nothing; degenerate or non-finite triangles are
    /// counted in [`TriangleScene::skipped`].
    pub fn add_mesh(&mut self, mesh: &Mesh, world_from_local: Affine3A) {
        if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
            return;
        }
        // The `try_` accessors: a mesh whose data lives only in the render world makes the
        // plain ones panic.
        let Ok(Some(VertexAttributeValues::Float32x3(positions))) =
            mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION)
        else {
            return;
        };
        let normals = match mesh.try_attribute_option(Mesh::ATTRIBUTE_NORMAL) {
            Ok(Some(VertexAttributeValues::Float32x3(normals)))
                if normals.len() == positions.len() =>
            {
                Some(normals)
            }
            _ => None,
        };
        let normal_matrix = world_from_local.matrix3.inverse().transpose();
        let indices: Vec<usize> = match mesh.try_indices_option() {
            Ok(Some(indices)) => indices.iter().collect(),
            _ => (0..positions.len()).collect(),
        };
        for tri in indices.chunks_exact(3) {
            if tri.iter().any(|&i| i >= positions.len()) {
                self.skipped += 1;
                continue;
            }
            let vertices =
                [0, 1, 2].map(|k| world_from_local.transform_point3(positions[tri[k]].into()));
            let triangle = Triangle {
                vertices,
                normals: normals.map(|n| {
                    [0, 1, 2].map(|k| (normal_matrix * Vec3::from(n[tri[k]])).normalize_or_zero())
                }),
            };
            let finite = vertices.iter().all(|v| v.is_finite());
            if !finite || triangle.face_normal().length_squared() <= f32::MIN_POSITIVE {
                self.skipped += 1;
                continue;
            }
            self.triangles.push(triangle);
        }
    }
}

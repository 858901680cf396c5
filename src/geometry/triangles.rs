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

/// The corners of a mesh's triangles, three vertex indices per triangle, from its topology and
/// its index buffer (or `0..n` without one): a triangle list as it is, a triangle strip unrolled
/// with every second triangle's first two corners swapped, as the rasterizer winds them. `None`
/// for points and lines, which have no triangles.
pub fn triangle_corners(topology: PrimitiveTopology, indices: Vec<usize>) -> Option<Vec<usize>> {
    match topology {
        PrimitiveTopology::TriangleList => Some(indices),
        PrimitiveTopology::TriangleStrip => Some(
            indices
                .windows(3)
                .enumerate()
                .flat_map(|(i, w)| {
                    if i % 2 == 0 {
                        [w[0], w[1], w[2]]
                    } else {
                        [w[1], w[0], w[2]]
                    }
                })
                .collect(),
        ),
        _ => None,
    }
}

impl TriangleScene {
    /// The axis-aligned bounds (min, max) of the triangles kept; (+∞, −∞) when there are none.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        triangle_bounds(&self.triangles)
    }

    /// Adds the triangles of `mesh` placed by `world_from_local`. Meshes of points or lines, and
    /// meshes that lack positions or keep their data only in the render world, add nothing;
    /// degenerate or non-finite triangles are counted in [`TriangleScene::skipped`].
    pub fn add_mesh(&mut self, mesh: &Mesh, world_from_local: Affine3A) {
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
        let Some(corners) = triangle_corners(mesh.primitive_topology(), indices) else {
            return;
        };
        for tri in corners.chunks_exact(3) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::asset::RenderAssetUsages;
    use bevy::mesh::Indices;

    fn quad(topology: PrimitiveTopology, indices: Vec<u32>) -> Mesh {
        Mesh::new(topology, RenderAssetUsages::default())
            .with_inserted_attribute(
                Mesh::ATTRIBUTE_POSITION,
                vec![
                    [0.0f32, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [1.0, 1.0, 0.0],
                ],
            )
            .with_inserted_indices(Indices::U32(indices))
    }

    #[test]
    fn a_strip_gives_the_triangles_of_the_same_list_wound_alike() {
        let mut list = TriangleScene::default();
        list.add_mesh(
            &quad(PrimitiveTopology::TriangleList, vec![0, 1, 2, 2, 1, 3]),
            Affine3A::IDENTITY,
        );
        let mut strip = TriangleScene::default();
        strip.add_mesh(
            &quad(PrimitiveTopology::TriangleStrip, vec![0, 1, 2, 3]),
            Affine3A::IDENTITY,
        );
        assert_eq!(strip.triangles.len(), 2);
        let rest = crate::geometry::rest_mesh::RestMesh::from_mesh(&quad(
            PrimitiveTopology::TriangleStrip,
            vec![0, 1, 2, 3],
        ))
        .expect("a strip is triangles");
        assert_eq!(rest.triangles, vec![[0, 1, 2], [2, 1, 3]]);
        for (a, b) in list.triangles.iter().zip(&strip.triangles) {
            assert_eq!(a.vertices, b.vertices);
            // Both face +z, as the list winds them (counter-clockwise seen from the front).
            assert!(b.face_normal().z > 0.0);
        }
    }

    #[test]
    fn points_and_lines_have_no_triangles() {
        for topology in [PrimitiveTopology::PointList, PrimitiveTopology::LineList] {
            let mut scene = TriangleScene::default();
            scene.add_mesh(&quad(topology, vec![0, 1, 2, 3]), Affine3A::IDENTITY);
            assert!(scene.triangles.is_empty(), "{topology:?}");
            assert_eq!(triangle_corners(topology, vec![0, 1, 2]), None);
        }
    }
}

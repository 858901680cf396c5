//! Whether a triangle soup encloses a volume.

use bevy::math::{IVec3, Vec3};
use bevy::platform::collections::HashMap;

/// Vertices closer than this share of the mesh's largest extent are one vertex for
/// [`encloses_volume`]. Meshes split vertices along hard edges and texture seams; where a seam's
/// copies are computed from different angles (0 and 2π in Bevy's UV sphere, torus and cylinder)
/// they differ in the last bits.
pub const WELD_TOLERANCE: f32 = 1e-5;

/// Whether every edge of a triangle soup, with vertices at exactly the same position welded,
/// belongs to exactly two triangles: what the voxel grid's parity fill needs, whose rule counts
/// an edge once only where both its triangles have exactly that edge (a seam whose copies differ
/// in their last bits could flip a column twice or not at all).
pub fn is_closed(triangles: impl IntoIterator<Item = [Vec3; 3]>) -> bool {
    let mut welded: HashMap<[u32; 3], u32> = HashMap::default();
    let mut id = |p: Vec3| {
        let next = welded.len() as u32;
        *welded.entry(p.to_array().map(f32::to_bits)).or_insert(next)
    };
    let mut ids = Vec::new();
    for triangle in triangles {
        let corners = triangle.map(&mut id);
        if corners[0] == corners[1] || corners[1] == corners[2] || corners[2] == corners[0] {
            return false;
        }
        ids.extend(corners);
    }
    edges_shared_twice(&ids)
}

/// Whether a triangle soup encloses a volume: every edge, with vertices within
/// [`WELD_TOLERANCE`] of the mesh's size welded, belongs to exactly two triangles. Triangles
/// that welding collapses (a UV sphere's rows at its poles) have no area and are left out.
/// Bevy's UV sphere, torus and cylinder enclose a volume and are not [`is_closed`].
pub fn encloses_volume(triangles: impl IntoIterator<Item = [Vec3; 3]>) -> bool {
    let triangles: Vec<[Vec3; 3]> = triangles.into_iter().collect();
    let ids: Vec<u32> = weld(triangles.iter().flatten().copied())
        .chunks_exact(3)
        .filter(|c| c[0] != c[1] && c[1] != c[2] && c[2] != c[0])
        .flatten()
        .copied()
        .collect();
    edges_shared_twice(&ids)
}

/// Whether the triangles (three vertex ids each) have edges, each shared by exactly two of them.
fn edges_shared_twice(ids: &[u32]) -> bool {
    let mut edges: HashMap<(u32, u32), u32> = HashMap::default();
    for corners in ids.chunks_exact(3) {
        for k in 0..3 {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    !edges.is_empty() && edges.values().all(|&count| count == 2)
}

/// One id per point, the same for points within [`WELD_TOLERANCE`] of the points' extent: each
/// point is looked for in its grid cell and the cells around it (a cell is the tolerance wide).
fn weld(points: impl Iterator<Item = Vec3>) -> Vec<u32> {
    let points: Vec<Vec3> = points.collect();
    let (lo, hi) = points.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let extent = (hi - lo).max_element();
    if !extent.is_finite() || extent <= 0.0 {
        return (0..points.len() as u32).collect();
    }
    let cell = extent * WELD_TOLERANCE;
    let key = |p: Vec3| ((p - lo) / cell).floor().as_ivec3();
    // Each occupied cell's welded points: their first position and id.
    let mut grid: HashMap<IVec3, Vec<(Vec3, u32)>> = HashMap::default();
    let mut next = 0;
    points
        .iter()
        .map(|&p| {
            let k = key(p);
            let found = (-1..=1)
                .flat_map(|x| {
                    (-1..=1).flat_map(move |y| (-1..=1).map(move |z| IVec3::new(x, y, z)))
                })
                .filter_map(|offset| grid.get(&(k + offset)))
                .flatten()
                .find(|(q, _)| (*q - p).abs().max_element() <= cell)
                .map(|(_, id)| *id);
            found.unwrap_or_else(|| {
                grid.entry(k).or_default().push((p, next));
                next += 1;
                next - 1
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rest_mesh::RestMesh;
    use bevy::prelude::*;

    fn triangles(mesh: impl Into<Mesh>) -> Vec<[Vec3; 3]> {
        let rest = RestMesh::from_mesh(&mesh.into()).expect("a mesh");
        rest.triangles
            .iter()
            .map(|t| t.map(|i| rest.positions[i as usize]))
            .collect()
    }

    /// Bevy's own solids enclose a volume, those whose seams are computed at 0 and 2π (UV
    /// sphere, torus, cylinder) and whose poles collapse triangles (UV sphere) among them; an
    /// open sheet, and any solid with a triangle taken away, does not. Only the solids whose
    /// seams share exact positions are closed for the parity fill.
    #[test]
    fn bevys_solids_enclose_a_volume_and_a_hole_opens_them() {
        // Each solid, and whether its seams share exact positions.
        let solids: [(&str, Mesh, bool); 8] = [
            ("cuboid", Cuboid::new(1.0, 2.0, 3.0).into(), true),
            ("UV sphere", Sphere::new(0.4).mesh().uv(48, 24), false),
            ("small UV sphere", Sphere::new(0.3).mesh().uv(16, 8), false),
            (
                "icosphere",
                Sphere::new(0.4).mesh().ico(3).expect("an icosphere"),
                true,
            ),
            ("torus", Torus::new(0.3, 0.6).into(), false),
            ("cylinder", Cylinder::new(0.3, 0.9).into(), false),
            ("capsule", Capsule3d::new(0.15, 0.8).into(), true),
            ("cone", Cone::new(0.3, 0.9).into(), true),
        ];
        for (name, mesh, exact) in solids {
            let mut soup = triangles(mesh);
            assert!(
                encloses_volume(soup.iter().copied()),
                "{name} encloses a volume"
            );
            assert_eq!(
                is_closed(soup.iter().copied()),
                exact,
                "{name} closed exactly"
            );
            // A triangle from the middle of the list: not one the poles collapse.
            soup.remove(soup.len() / 2);
            assert!(!encloses_volume(soup.iter().copied()), "{name} with a hole");
            assert!(!is_closed(soup), "{name} with a hole is open");
        }
        let sheet = triangles(Plane3d::default().mesh().size(2.0, 2.0));
        assert!(!encloses_volume(sheet.iter().copied()) && !is_closed(sheet));
        assert!(!encloses_volume([]) && !is_closed([]));
    }

    /// Copies of a vertex that differ in their last bits weld wherever they fall on the grid,
    /// and vertices further apart than the tolerance do not.
    #[test]
    fn near_copies_weld_and_distinct_vertices_do_not() {
        let tetrahedron = |d: Vec3| {
            let [a, b, c, e] = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
            // The first triangle's copy of `a` is moved by `d`.
            [[a + d, c, b], [a, b, e], [a, e, c], [b, c, e]]
        };
        let cell = WELD_TOLERANCE;
        for d in [
            Vec3::splat(1e-7),
            Vec3::new(0.9 * cell, 0.0, 0.0),
            Vec3::new(0.0, -0.9 * cell, 0.4 * cell),
        ] {
            assert!(encloses_volume(tetrahedron(d)), "moved by {d}");
            assert!(
                !is_closed(tetrahedron(d)),
                "moved by {d}, not closed exactly"
            );
        }
        assert!(is_closed(tetrahedron(Vec3::ZERO)));
        assert!(!encloses_volume(tetrahedron(Vec3::new(
            3.0 * cell,
            0.0,
            0.0
        ))));
    }
}

//! Lloyd clustering of a mesh's rest-pose vertices into spheres (Shanmugam & Arikan 2007, §5).
//!
//! Vertices carry the surface area around them as weight, so a finely tessellated hand does
//! not draw more spheres than a coarse torso. Seeding is k-means++ with a fixed hash-based
//! random sequence: the same mesh always gives the same spheres.
//!
//! Each cluster is a patch of surface; its sphere stands for the volume under that patch, so
//! it is pushed inwards and kept inside the surface. That matters because A_ψ = 1 inside a
//! sphere (§6): a sphere poking out of the mesh would black out the object's own surface.

use bevy::math::{Mat3, Vec3, Vec3A};

use crate::geometry::bvh::Bvh;
use crate::geometry::hash::pcg_hash;
use crate::geometry::rest_mesh::RestMesh;
use crate::geometry::triangles::Triangle;

/// Most Lloyd iterations; clustering usually settles well before.
const MAX_ITERATIONS: usize = 32;

/// Places tried along the inward direction of a patch for its sphere.
const INWARD_STEPS: u32 = 16;

/// Share of the distance to the nearest triangle a sphere may fill.
const INSIDE_MARGIN: f32 = 0.95;

/// One proxy in the rest pose (a sphere, or a box of [`fit`](super::fit)), with what the
/// per-frame refit needs to move it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestSphere {
    /// Centre, mesh space, metres.
    pub center: Vec3,
    /// Radius of a sphere; of a box, half its diagonal. Metres.
    pub radius: f32,
    /// Half-extent vectors (columns), mesh space, metres: `radius` × identity for a sphere.
    pub axes: Mat3,
    /// Area-weighted centroid of the cluster's vertices, mesh space.
    pub centroid: Vec3,
    /// Area-weighted RMS distance of the cluster's vertices from `centroid` (0 when they
    /// coincide), metres.
    pub spread: f32,
    /// Area-weighted RMS spread of the cluster's vertices along each of `axes`' directions, mesh
    /// space, metres: what the refit holds a morphed box's vertices against, so that the box
    /// takes their shape.
    pub axis_spreads: Vec3,
    /// What this proxy is: a box fit gives a round part of an unskinned mesh a ball
    /// ([`ProxyShape::Spheres`](super::ProxyShape::Spheres)), which the refit moves as it moves
    /// the boxes (and sizes to the volume of a morphed box).
    pub shape: super::ProxyShape,
}

/// The area-weighted RMS spread of the rest vertices `members` along each of the directions of
/// `axes` (mesh space), metres; 0 where they carry no area. Computed once per fit, for
/// the refit of a morphed box (`refit::box_stretch`).
pub(crate) fn rest_axis_spreads(mesh: &RestMesh, members: &[u32], axes: Mat3) -> Vec3 {
    let along = [0, 1, 2].map(|k| Vec3A::from(axes.col(k).normalize_or_zero()));
    let points = members.iter().map(|&v| {
        let v = v as usize;
        (mesh.areas[v], Vec3A::from(mesh.positions[v]))
    });
    Vec3::from(axis_spreads(points, along))
}

/// The area-weighted RMS spread of `points` (area m², position) along each of the unit
/// directions `along`, metres; 0 where they carry no area.
pub(crate) fn axis_spreads(
    mut points: impl Iterator<Item = (f32, Vec3A)>,
    along: [Vec3A; 3],
) -> [f32; 3] {
    let Some((first_area, origin)) = points.next() else {
        return [0.0; 3];
    };
    // Sums relative to the first point keep the spreads accurate far from the origin.
    let mut area = first_area;
    let mut sums = [[0.0f32; 2]; 3];
    for (a, p) in points {
        let d = p - origin;
        area += a;
        for k in 0..3 {
            let x = d.dot(along[k]);
            sums[k] = [sums[k][0] + x * a, sums[k][1] + x * x * a];
        }
    }
    if area <= 0.0 {
        return [0.0; 3];
    }
    sums.map(|[sum, squares]| {
        let mean = sum / area;
        (squares / area - mean * mean).max(0.0).sqrt()
    })
}

/// A mesh cut into clusters, with vertex data sorted by cluster so the refit walks memory in
/// order.
#[derive(Clone, Debug, Default)]
pub struct ClusteredMesh {
    /// One sphere per non-empty cluster.
    pub spheres: Vec<RestSphere>,
    /// Vertices of sphere `i` are `order[ranges[i].0..ranges[i].1]`.
    pub ranges: Vec<(u32, u32)>,
    /// Vertex indices of the rest mesh, grouped by cluster.
    pub order: Vec<u32>,
    /// Joint weights of each sphere (summed vertex weights × areas, normalized): what moves
    /// the offset from the centroid to the centre.
    pub sphere_joints: Vec<Vec<(u16, f32)>>,
    /// What the proxies are.
    pub shape: super::ProxyShape,
}

/// Clusters the vertices of `mesh` that carry area into at most `count` clusters and fits a
/// sphere to each. Fewer spheres come back when the mesh has fewer distinct vertices.
pub fn cluster(mesh: &RestMesh, count: u32) -> ClusteredMesh {
    let vertices: Vec<u32> = (0..mesh.positions.len() as u32)
        .filter(|&i| mesh.areas[i as usize] > 0.0 && mesh.positions[i as usize].is_finite())
        .collect();
    if vertices.is_empty() || count == 0 {
        return ClusteredMesh::default();
    }
    let points: Vec<Vec3> = vertices
        .iter()
        .map(|&i| mesh.positions[i as usize])
        .collect();
    let weights: Vec<f32> = vertices.iter().map(|&i| mesh.areas[i as usize]).collect();
    let mut centres = seed(&points, &weights, count as usize);
    let mut assignment = vec![0u32; points.len()];
    for iteration in 0..MAX_ITERATIONS {
        let mut changed = false;
        for (p, slot) in points.iter().zip(&mut assignment) {
            let nearest = nearest(&centres, *p);
            changed |= nearest != *slot;
            *slot = nearest;
        }
        if !changed && iteration > 0 {
            break;
        }
        let mut sums = vec![(Vec3::ZERO, 0.0f32); centres.len()];
        for ((p, w), &a) in points.iter().zip(&weights).zip(&assignment) {
            sums[a as usize].0 += *p * *w;
            sums[a as usize].1 += *w;
        }
        for (centre, (sum, weight)) in centres.iter_mut().zip(sums) {
            if weight > 0.0 {
                *centre = sum / weight;
            }
        }
    }

    let bvh = Bvh::new(
        mesh.triangles
            .iter()
            .map(|t| Triangle {
                vertices: t.map(|i| mesh.positions[i as usize]),
                normals: None,
            })
            .collect(),
    );
    let mut clustered = ClusteredMesh {
        shape: super::ProxyShape::Spheres,
        ..ClusteredMesh::default()
    };
    for k in 0..centres.len() as u32 {
        let members: Vec<u32> = vertices
            .iter()
            .zip(&assignment)
            .filter(|(_, a)| **a == k)
            .map(|(v, _)| *v)
            .collect();
        let Some(sphere) = fit_sphere(mesh, &bvh, &members) else {
            continue;
        };
        let start = clustered.order.len() as u32;
        clustered.order.extend_from_slice(&members);
        clustered.ranges.push((start, clustered.order.len() as u32));
        clustered.spheres.push(sphere);
        clustered.sphere_joints.push(sphere_joints(mesh, &members));
    }
    clustered
}

/// k-means++ seeding: each new centre is drawn with probability ∝ area × squared distance to
/// the nearest centre so far, from a fixed hash sequence.
fn seed(points: &[Vec3], weights: &[f32], count: usize) -> Vec<Vec3> {
    let mut random = 0x5eed_u32;
    let mut next = move || {
        random = pcg_hash(random);
        random as f32 / u32::MAX as f32
    };
    let pick = |scores: &[f32], u: f32| -> usize {
        let total: f32 = scores.iter().sum();
        let mut target = u * total;
        for (i, s) in scores.iter().enumerate() {
            target -= s;
            if target <= 0.0 && *s > 0.0 {
                return i;
            }
        }
        scores.iter().rposition(|s| *s > 0.0).unwrap_or(0)
    };
    let mut centres = vec![points[pick(weights, next())]];
    let mut distance2: Vec<f32> = points
        .iter()
        .map(|p| p.distance_squared(centres[0]))
        .collect();
    while centres.len() < count {
        let scores: Vec<f32> = distance2.iter().zip(weights).map(|(d, w)| d * w).collect();
        if scores.iter().all(|s| *s <= 0.0) {
            // Every remaining vertex coincides with a centre: no more distinct clusters.
            break;
        }
        let centre = points[pick(&scores, next())];
        for (d, p) in distance2.iter_mut().zip(points) {
            *d = d.min(p.distance_squared(centre));
        }
        centres.push(centre);
    }
    centres
}

fn nearest(centres: &[Vec3], p: Vec3) -> u32 {
    let mut best = (0, f32::INFINITY);
    for (i, c) in centres.iter().enumerate() {
        let d = p.distance_squared(*c);
        if d < best.1 {
            best = (i as u32, d);
        }
    }
    best.0
}

/// The sphere of one cluster: centred under the patch by the thickness of the mesh there, no
/// larger than the patch, and no larger than the distance to the nearest triangle, so it stays
/// inside a closed surface.
fn fit_sphere(mesh: &RestMesh, bvh: &Bvh, members: &[u32]) -> Option<RestSphere> {
    let (mut area, mut centroid, mut mean_normal) = (0.0f32, Vec3::ZERO, Vec3::ZERO);
    for &i in members {
        let w = mesh.areas[i as usize];
        area += w;
        centroid += mesh.positions[i as usize] * w;
        mean_normal += mesh.normals[i as usize] * w;
    }
    if area <= 0.0 {
        return None;
    }
    centroid /= area;
    // |mean_normal| is 1 for a flat patch and near 0 for one that wraps around a limb, whose
    // centroid already lies inside.
    mean_normal /= area;
    let spread = (members
        .iter()
        .map(|&i| mesh.areas[i as usize] * mesh.positions[i as usize].distance_squared(centroid))
        .sum::<f32>()
        / area)
        .sqrt();
    // Vertices that coincide (the corners of a low-poly box) have no spread; the patch's area
    // still says how large it is: a sphere with the same surface area.
    let size = spread.max((area / (4.0 * std::f32::consts::PI)).sqrt());
    // Walk inwards from the centroid to where the largest sphere fits (no larger than the patch):
    // a patch on a thick body gets a sphere of its own size touching it, a box corner one that
    // fills its octant, a thin wall one as thick as the wall. A patch that wraps around a limb
    // has no inward direction; its centroid already lies inside.
    let inward = -mean_normal.normalize_or_zero();
    let thickness = if inward == Vec3::ZERO {
        0.0
    } else {
        bvh.closest_hit(centroid, inward, 1e-5 * size, f32::INFINITY)
            .map_or(f32::INFINITY, |hit| hit.t)
    };
    let depth = (2.0 * size).min(thickness);
    // The margin keeps the object's own surface out of the sphere: inside, A_ψ = 1 would black
    // out the very pixels the sphere stands for.
    let fits =
        |t: f32| size.min(INSIDE_MARGIN * nearest_surface_distance(mesh, centroid + inward * t));
    let (mut center, mut radius) = (centroid, fits(0.0));
    for step in 1..=INWARD_STEPS {
        let t = depth * step as f32 / INWARD_STEPS as f32;
        let r = fits(t);
        if r > radius * (1.0 + 1e-4) {
            (center, radius) = (centroid + inward * t, r);
        }
    }
    let axes = Mat3::from_diagonal(Vec3::splat(radius));
    (radius > 1e-6 && radius.is_finite()).then(|| RestSphere {
        center,
        radius,
        axes,
        centroid,
        spread,
        axis_spreads: rest_axis_spreads(mesh, members, axes),
        shape: super::ProxyShape::Spheres,
    })
}

fn nearest_surface_distance(mesh: &RestMesh, p: Vec3) -> f32 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            closest_point_on_triangle(p, a, b, c).distance(p)
        })
        .fold(f32::INFINITY, f32::min)
}

/// Closest point to `p` on triangle `abc` (region tests on the barycentric coordinates).
fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

pub(crate) fn sphere_joints(mesh: &RestMesh, members: &[u32]) -> Vec<(u16, f32)> {
    let Some(skin) = &mesh.skin else {
        return Vec::new();
    };
    let mut joints: Vec<(u16, f32)> = Vec::new();
    for &i in members {
        let s = &skin[i as usize];
        for (j, w) in s.joints.iter().zip(s.weights) {
            let w = w * mesh.areas[i as usize];
            if w <= 0.0 {
                continue;
            }
            match joints.iter_mut().find(|(k, _)| k == j) {
                Some(entry) => entry.1 += w,
                None => joints.push((*j, w)),
            }
        }
    }
    let total: f32 = joints.iter().map(|(_, w)| w).sum();
    if total > 0.0 {
        joints.iter_mut().for_each(|(_, w)| *w /= total);
    }
    joints
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A UV sphere of `radius` around `center`.
    pub(crate) fn uv_sphere(center: Vec3, radius: f32, rings: usize) -> RestMesh {
        let segments = rings * 2;
        let mut positions = Vec::new();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = std::f32::consts::TAU * s as f32 / segments as f32;
                let n = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                positions.push(center + n * radius);
            }
        }
        let normals = positions.iter().map(|p| (*p - center) / radius).collect();
        let mut indices = Vec::new();
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let (a, b) = (r * row + s, (r + 1) * row + s);
                indices.extend([a, a + 1, b, a + 1, b + 1, b]);
            }
        }
        RestMesh::new(positions, Some(normals), &indices, None, Vec::new(), 0).unwrap()
    }

    #[test]
    fn one_cluster_of_a_sphere_is_the_sphere() {
        let mesh = uv_sphere(Vec3::new(1.0, 2.0, 3.0), 0.5, 16);
        let clustered = cluster(&mesh, 1);
        assert_eq!(clustered.spheres.len(), 1);
        let s = clustered.spheres[0];
        assert!(s.center.distance(Vec3::new(1.0, 2.0, 3.0)) < 0.01, "{s:?}");
        // The inscribed sphere of the tessellation, less the margin.
        assert!(s.radius > 0.45 && s.radius <= 0.475, "{s:?}");
    }

    #[test]
    fn spheres_stay_inside_a_closed_mesh_and_cover_it() {
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 16);
        let clustered = cluster(&mesh, 12);
        assert_eq!(clustered.spheres.len(), 12);
        for s in &clustered.spheres {
            assert!(
                s.center.length() + s.radius <= 1.0 + 1e-3,
                "{s:?} pokes out"
            );
            assert!(s.radius > 0.15, "{s:?} is too small to stand for its patch");
        }
        // Every vertex belongs to exactly one cluster.
        let mut seen: Vec<u32> = clustered.order.clone();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), clustered.order.len());
    }

    #[test]
    fn clustering_is_deterministic() {
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 12);
        assert_eq!(cluster(&mesh, 8).spheres, cluster(&mesh, 8).spheres);
    }

    #[test]
    fn more_clusters_than_vertices_gives_one_per_distinct_vertex_at_most() {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let mesh = RestMesh::new(positions, None, &[0, 1, 2], None, Vec::new(), 0).unwrap();
        let clustered = cluster(&mesh, 100);
        assert!(clustered.ranges.len() <= 3);
        assert!(clustered.spheres.iter().all(|s| s.radius.is_finite()));
    }

    #[test]
    fn a_low_poly_box_gets_spheres_inside_it() {
        let box_mesh: bevy::mesh::Mesh = bevy::math::primitives::Cuboid::new(1.0, 1.0, 1.0).into();
        let mesh = RestMesh::from_mesh(&box_mesh).unwrap();
        let one = cluster(&mesh, 1);
        assert_eq!(one.spheres.len(), 1);
        assert!(one.spheres[0].center.length() < 1e-4);
        assert!(
            (one.spheres[0].radius - 0.475).abs() < 1e-4,
            "{:?}",
            one.spheres[0]
        );
        // Sixteen asked, eight distinct corners: eight spheres, each inside the box.
        let corners = cluster(&mesh, 16);
        assert_eq!(corners.spheres.len(), 8);
        for s in &corners.spheres {
            assert!(
                s.center.abs().max_element() + s.radius <= 0.5 + 1e-4,
                "{s:?}"
            );
        }
    }

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let cases = [
            (Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.2, 0.2, 0.0)),
            (Vec3::new(-1.0, -1.0, 0.0), a),
            (Vec3::new(2.0, -0.5, 0.0), b),
            (Vec3::new(0.5, -1.0, 0.0), Vec3::new(0.5, 0.0, 0.0)),
            (Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.5, 0.5, 0.0)),
        ];
        for (p, expected) in cases {
            let q = closest_point_on_triangle(p, a, b, c);
            assert!(
                q.distance(expected) < 1e-5,
                "{p} -> {q}, expected {expected}"
            );
        }
    }
}

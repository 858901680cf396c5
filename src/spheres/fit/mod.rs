//! Fitting a mesh with a few oriented boxes (and balls, for round parts) that fill its shape, the
//! default far-field proxies.
//!
//! Shanmugam & Arikan's spheres sit inside the surface (§5), so a set of them fills only part of
//! a box, and none fits a floor or a wall, which enclose no volume. The occlusion an object casts
//! at a distance is set by the solid angle it covers, so the proxies here cover the object's
//! solid instead:
//!
//! 1. The mesh is voxelized (40 cells along its longest side) from dense samples of its
//!    triangles; cells the outside cannot reach through empty cells are its interior (a mesh with
//!    holes larger than a cell gets a shell, which still projects like the solid).
//! 2. Top-down splitting: starting from one cluster of every sample (surface points and interior
//!    cell centres), the cluster whose box fills its own silhouette worst is cut in two (2-means
//!    along its longest axis) until every box fills its silhouette to 3/4 or `count` boxes exist.
//!    A box-shaped mesh stays one box, a floor or a wall one flat box; an L-shape becomes two.
//! 3. Each box is the cluster's principal-axis bounding box, shrunk per axis so that its
//!    silhouette along each axis has the area the cluster's own silhouette has: a ball's box
//!    covers the ball's disk face-on.
//! 4. A round cluster of an unskinned mesh gets a ball instead, of its mean silhouette's area,
//!    where the ball's silhouettes match the cluster's better than the box's do (and match
//!    well): a box round a ball sticks out at its corners.
//!
//! Few boxes matter: proxies are splatted independently, so proxies one behind the other both
//! count (multiplied as independent occluders), which overstates what they block together.

mod cluster;
mod frame;
mod samples;
#[cfg(test)]
mod tests;

use bevy::math::{IVec3, Mat3, Vec3};
use bevy::platform::collections::HashSet;

use super::ProxyShape;
use super::lloyd::{ClusteredMesh, RestSphere, rest_axis_spreads, sphere_joints};
use crate::geometry::rest_mesh::RestMesh;
use cluster::Cluster;
use samples::{Sample, cell_size, solid_samples};

/// Voxels along the longest side of the mesh's bounds.
const CELLS: f32 = 40.0;
/// Silhouette fill below which a cluster is split.
const GOOD_FILL: f32 = 0.75;
/// Silhouette match (intersection over union, `Cluster::silhouette_match`) a ball needs to stand
/// for a cluster: a ball matches itself to 0.94 on the fit's grid, a cube's ball 0.75.
const ROUND: f32 = 0.8;
/// Cells of the occupancy grid a silhouette is measured on, per side at most.
const SILHOUETTE_CELLS: usize = 24;
/// 2-means iterations per split.
const SPLIT_ITERATIONS: usize = 8;

/// Fits at most `count` boxes to `mesh` and groups its vertices by box, for the per-frame refit.
pub fn fit_boxes(mesh: &RestMesh, count: u32) -> ClusteredMesh {
    let samples = solid_samples(mesh);
    if samples.is_empty() || count == 0 {
        return ClusteredMesh::default();
    }
    let cell = cell_size(mesh);
    let mut clusters = if mesh.skin.is_some() {
        joint_clusters(samples, count as usize, cell)
    } else {
        vec![Cluster::new(samples, cell)]
    };
    while clusters.len() < count as usize {
        let worst = clusters
            .iter()
            .enumerate()
            .filter(|(_, c)| !c.settled && c.fill.min_element() < GOOD_FILL)
            .max_by(|(_, a), (_, b)| a.split_priority().total_cmp(&b.split_priority()))
            .map(|(i, _)| i);
        let Some(worst) = worst else {
            break;
        };
        let cluster = clusters.swap_remove(worst);
        match cluster.split(cell) {
            Ok((a, b)) => clusters.extend([a, b]),
            Err(mut cluster) => {
                cluster.settled = true;
                clusters.push(cluster);
            }
        }
    }
    // Deterministic order: by centre, x then y then z.
    clusters.sort_by(|a, b| {
        a.center
            .to_array()
            .partial_cmp(&b.center.to_array())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    // A skinned mesh's parts keep their boxes: the splat spares a receiver on the surface of a
    // character's box (its own relief, which the near field reads), and a ball, which has no
    // faces, would cover a whole hemisphere of the skin inside it (a part each of CesiumMan and
    // the walker took a ball, and the spheres alone read 0.016 → 0.018 on CesiumMan).
    let balls = mesh.skin.is_none();
    let proxies: Vec<Proxy> = clusters.iter().map(|c| proxy(c, cell, balls)).collect();
    group_vertices(mesh, &proxies)
}

/// A fitted proxy: centre, half-extent vectors (columns; a ball's all of its radius) and shape.
type Proxy = (Vec3, Mat3, ProxyShape);

/// A cluster's box, or (where `balls`) a ball where the cluster is round: where a ball covers its
/// silhouettes better than its box does, and well (`ROUND`). A round part's box sticks out at its
/// corners, and a floor under those corners has the box's lower face overhead (the box of a ball
/// on a floor darkened the floor in front of it). Parts that match neither well keep their box:
/// a ball would stand in for the two walls of a room's corner.
fn proxy(cluster: &Cluster, cell: f32, balls: bool) -> Proxy {
    let (centre, axes) = cluster.proxy_box(cell);
    if !balls {
        return (centre, axes, ProxyShape::Boxes);
    }
    let (ball_centre, radius) = cluster.proxy_ball(cell);
    let as_ball = cluster.silhouette_match(ball_centre, axes, Some(radius), cell);
    if as_ball >= ROUND && as_ball > cluster.silhouette_match(centre, axes, None, cell) {
        (ball_centre, cluster.axes * radius, ProxyShape::Spheres)
    } else {
        (centre, axes, ProxyShape::Boxes)
    }
}

/// A skinned mesh starts from one cluster per joint (by the joint that moves each sample most).
/// The lightest is merged into the group it touches most (samples in the same or adjacent cells)
/// until at most `count` remain; one that touches none joins the group with the nearest centre.
/// Touch, not nearness of centres, keeps a foot with its own leg: two feet side by side have
/// centres closer than a foot's and its shin's, and one box round both would wall off the floor
/// between them.
fn joint_clusters(samples: Vec<Sample>, count: usize, cell: f32) -> Vec<Cluster> {
    let mut groups: Vec<(u16, Vec<Sample>)> = Vec::new();
    for s in samples {
        match groups.iter_mut().find(|(j, _)| *j == s.joint) {
            Some((_, group)) => group.push(s),
            None => groups.push((s.joint, vec![s])),
        }
    }
    groups.sort_by_key(|(j, _)| *j);
    let cell_of = |p: Vec3| (p / cell).floor().as_ivec3();
    let mut groups: Vec<(Vec<Sample>, HashSet<IVec3>)> = groups
        .into_iter()
        .map(|(_, g)| {
            let cells = g.iter().map(|s| cell_of(s.position)).collect();
            (g, cells)
        })
        .collect();
    let weight = |g: &[Sample]| g.iter().map(|s| s.weight).sum::<f32>();
    let centre = |g: &[Sample]| {
        g.iter().fold(Vec3::ZERO, |m, s| m + s.position * s.weight) / weight(g).max(1e-30)
    };
    let total: f32 = groups.iter().map(|(g, _)| weight(g)).sum();
    loop {
        let lightest = (0..groups.len())
            .min_by(|&a, &b| weight(&groups[a].0).total_cmp(&weight(&groups[b].0)))
            .expect("at least one group");
        // Joints that move only a sliver of the surface do not get a box of their own.
        let sliver = weight(&groups[lightest].0) < 0.01 * total;
        if groups.len() <= 1 || (groups.len() <= count.max(1) && !sliver) {
            break;
        }
        let (merged, merged_cells) = groups.swap_remove(lightest);
        let at = centre(&merged);
        let touching = |cells: &HashSet<IVec3>| {
            merged_cells
                .iter()
                .filter(|c| NEIGHBOURS.iter().any(|d| cells.contains(&(**c + *d))))
                .count()
        };
        // Most cells touching first, then the nearest centre.
        let into = groups
            .iter()
            .map(|(g, cells)| (touching(cells), -centre(g).distance_squared(at)))
            .enumerate()
            .max_by(|(_, a), (_, b)| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)))
            .map(|(i, _)| i)
            .expect("another group");
        groups[into].0.extend(merged);
        groups[into].1.extend(merged_cells);
    }
    groups
        .into_iter()
        .map(|(g, _)| Cluster::new(g, cell))
        .collect()
}

/// A cell and its 26 neighbours, as offsets.
const NEIGHBOURS: [IVec3; 27] = {
    let mut offsets = [IVec3::ZERO; 27];
    let mut i = 0;
    while i < 27 {
        offsets[i] = IVec3::new(i as i32 % 3 - 1, (i as i32 / 3) % 3 - 1, i as i32 / 9 - 1);
        i += 1;
    }
    offsets
};

/// Every vertex joins the box nearest to it (0 inside); each box's refit data comes from its
/// vertices.
fn group_vertices(mesh: &RestMesh, boxes: &[Proxy]) -> ClusteredMesh {
    let outside = |p: Vec3, (center, axes, _): &Proxy| {
        let d = p - *center;
        let mut excess = Vec3::ZERO;
        for i in 0..3 {
            let axis = axes.col(i);
            let half = axis.length();
            let along = if half > 0.0 { d.dot(axis / half) } else { 0.0 };
            excess[i] = (along.abs() - half).max(0.0);
        }
        excess.length_squared()
    };
    let mut members = vec![Vec::new(); boxes.len()];
    for (v, p) in mesh.positions.iter().enumerate() {
        if !p.is_finite() {
            continue;
        }
        let nearest = (0..boxes.len())
            .min_by(|&a, &b| outside(*p, &boxes[a]).total_cmp(&outside(*p, &boxes[b])))
            .unwrap_or(0);
        members[nearest].push(v as u32);
    }
    let mut clustered = ClusteredMesh {
        shape: ProxyShape::Boxes,
        ..ClusteredMesh::default()
    };
    for ((center, axes, shape), members) in boxes.iter().zip(members) {
        if members.is_empty() {
            continue;
        }
        // Vertices without area (unused, or of degenerate triangles) still move with the box.
        let weight = |v: u32| mesh.areas[v as usize].max(1e-12);
        let area: f32 = members.iter().map(|&v| weight(v)).sum();
        let centroid = members
            .iter()
            .map(|&v| mesh.positions[v as usize] * weight(v))
            .sum::<Vec3>()
            / area;
        let spread = (members
            .iter()
            .map(|&v| weight(v) * mesh.positions[v as usize].distance_squared(centroid))
            .sum::<f32>()
            / area)
            .sqrt();
        let start = clustered.order.len() as u32;
        clustered.order.extend_from_slice(&members);
        clustered.ranges.push((start, clustered.order.len() as u32));
        clustered.sphere_joints.push(sphere_joints(mesh, &members));
        clustered.spheres.push(RestSphere {
            center: *center,
            radius: match shape {
                ProxyShape::Spheres => axes.x_axis.length(),
                ProxyShape::Boxes => (axes.x_axis + axes.y_axis + axes.z_axis)
                    .length()
                    .max(axes.x_axis.length()),
            },
            axes: *axes,
            centroid,
            spread,
            axis_spreads: rest_axis_spreads(mesh, &members, *axes),
            shape: *shape,
        });
    }
    clustered
}

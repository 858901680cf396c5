//! Fitting a mesh with a few oriented boxes that fill its shape, the default far-field proxies.
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
//!
//! Few boxes matter: proxies are splatted independently, so proxies one behind the other both
//! count (multiplied as independent occluders), which overstates what they block together.

use bevy::math::{Mat3, Vec3};

use super::lloyd::{ClusteredMesh, RestSphere, sphere_joints};
use super::rest_mesh::RestMesh;

/// Voxels along the longest side of the mesh's bounds.
const CELLS: f32 = 40.0;
/// Silhouette fill below which a cluster is split.
const GOOD_FILL: f32 = 0.75;
/// Cells of the occupancy grid a silhouette is measured on, per side at most.
const SILHOUETTE_CELLS: usize = 24;
/// 2-means iterations per split.
const SPLIT_ITERATIONS: usize = 8;

/// A point of the mesh's solid: a sample of its surface or the centre of an interior voxel.
#[derive(Clone, Copy)]
struct Sample {
    position: Vec3,
    /// Volume it stands for, m³ (surface samples: their area times a third of a cell).
    weight: f32,
    /// The surface's unit normal at a surface sample; zero inside.
    normal: Vec3,
    /// The joint that moves a surface sample of a skinned mesh most; `u16::MAX` otherwise.
    joint: u16,
}

/// One cluster of samples and its principal-axis box.
struct Cluster {
    samples: Vec<Sample>,
    center: Vec3,
    /// Unit principal axes (columns), largest spread first.
    axes: Mat3,
    /// Half extents along `axes`, metres.
    half: Vec3,
    /// Share of the box's face that the cluster's silhouette covers, seen along each axis.
    fill: Vec3,
    /// Too few samples to split further.
    settled: bool,
}

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
    let boxes: Vec<(Vec3, Mat3)> = clusters.iter().map(|c| c.proxy_box(cell)).collect();
    group_vertices(mesh, &boxes)
}

/// The joint with the largest weight summed over a triangle's corners.
fn dominant_joint(mesh: &RestMesh, triangle: &[u32; 3]) -> u16 {
    let Some(skin) = &mesh.skin else {
        return u16::MAX;
    };
    let mut weights: Vec<(u16, f32)> = Vec::with_capacity(12);
    for &v in triangle {
        let s = &skin[v as usize];
        for (j, w) in s.joints.iter().zip(s.weights) {
            match weights.iter_mut().find(|(k, _)| k == j) {
                Some(entry) => entry.1 += w,
                None => weights.push((*j, w)),
            }
        }
    }
    weights
        .into_iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(u16::MAX, |(j, _)| j)
}

/// A skinned mesh starts from one cluster per joint (by the joint that moves each sample most),
/// the lightest merged into the one with the nearest centre until at most `count` remain.
fn joint_clusters(samples: Vec<Sample>, count: usize, cell: f32) -> Vec<Cluster> {
    let mut groups: Vec<(u16, Vec<Sample>)> = Vec::new();
    for s in samples {
        match groups.iter_mut().find(|(j, _)| *j == s.joint) {
            Some((_, group)) => group.push(s),
            None => groups.push((s.joint, vec![s])),
        }
    }
    groups.sort_by_key(|(j, _)| *j);
    let mut groups: Vec<Vec<Sample>> = groups.into_iter().map(|(_, g)| g).collect();
    let weight = |g: &[Sample]| g.iter().map(|s| s.weight).sum::<f32>();
    let centre = |g: &[Sample]| {
        g.iter().fold(Vec3::ZERO, |m, s| m + s.position * s.weight) / weight(g).max(1e-30)
    };
    let total: f32 = groups.iter().map(|g| weight(g)).sum();
    loop {
        let lightest = (0..groups.len())
            .min_by(|&a, &b| weight(&groups[a]).total_cmp(&weight(&groups[b])))
            .expect("at least one group");
        // Joints that move only a sliver of the surface do not get a box of their own.
        let sliver = weight(&groups[lightest]) < 0.01 * total;
        if groups.len() <= 1 || (groups.len() <= count.max(1) && !sliver) {
            break;
        }
        let merged = groups.swap_remove(lightest);
        let at = centre(&merged);
        let nearest = (0..groups.len())
            .min_by(|&a, &b| {
                centre(&groups[a])
                    .distance_squared(at)
                    .total_cmp(&centre(&groups[b]).distance_squared(at))
            })
            .expect("another group");
        groups[nearest].extend(merged);
    }
    groups.into_iter().map(|g| Cluster::new(g, cell)).collect()
}

fn cell_size(mesh: &RestMesh) -> f32 {
    let (lo, hi) = bounds(mesh.positions.iter().copied());
    ((hi - lo).max_element() / CELLS).max(1e-6)
}

fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    points
        .filter(|p| p.is_finite())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        })
}

/// Dense samples of the surface, and the centres of the voxels it encloses.
fn solid_samples(mesh: &RestMesh) -> Vec<Sample> {
    let (lo, hi) = bounds(mesh.positions.iter().copied());
    if !lo.is_finite() {
        return Vec::new();
    }
    let cell = cell_size(mesh);
    // Surface samples a third of a cell apart: every voxel the surface crosses gets one.
    let spacing = cell / 3.0;
    let mut samples = Vec::new();
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let cross = (b - a).cross(c - a);
        let area = 0.5 * cross.length();
        let normal = cross.normalize_or_zero();
        let joint = dominant_joint(mesh, t);
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        let m = ((longest / spacing).ceil() as usize).clamp(1, 256);
        let weight = area / (m * m) as f32 * (cell / 3.0);
        // The centroids of the m² triangles of a regular subdivision.
        for i in 0..m {
            for j in 0..m - i {
                for (u, v) in [
                    (
                        (i as f32 + 1.0 / 3.0) / m as f32,
                        (j as f32 + 1.0 / 3.0) / m as f32,
                    ),
                    (
                        (i as f32 + 2.0 / 3.0) / m as f32,
                        (j as f32 + 2.0 / 3.0) / m as f32,
                    ),
                ] {
                    if u + v <= 1.0 {
                        samples.push(Sample {
                            position: a + (b - a) * u + (c - a) * v,
                            weight,
                            normal,
                            joint,
                        });
                    }
                }
            }
        }
    }
    if mesh.skin.is_some() {
        // A character's parts move apart: each box follows its own joints, and interior cells
        // belong to no joint. Silhouettes of the surface alone still fill its boxes.
        return samples;
    }
    // Voxels with one cell of padding, so the outside is connected around the mesh.
    let origin = lo - Vec3::splat(cell);
    let dims = ((hi - lo) / cell).ceil().as_uvec3() + bevy::math::UVec3::splat(3);
    let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
    let index = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
    let mut surface = vec![false; nx * ny * nz];
    for s in &samples {
        let g = ((s.position - origin) / cell).floor().as_uvec3();
        let (x, y, z) = (
            (g.x as usize).min(nx - 1),
            (g.y as usize).min(ny - 1),
            (g.z as usize).min(nz - 1),
        );
        surface[index(x, y, z)] = true;
    }
    // Flood the outside through empty cells; what it cannot reach is interior.
    let mut outside = vec![false; nx * ny * nz];
    let mut stack = vec![(0usize, 0usize, 0usize)];
    outside[0] = true;
    while let Some((x, y, z)) = stack.pop() {
        let mut visit = |x: usize, y: usize, z: usize| {
            let i = index(x, y, z);
            if !outside[i] && !surface[i] {
                outside[i] = true;
                stack.push((x, y, z));
            }
        };
        if x > 0 {
            visit(x - 1, y, z);
        }
        if x + 1 < nx {
            visit(x + 1, y, z);
        }
        if y > 0 {
            visit(x, y - 1, z);
        }
        if y + 1 < ny {
            visit(x, y + 1, z);
        }
        if z > 0 {
            visit(x, y, z - 1);
        }
        if z + 1 < nz {
            visit(x, y, z + 1);
        }
    }
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let i = index(x, y, z);
                if !outside[i] && !surface[i] {
                    samples.push(Sample {
                        position: origin + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * cell,
                        weight: cell * cell * cell,
                        normal: Vec3::ZERO,
                        joint: u16::MAX,
                    });
                }
            }
        }
    }
    samples.retain(|s| s.position.is_finite() && s.weight > 0.0);
    samples
}

impl Cluster {
    fn new(samples: Vec<Sample>, cell: f32) -> Self {
        let total: f32 = samples.iter().map(|s| s.weight).sum();
        let mean = samples
            .iter()
            .fold(Vec3::ZERO, |m, s| m + s.position * s.weight)
            / total.max(f32::MIN_POSITIVE);
        let mut covariance = Mat3::ZERO;
        for s in &samples {
            let d = s.position - mean;
            covariance += Mat3::from_cols(d * d.x, d * d.y, d * d.z) * s.weight;
        }
        // Principal axes alone are arbitrary where spreads are equal (a cube, a square floor):
        // also try frames around the thinnest principal axis and around the dominant surface
        // normal, each turned about that axis to the tightest fit, and keep the smallest box.
        let principal = principal_axes(covariance);
        let mut candidates = vec![principal, tightest_about(&samples, principal.z_axis, cell)];
        if let Some(normal) = dominant_normal(&samples) {
            candidates.push(tightest_about(&samples, normal, cell));
        }
        let (axes, (lo, hi)) = candidates
            .into_iter()
            .map(|axes| (axes, local_bounds(&samples, axes)))
            .min_by(|(_, a), (_, b)| box_volume(*a, cell).total_cmp(&box_volume(*b, cell)))
            .expect("three candidates");
        let center = axes * ((lo + hi) * 0.5);
        let half = ((hi - lo) * 0.5).max(Vec3::ZERO);
        let mut cluster = Self {
            samples,
            center,
            axes,
            half,
            fill: Vec3::ONE,
            settled: false,
        };
        cluster.fill = Vec3::new(
            cluster.silhouette_fill(0, cell),
            cluster.silhouette_fill(1, cell),
            cluster.silhouette_fill(2, cell),
        );
        cluster
    }

    /// The share of the box's face across `axis` that the samples cover, seen along `axis`:
    /// occupied cells of a grid over the face, less half of those on the silhouette's edge
    /// (which the silhouette covers about half of).
    fn silhouette_fill(&self, axis: usize, cell: f32) -> f32 {
        let (j, k) = ((axis + 1) % 3, (axis + 2) % 3);
        let cells = |half: f32| ((2.0 * half / cell).ceil() as usize).clamp(1, SILHOUETTE_CELLS);
        let (cj, ck) = (cells(self.half[j]), cells(self.half[k]));
        let mut covered = vec![false; cj * ck];
        let (ej, ek) = (self.axes.col(j), self.axes.col(k));
        for s in &self.samples {
            let d = s.position - self.center;
            let at = |e: Vec3, half: f32, n: usize| {
                if half <= 0.0 {
                    0
                } else {
                    (((e.dot(d) / half * 0.5 + 0.5) * n as f32) as usize).min(n - 1)
                }
            };
            covered[at(ej, self.half[j], cj) + cj * at(ek, self.half[k], ck)] = true;
        }
        edge_corrected_share(&covered, cj, ck)
    }

    /// Clusters whose boxes waste the most silhouette go first.
    fn split_priority(&self) -> f32 {
        let h = self.half;
        let area = h.x * h.y + h.y * h.z + h.x * h.z;
        (1.0 - self.fill.min_element()) * area
    }

    /// 2-means along the longest axis; the cluster back when one side would be empty.
    fn split(self, cell: f32) -> Result<(Self, Self), Self> {
        if self.samples.len() < 8 {
            return Err(self);
        }
        let axis = self.axes.col(0);
        let mut centres = [
            self.center - axis * self.half.x * 0.5,
            self.center + axis * self.half.x * 0.5,
        ];
        let mut side = vec![false; self.samples.len()];
        for _ in 0..SPLIT_ITERATIONS {
            let mut sums = [(Vec3::ZERO, 0.0f32); 2];
            for (s, side) in self.samples.iter().zip(&mut side) {
                *side = s.position.distance_squared(centres[1])
                    < s.position.distance_squared(centres[0]);
                let sum = &mut sums[usize::from(*side)];
                sum.0 += s.position * s.weight;
                sum.1 += s.weight;
            }
            for (centre, (sum, weight)) in centres.iter_mut().zip(sums) {
                if weight > 0.0 {
                    *centre = sum / weight;
                }
            }
        }
        let (b, a): (Vec<(Sample, bool)>, Vec<(Sample, bool)>) = self
            .samples
            .iter()
            .copied()
            .zip(side)
            .partition(|(_, s)| *s);
        if a.is_empty() || b.is_empty() {
            return Err(self);
        }
        let strip = |v: Vec<(Sample, bool)>| v.into_iter().map(|(s, _)| s).collect();
        Ok((Self::new(strip(a), cell), Self::new(strip(b), cell)))
    }

    /// The proxy: centre and half-extent vectors (columns). Each axis is shrunk so the box's
    /// silhouette along every axis has the area of the cluster's own silhouette there, then all
    /// three together so that the box's silhouette averaged over 13 directions (axes, face and
    /// body diagonals) has the cluster's average: seen obliquely, a box covers more than a round
    /// part of the same face-on silhouette.
    fn proxy_box(&self, cell: f32) -> (Vec3, Mat3) {
        let f = self.fill.max(Vec3::splat(0.05));
        let scale = Vec3::new(
            (f.y * f.z / f.x).sqrt(),
            (f.x * f.z / f.y).sqrt(),
            (f.x * f.y / f.z).sqrt(),
        )
        .clamp(Vec3::splat(0.5), Vec3::ONE);
        let mut half = self.half * scale;
        let (mut ours, mut theirs) = (0.0, 0.0);
        for d in mean_directions() {
            let local = d.abs();
            ours += 4.0
                * (local.x * half.y * half.z
                    + local.y * half.x * half.z
                    + local.z * half.x * half.y);
            theirs += self.silhouette_area(self.axes * d, cell);
        }
        if ours > 0.0 && theirs > 0.0 {
            half *= (theirs / ours).sqrt().clamp(0.5, 1.0);
        }
        (
            self.center,
            Mat3::from_cols(
                self.axes.x_axis * half.x,
                self.axes.y_axis * half.y,
                self.axes.z_axis * half.z,
            ),
        )
    }

    /// The area of the samples' silhouette seen along unit `direction`: occupied cells of a grid
    /// over its bounds, less half of those on its edge.
    fn silhouette_area(&self, direction: Vec3, cell: f32) -> f32 {
        let (u, v) = direction.any_orthonormal_pair();
        let points: Vec<(f32, f32)> = self
            .samples
            .iter()
            .map(|s| (u.dot(s.position), v.dot(s.position)))
            .collect();
        let (mut lo, mut hi) = (
            (f32::INFINITY, f32::INFINITY),
            (f32::NEG_INFINITY, f32::NEG_INFINITY),
        );
        for &(a, b) in &points {
            lo = (lo.0.min(a), lo.1.min(b));
            hi = (hi.0.max(a), hi.1.max(b));
        }
        let cells = |span: f32| ((span / cell).ceil() as usize).clamp(1, SILHOUETTE_CELLS);
        let (cu, cv) = (cells(hi.0 - lo.0), cells(hi.1 - lo.1));
        let (su, sv) = ((hi.0 - lo.0).max(1e-12), (hi.1 - lo.1).max(1e-12));
        let mut covered = vec![false; cu * cv];
        for &(a, b) in &points {
            let i = (((a - lo.0) / su * cu as f32) as usize).min(cu - 1);
            let j = (((b - lo.1) / sv * cv as f32) as usize).min(cv - 1);
            covered[i + cu * j] = true;
        }
        let share = edge_corrected_share(&covered, cu, cv);
        // A flat cluster seen edge-on has no area.
        share * (hi.0 - lo.0) * (hi.1 - lo.1)
    }
}

/// 13 directions spread over the half sphere: the axes, the face diagonals and the body
/// diagonals.
fn mean_directions() -> impl Iterator<Item = Vec3> {
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    let faces = [
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, -1.0),
    ];
    let bodies = [
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(-1.0, 1.0, 1.0),
    ];
    axes.into_iter()
        .chain(faces)
        .chain(bodies)
        .map(Vec3::normalize)
}

/// The share of a grid that occupied cells cover, counting cells on the occupied region's edge
/// (next to an empty cell inside the grid) as half covered.
fn edge_corrected_share(covered: &[bool], cu: usize, cv: usize) -> f32 {
    let is = |x: isize, y: isize| {
        x >= 0
            && y >= 0
            && (x as usize) < cu
            && (y as usize) < cv
            && covered[x as usize + cu * y as usize]
    };
    let open = |x: isize, y: isize| {
        x >= 0 && y >= 0 && (x as usize) < cu && (y as usize) < cv && !is(x, y)
    };
    let (mut inside, mut edge) = (0usize, 0usize);
    for y in 0..cv as isize {
        for x in 0..cu as isize {
            if !is(x, y) {
                continue;
            }
            if open(x - 1, y) || open(x + 1, y) || open(x, y - 1) || open(x, y + 1) {
                edge += 1;
            } else {
                inside += 1;
            }
        }
    }
    (inside as f32 + 0.5 * edge as f32) / covered.len() as f32
}

/// The samples' bounds along `axes` (relative to the origin of the mesh space).
fn local_bounds(samples: &[Sample], axes: Mat3) -> (Vec3, Vec3) {
    let to_local = axes.transpose();
    bounds(samples.iter().map(|s| to_local * s.position))
}

/// A box's volume, each side at least one cell, so flat boxes compare by area.
fn box_volume((lo, hi): (Vec3, Vec3), cell: f32) -> f32 {
    let size = (hi - lo).max(Vec3::splat(cell));
    size.x * size.y * size.z
}

/// The frame whose third axis is `axis`, turned about it so that the samples' bounds across it
/// have the least area (32 turns over a quarter circle).
fn tightest_about(samples: &[Sample], axis: Vec3, cell: f32) -> Mat3 {
    let z = axis.normalize_or(Vec3::Z);
    let (x0, y0) = z.any_orthonormal_pair();
    (0..32)
        .map(|i| {
            let angle = i as f32 / 32.0 * std::f32::consts::FRAC_PI_2;
            let (sin, cos) = angle.sin_cos();
            let x = x0 * cos + y0 * sin;
            Mat3::from_cols(x, z.cross(x), z)
        })
        .min_by(|a, b| {
            box_volume(local_bounds(samples, *a), cell)
                .total_cmp(&box_volume(local_bounds(samples, *b), cell))
        })
        .expect("32 turns")
}

/// The direction most of the surface faces (n and −n alike): the heaviest of 6 × 8 × 8
/// cube-map bins of the area-weighted normals, averaged within the bin.
fn dominant_normal(samples: &[Sample]) -> Option<Vec3> {
    let mut bins = vec![(Vec3::ZERO, 0.0f32); 6 * 64];
    for s in samples.iter().filter(|s| s.normal != Vec3::ZERO) {
        // Fold n and −n together: the largest component positive.
        let a = s.normal.abs();
        let major = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let n = if s.normal[major] < 0.0 {
            -s.normal
        } else {
            s.normal
        };
        let (u, v) = (n[(major + 1) % 3] / n[major], n[(major + 2) % 3] / n[major]);
        let cell = |t: f32| (((t * 0.5 + 0.5) * 8.0) as usize).min(7);
        let bin = &mut bins[major * 64 + cell(u) + 8 * cell(v)];
        bin.0 += n * s.weight;
        bin.1 += s.weight;
    }
    bins.iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .filter(|bin| bin.1 > 0.0)
        .map(|bin| bin.0.normalize_or_zero())
        .filter(|n| *n != Vec3::ZERO)
}

/// Unit eigenvectors of a symmetric 3 × 3 matrix (Jacobi rotations), as columns ordered by
/// decreasing eigenvalue, forming a right-handed frame.
fn principal_axes(m: Mat3) -> Mat3 {
    let mut a = [[0.0f32; 3]; 3];
    for (i, row) in a.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = m.col(j)[i];
        }
    }
    let mut v = [[1.0f32, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if off <= 1e-9 * scale.max(f32::MIN_POSITIVE) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() <= f32::MIN_POSITIVE {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (row_p, row_q) = (a[p], a[q]);
            for (k, (apk, aqk)) in row_p.into_iter().zip(row_q).enumerate() {
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    let column = |i: usize| Vec3::new(v[0][i], v[1][i], v[2][i]).normalize_or(Vec3::X);
    let x = column(order[0]);
    let mut y = column(order[1]);
    y = (y - x * x.dot(y)).normalize_or(x.any_orthonormal_vector());
    Mat3::from_cols(x, y, x.cross(y))
}

/// Every vertex joins the box nearest to it (0 inside); each box's refit data comes from its
/// vertices.
fn group_vertices(mesh: &RestMesh, boxes: &[(Vec3, Mat3)]) -> ClusteredMesh {
    let outside = |p: Vec3, (center, axes): &(Vec3, Mat3)| {
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
        shape: super::ProxyShape::Boxes,
        ..ClusteredMesh::default()
    };
    for ((center, axes), members) in boxes.iter().zip(members) {
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
            radius: (axes.x_axis + axes.y_axis + axes.z_axis)
                .length()
                .max(axes.x_axis.length()),
            axes: *axes,
            centroid,
            spread,
        });
    }
    clustered
}

#[cfg(test)]
mod tests {
    use bevy::math::Quat;
    use bevy::prelude::*;

    use super::*;

    fn rest(mesh: Mesh, transform: Transform) -> RestMesh {
        RestMesh::from_mesh(&mesh.transformed_by(transform)).unwrap()
    }

    fn half_extents(s: &RestSphere) -> Vec3 {
        Vec3::new(
            s.axes.x_axis.length(),
            s.axes.y_axis.length(),
            s.axes.z_axis.length(),
        )
    }

    #[test]
    fn a_box_is_one_box() {
        let turned = Transform::from_rotation(Quat::from_euler(EulerRot::XYZ, 0.3, 0.7, -0.2));
        let fitted = fit_boxes(&rest(Cuboid::new(1.0, 0.5, 2.0).into(), turned), 16);
        assert_eq!(fitted.spheres.len(), 1, "{:?}", fitted.spheres);
        let mut half = half_extents(&fitted.spheres[0]).to_array();
        half.sort_by(f32::total_cmp);
        for (got, want) in half.iter().zip([0.25, 0.5, 1.0]) {
            assert!((got - want).abs() < 0.03, "{half:?}");
        }
        assert!(fitted.spheres[0].center.length() < 0.02);
    }

    #[test]
    fn a_floor_is_one_flat_box() {
        let fitted = fit_boxes(
            &rest(
                Plane3d::default().mesh().size(20.0, 20.0).build(),
                Transform::IDENTITY,
            ),
            16,
        );
        assert_eq!(fitted.spheres.len(), 1);
        let h = half_extents(&fitted.spheres[0]);
        let mut sorted = h.to_array();
        sorted.sort_by(f32::total_cmp);
        assert!(sorted[0] < 1e-4, "a floor has no thickness: {h}");
        assert!(
            (sorted[1] - 10.0).abs() < 0.1 && (sorted[2] - 10.0).abs() < 0.1,
            "{h}"
        );
    }

    #[test]
    fn an_l_shape_takes_two_boxes() {
        // Two 1 × 0.2 × 0.2 bars meeting at a corner.
        let mut mesh: Mesh = Cuboid::new(1.0, 0.2, 0.2).into();
        mesh = mesh.transformed_by(Transform::from_xyz(0.5, 0.0, 0.0));
        let mut other: Mesh = Cuboid::new(0.2, 1.0, 0.2).into();
        other = other.transformed_by(Transform::from_xyz(-0.1, 0.6, 0.0));
        mesh.merge(&other).unwrap();
        let fitted = fit_boxes(&RestMesh::from_mesh(&mesh).unwrap(), 16);
        assert!(
            (2..=4).contains(&fitted.spheres.len()),
            "{} boxes",
            fitted.spheres.len()
        );
        let volume: f32 = fitted
            .spheres
            .iter()
            .map(|s| 8.0 * half_extents(s).x * half_extents(s).y * half_extents(s).z)
            .sum();
        // The solid is 0.08 m³; its bounding box 0.24 m³.
        assert!((0.06..0.12).contains(&volume), "boxes hold {volume} m³");
    }

    #[test]
    fn a_ball_gets_a_box_of_its_mean_silhouette() {
        let fitted = fit_boxes(
            &rest(Sphere::new(0.5).mesh().uv(32, 16), Transform::IDENTITY),
            1,
        );
        assert_eq!(fitted.spheres.len(), 1);
        let h = half_extents(&fitted.spheres[0]);
        // Averaged over directions a cube shows 1.5 faces: 6h² = π r².
        for side in h.to_array() {
            let mean = 6.0 * side * side;
            assert!(
                (mean / (std::f32::consts::PI * 0.25) - 1.0).abs() < 0.1,
                "{h}"
            );
        }
    }

    #[test]
    fn every_vertex_belongs_to_a_box() {
        let mesh = rest(Capsule3d::new(0.2, 1.0).mesh().into(), Transform::IDENTITY);
        let fitted = fit_boxes(&mesh, 4);
        assert_eq!(fitted.order.len(), mesh.positions.len());
        assert!(!fitted.spheres.is_empty() && fitted.spheres.len() <= 4);
    }
}

/// The occlusion a proxy set casts around its mesh against the mesh's own, for tests.
#[cfg(test)]
pub(crate) mod cast {
    use bevy::math::Affine3A;
    use bevy::prelude::*;

    use crate::reference::bvh::Bvh;
    use crate::reference::ground_truth::point_occlusion;
    use crate::reference::scene::{Triangle, triangle_bounds};
    use crate::reference::spheres::{proxy_occlusion, sphere_union};
    use crate::spheres::OccluderSphere;

    /// Cosine-weighted share of rays from `p` that meet `bvh` within `reach`.
    fn traced(bvh: &Bvh, p: Vec3, n: Vec3, reach: f32) -> f32 {
        point_occlusion(bvh, p + n * 1e-4, n, reach, 4096)
    }

    /// Mean occlusion (proxies, mesh) over 96 receivers on a sphere around the mesh's bounds,
    /// `distance` times their half diagonal from the centre, facing the centre, counted within
    /// `reach`; the proxies join as `compose` joins them.
    pub(crate) fn proxies_and_mesh(
        triangles: Vec<Triangle>,
        proxies: &[OccluderSphere],
        distance: f32,
        reach: f32,
    ) -> (f32, f32) {
        let (lo, hi) = triangle_bounds(&triangles);
        let (centre, size) = ((lo + hi) / 2.0, (hi - lo).length() / 2.0);
        let bvh = Bvh::new(triangles);
        let (mut ours, mut theirs) = (0.0, 0.0);
        let count = 96;
        for i in 0..count {
            let a = i as f32 * 2.399_963;
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / count as f32;
            let dir = Vec3::new(
                (1.0 - z * z).sqrt() * a.cos(),
                z,
                (1.0 - z * z).sqrt() * a.sin(),
            );
            let p = centre + dir * size * distance;
            let n = -dir;
            let mut open = 1.0;
            for q in proxies {
                open *= 1.0 - proxy_occlusion(q, p, n, reach).clamp(0.0, 1.0);
            }
            // A rigid mesh's proxies: no skinned proxy, so the union is their product.
            ours += sphere_union([0.0, 1.0 - open], 1.0, 0.0)[1];
            theirs += traced(&bvh, p, n, if reach > 0.0 { reach } else { f32::INFINITY });
        }
        (ours / count as f32, theirs / count as f32)
    }

    /// The proxies of a fit, placed where the mesh was fitted.
    pub(crate) fn rest_proxies(fitted: &super::ClusteredMesh) -> Vec<OccluderSphere> {
        fitted
            .spheres
            .iter()
            .map(|s| OccluderSphere {
                center: s.center,
                radius: s.radius,
                axes: s.axes,
                shape: fitted.shape,
            })
            .collect()
    }

    /// The triangles of `mesh` placed by `placed`.
    pub(crate) fn triangles(mesh: &Mesh, placed: Affine3A) -> Vec<Triangle> {
        let mut scene = crate::reference::scene::TriangleScene::default();
        scene.add_mesh(mesh, placed);
        scene.triangles
    }
}

#[cfg(test)]
mod cast_tests {
    use bevy::math::Affine3A;
    use bevy::prelude::*;

    use super::cast::{proxies_and_mesh, rest_proxies, triangles};
    use super::*;

    /// The occlusion a box, a wall, a thin rod and a ball cast through their boxes, against the
    /// occlusion the meshes themselves cast, on receivers 1.5 and 3 half-diagonals from their
    /// centre (within 2 m and unlimited). Measured: box and wall within 1.5 %, the ball 9 % over
    /// (a box covers more than a round part seen obliquely), the 3 cm rod about 20 % over.
    #[test]
    fn proxies_cast_what_their_meshes_cast() {
        for (name, mesh, bound) in [
            ("box", Mesh::from(Cuboid::new(1.0, 0.6, 0.8)), 0.03),
            ("wall", Mesh::from(Cuboid::new(4.0, 2.5, 0.1)), 0.03),
            (
                "rod",
                Mesh::from(Cylinder::new(0.03, 1.5).mesh().resolution(16)),
                0.25,
            ),
            ("ball", Sphere::new(0.5).mesh().uv(32, 16), 0.12),
        ] {
            let rest = RestMesh::from_mesh(&mesh).unwrap();
            let fitted = fit_boxes(&rest, 16);
            assert_eq!(fitted.spheres.len(), 1, "{name} is one box");
            for (distance, reach) in [(1.5, 2.0), (3.0, 0.0)] {
                let (ours, theirs) = proxies_and_mesh(
                    triangles(&mesh, Affine3A::IDENTITY),
                    &rest_proxies(&fitted),
                    distance,
                    reach,
                );
                println!(
                    "{name}, {distance} half-diagonals, reach {reach}: proxies {ours:.4}, mesh \
                     {theirs:.4}"
                );
                assert!(theirs > 1e-3, "{name}: the receivers should see the mesh");
                assert!(
                    (ours / theirs - 1.0).abs() < bound,
                    "{name}: proxies {ours}, mesh {theirs}"
                );
            }
        }
    }
}

//! One cluster of samples, its principal-axis box, how well the box fills its silhouette, and
//! the 2-means split of a cluster in two.

use bevy::math::{Mat3, Vec2, Vec3};

use super::frame::*;
use super::samples::Sample;
use super::{SILHOUETTE_CELLS, SPLIT_ITERATIONS};

/// One cluster of samples and its principal-axis box.
pub(super) struct Cluster {
    pub(super) samples: Vec<Sample>,
    pub(super) center: Vec3,
    /// Unit principal axes (columns), largest spread first.
    pub(super) axes: Mat3,
    /// Half extents along `axes`, metres.
    pub(super) half: Vec3,
    /// Share of the box's face that the cluster's silhouette covers, seen along each axis.
    pub(super) fill: Vec3,
    /// Too few samples to split further.
    pub(super) settled: bool,
}

impl Cluster {
    pub(super) fn new(samples: Vec<Sample>, cell: f32) -> Self {
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
    pub(super) fn silhouette_fill(&self, axis: usize, cell: f32) -> f32 {
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
    pub(super) fn split_priority(&self) -> f32 {
        let h = self.half;
        let area = h.x * h.y + h.y * h.z + h.x * h.z;
        (1.0 - self.fill.min_element()) * area
    }

    /// 2-means along the longest axis; the cluster back when one side would be empty.
    pub(super) fn split(self, cell: f32) -> Result<(Self, Self), Self> {
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
    pub(super) fn proxy_box(&self, cell: f32) -> (Vec3, Mat3) {
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

    /// The ball that stands for the cluster where it is round: centred on its box, with the
    /// cluster's silhouette area averaged over 13 directions (`mean_directions`) as its disk's.
    pub(super) fn proxy_ball(&self, cell: f32) -> (Vec3, f32) {
        let mean_area = mean_directions()
            .map(|d| self.silhouette_area(self.axes * d, cell))
            .sum::<f32>()
            / mean_directions().count() as f32;
        (self.center, (mean_area / std::f32::consts::PI).sqrt())
    }

    /// How well a proxy's silhouettes cover the cluster's: over the 13 directions of
    /// `mean_directions`, the cells of a grid that both cover over the cells that either does
    /// (intersection over union), a cell counting for the proxy where its centre lies in the
    /// proxy's projection. `ball` is `Some(radius)` for a ball at `centre`, `None` for the box
    /// `centre` ± `axes`' columns.
    pub(super) fn silhouette_match(
        &self,
        centre: Vec3,
        axes: Mat3,
        ball: Option<f32>,
        cell: f32,
    ) -> f32 {
        let (mut both, mut either) = (0usize, 0usize);
        for d in mean_directions() {
            let direction = self.axes * d;
            let points = self.projected(direction);
            let (u, v) = direction.any_orthonormal_pair();
            let flat = |p: Vec3| Vec2::new(u.dot(p), v.dot(p));
            let c = flat(centre);
            // A box projects to the sum of its three projected half-axes (a zonotope), whose
            // edges run along them: a point lies in it where, measured across each half-axis,
            // its offset from the centre is within the three half-axes' extent.
            let generators = [0, 1, 2].map(|k| flat(axes.col(k)));
            let reach = match ball {
                Some(r) => Vec2::splat(r),
                None => generators.iter().fold(Vec2::ZERO, |m, g| m + g.abs()),
            };
            let inside = |q: Vec2| match ball {
                Some(r) => q.distance_squared(c) <= r * r,
                None => generators.iter().all(|g| {
                    let n = g.perp();
                    let extent: f32 = generators.iter().map(|h| n.dot(*h).abs()).sum();
                    g.length_squared() <= f32::MIN_POSITIVE || n.dot(q - c).abs() <= extent
                }),
            };
            let (lo, hi) = bounds(&points, c - reach, c + reach);
            let grid = Occupancy::new(&points, lo, hi, cell);
            let (cu, cv) = grid.cells;
            for j in 0..cv {
                for i in 0..cu {
                    let at = Vec2::new((i as f32 + 0.5) / cu as f32, (j as f32 + 0.5) / cv as f32);
                    let (ours, theirs) = (inside(lo + grid.span * at), grid.covered[i + cu * j]);
                    both += usize::from(ours && theirs);
                    either += usize::from(ours || theirs);
                }
            }
        }
        if either == 0 {
            0.0
        } else {
            both as f32 / either as f32
        }
    }

    /// The area of the samples' silhouette seen along unit `direction`: occupied cells of a grid
    /// over its bounds, less half of those on its edge.
    pub(super) fn silhouette_area(&self, direction: Vec3, cell: f32) -> f32 {
        let points = self.projected(direction);
        let (lo, hi) = bounds(&points, Vec2::INFINITY, Vec2::NEG_INFINITY);
        let grid = Occupancy::new(&points, lo, hi, cell);
        // A flat cluster seen edge-on has no area.
        edge_corrected_share(&grid.covered, grid.cells.0, grid.cells.1)
            * (hi.x - lo.x)
            * (hi.y - lo.y)
    }

    /// The samples seen along unit `direction`, in a plane across it.
    fn projected(&self, direction: Vec3) -> Vec<Vec2> {
        let (u, v) = direction.any_orthonormal_pair();
        self.samples
            .iter()
            .map(|s| Vec2::new(u.dot(s.position), v.dot(s.position)))
            .collect()
    }
}

/// The bounds of `points` and of the rectangle `lo`–`hi`.
fn bounds(points: &[Vec2], lo: Vec2, hi: Vec2) -> (Vec2, Vec2) {
    points
        .iter()
        .fold((lo, hi), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

/// Which cells of a grid over `lo`–`hi` (square cells of about `cell`, at most
/// `SILHOUETTE_CELLS` a side) hold a point.
struct Occupancy {
    covered: Vec<bool>,
    /// Cells along each side.
    cells: (usize, usize),
    /// The grid's size, never 0.
    span: Vec2,
}

impl Occupancy {
    fn new(points: &[Vec2], lo: Vec2, hi: Vec2, cell: f32) -> Self {
        let count = |span: f32| ((span / cell).ceil() as usize).clamp(1, SILHOUETTE_CELLS);
        let (cu, cv) = (count(hi.x - lo.x), count(hi.y - lo.y));
        let span = (hi - lo).max(Vec2::splat(1e-12));
        let mut covered = vec![false; cu * cv];
        for p in points {
            let i = (((p.x - lo.x) / span.x * cu as f32) as usize).min(cu - 1);
            let j = (((p.y - lo.y) / span.y * cv as f32) as usize).min(cv - 1);
            covered[i + cu * j] = true;
        }
        Self {
            covered,
            cells: (cu, cv),
            span,
        }
    }
}

//! One cluster of samples, its principal-axis box, how well the box fills its silhouette, and
//! the 2-means split of a cluster in two.

use bevy::math::{Mat3, Vec3};

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

    /// The area of the samples' silhouette seen along unit `direction`: occupied cells of a grid
    /// over its bounds, less half of those on its edge.
    pub(super) fn silhouette_area(&self, direction: Vec3, cell: f32) -> f32 {
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

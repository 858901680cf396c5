//! The orientation and size of a box: principal axes, the dominant surface normal, the tightest
//! turn about an axis, and silhouette coverage.

use bevy::math::{Mat3, Vec3};

use super::samples::{Sample, bounds};

/// 13 directions spread over the half sphere: the axes, the face diagonals and the body
/// diagonals.
pub(super) fn mean_directions() -> impl Iterator<Item = Vec3> {
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
pub(super) fn edge_corrected_share(covered: &[bool], cu: usize, cv: usize) -> f32 {
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
pub(super) fn local_bounds(samples: &[Sample], axes: Mat3) -> (Vec3, Vec3) {
    let to_local = axes.transpose();
    bounds(samples.iter().map(|s| to_local * s.position))
}

/// A box's volume, each side at least one cell, so flat boxes compare by area.
pub(super) fn box_volume((lo, hi): (Vec3, Vec3), cell: f32) -> f32 {
    let size = (hi - lo).max(Vec3::splat(cell));
    size.x * size.y * size.z
}

/// The frame whose third axis is `axis`, turned about it so that the samples' bounds across it
/// have the least area (32 turns over a quarter circle).
pub(super) fn tightest_about(samples: &[Sample], axis: Vec3, cell: f32) -> Mat3 {
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
pub(super) fn dominant_normal(samples: &[Sample]) -> Option<Vec3> {
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
pub(super) fn principal_axes(m: Mat3) -> Mat3 {
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

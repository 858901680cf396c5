//! Dense samples of a mesh's surface and the centres of the voxels it encloses: the solid the
//! boxes are fitted to.

use bevy::math::Vec3;

use super::CELLS;
use crate::geometry::rest_mesh::RestMesh;

/// A point of the mesh's solid: a sample of its surface or the centre of an interior voxel.
#[derive(Clone, Copy)]
pub(super) struct Sample {
    pub(super) position: Vec3,
    /// Volume it stands for, m³ (surface samples: their area times a third of a cell).
    pub(super) weight: f32,
    /// The surface's unit normal at a surface sample; zero inside.
    pub(super) normal: Vec3,
    /// The joint that moves a surface sample of a skinned mesh most; `u16::MAX` otherwise.
    pub(super) joint: u16,
}

pub(super) fn cell_size(mesh: &RestMesh) -> f32 {
    let (lo, hi) = bounds(mesh.positions.iter().copied());
    ((hi - lo).max_element() / CELLS).max(1e-6)
}

pub(super) fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    points
        .filter(|p| p.is_finite())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        })
}

/// Dense samples of the surface, and the centres of the voxels it encloses.
pub(super) fn solid_samples(mesh: &RestMesh) -> Vec<Sample> {
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

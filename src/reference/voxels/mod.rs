//! Voxel volumes on the CPU: triangle–cell voxelization by brute force over each triangle's
//! bounding box, and the AO sampling of `voxels/voxel_ao.wgsl`, step for step with the same
//! hashes, so the GPU passes can be checked against them.

use bevy::math::{Affine3A, Vec2, Vec3};

use super::filter::wendland;
use super::nd_buffer::{NdBuffer, ViewMatrices};
use super::sampling::{pcg_hash, tangent_frame};
use crate::geometry::triangles::Triangle;
use crate::voxels::{VoxelAoVolume, VoxelFalloff, VoxelMarch, VoxelRays};

/// A bit grid of `resolution`³ cells; cell (x, y, z) is bit `i % 32` of word `i / 32`,
/// `i = x + resolution · (y + resolution · z)`, in two layers: the surface cells triangles touch,
/// and the interior cells of closed meshes. A cell is occupied when either bit is set.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelGrid {
    /// Cells per axis.
    pub resolution: u32,
    /// World space → grid space; cell (x, y, z) spans [x, x + 1]³.
    pub grid_from_world: Affine3A,
    /// Surface bits.
    pub words: Vec<u32>,
    /// Interior bits (parity of the closed surfaces below each cell centre).
    pub solid: Vec<u32>,
}

impl VoxelGrid {
    /// An empty grid.
    pub fn new(resolution: u32, grid_from_world: Affine3A) -> Self {
        Self {
            resolution,
            grid_from_world,
            words: vec![0; crate::voxels::VoxelGridInfo::words_for(resolution) as usize],
            solid: vec![0; crate::voxels::VoxelGridInfo::words_for(resolution) as usize],
        }
    }

    fn index(&self, cell: [i32; 3]) -> Option<usize> {
        let n = self.resolution as i32;
        if cell.iter().any(|&c| c < 0 || c >= n) {
            return None;
        }
        Some((cell[0] + n * (cell[1] + n * cell[2])) as usize)
    }

    /// Whether cell `cell` is occupied (false outside the grid).
    pub fn occupied(&self, cell: [i32; 3]) -> bool {
        self.index(cell)
            .is_some_and(|i| (self.words[i / 32] | self.solid[i / 32]) & (1 << (i % 32)) != 0)
    }

    fn set(&mut self, cell: [i32; 3]) {
        if let Some(i) = self.index(cell) {
            self.words[i / 32] |= 1 << (i % 32);
        }
    }

    /// Whether the cell holding world point `p` is occupied.
    pub fn occupied_at(&self, p: Vec3) -> bool {
        let g = self.grid_from_world.transform_point3(p).floor();
        self.occupied([g.x as i32, g.y as i32, g.z as i32])
    }

    /// Occupied cells.
    pub fn count(&self) -> u32 {
        self.words
            .iter()
            .zip(&self.solid)
            .map(|(w, s)| (w | s).count_ones())
            .sum()
    }

    /// Fills the interior of closed `triangles` (world space): every triangle flips the interior
    /// bit of every cell whose centre lies above it along the grid's z axis, so a cell ends up set
    /// when an odd number of surfaces lie below it. Shared edges and vertices count once, by the
    /// top-left rule on edge values computed the same way for both triangles that share an edge.
    pub fn fill_closed(&mut self, triangles: &[Triangle]) {
        let n = self.resolution as i32;
        for t in triangles {
            let [a, b, c] = t.vertices.map(|p| self.grid_from_world.transform_point3(p));
            let Some(triangle) = ClosedTriangle::new(a, b, c, n) else {
                continue;
            };
            let (lo, hi) = triangle.columns;
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let Some(first) = triangle.first_cell_above(x, y) else {
                        continue;
                    };
                    for z in first..n {
                        let i = (x + n * (y + n * z)) as usize;
                        self.solid[i / 32] ^= 1 << (i % 32);
                    }
                }
            }
        }
    }
}

/// The value of the 2D edge function of (a, b) at p, computed from the lexicographically smaller
/// end, so the two triangles that share an edge get exactly opposite values.
pub fn edge_value(a: Vec2, b: Vec2, p: Vec2) -> f32 {
    if a.x < b.x || (a.x == b.x && a.y < b.y) {
        (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)
    } else {
        -((a.x - b.x) * (p.y - b.y) - (a.y - b.y) * (p.x - b.x))
    }
}

/// Whether a point with edge value `e` on edge a → b of a counter-clockwise triangle belongs to
/// it: inside, or on an edge it owns (the top-left rule).
fn owns(e: f32, a: Vec2, b: Vec2) -> bool {
    let d = b - a;
    e > 0.0 || (e == 0.0 && (d.y > 0.0 || (d.y == 0.0 && d.x < 0.0)))
}

/// A closed-mesh triangle in grid space, turned counter-clockwise as seen down the z axis.
pub struct ClosedTriangle {
    p: [Vec3; 3],
    area: f32,
    /// First and last column (x, y) of its bounds, clamped to the grid.
    pub columns: (bevy::math::IVec2, bevy::math::IVec2),
}

impl ClosedTriangle {
    /// None for triangles edge-on to z, not finite, or outside the grid's columns or above it.
    pub fn new(a: Vec3, b: Vec3, c: Vec3, n: i32) -> Option<Self> {
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            return None;
        }
        let area = edge_value(a.truncate(), b.truncate(), c.truncate());
        if area == 0.0 {
            return None;
        }
        let p = if area > 0.0 { [a, b, c] } else { [b, a, c] };
        let lo = a.min(b.min(c)).truncate().floor().as_ivec2();
        let hi = a.max(b.max(c)).truncate().floor().as_ivec2();
        let lo = lo.max(bevy::math::IVec2::ZERO);
        let hi = hi.min(bevy::math::IVec2::splat(n - 1));
        if lo.x > hi.x || lo.y > hi.y || a.z.min(b.z.min(c.z)) >= n as f32 {
            return None;
        }
        Some(Self {
            p,
            area: area.abs(),
            columns: (lo, hi),
        })
    }

    /// The first cell of column (x, y) whose centre lies above the triangle, or None when the
    /// column's centre is not covered by it.
    pub fn first_cell_above(&self, x: i32, y: i32) -> Option<i32> {
        let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let [p0, p1, p2] = self.p;
        let (v0, v1, v2) = (p0.truncate(), p1.truncate(), p2.truncate());
        let e0 = edge_value(v1, v2, q);
        let e1 = edge_value(v2, v0, q);
        let e2 = edge_value(v0, v1, q);
        if !(owns(e0, v1, v2) && owns(e1, v2, v0) && owns(e2, v0, v1)) {
            return None;
        }
        let z = (e0 * p0.z + e1 * p1.z + e2 * p2.z) / self.area;
        Some(((z - 0.5).floor() as i32 + 1).max(0))
    }
}

/// Whether the triangle (v0, v1, v2), relative to a cell's centre, overlaps the cell [−½, ½]³:
/// the separating-axis test of Akenine-Möller (2001), touching counts as overlapping.
pub fn triangle_overlaps_cell(v0: Vec3, v1: Vec3, v2: Vec3) -> bool {
    let edges = [v1 - v0, v2 - v1, v0 - v2];
    for edge in edges {
        for unit in [Vec3::X, Vec3::Y, Vec3::Z] {
            let axis = unit.cross(edge);
            let (p0, p1, p2) = (axis.dot(v0), axis.dot(v1), axis.dot(v2));
            let r = 0.5 * (axis.x.abs() + axis.y.abs() + axis.z.abs());
            if p0.min(p1.min(p2)) > r || p0.max(p1.max(p2)) < -r {
                return false;
            }
        }
    }
    let lo = v0.min(v1.min(v2));
    let hi = v0.max(v1.max(v2));
    if lo.cmpgt(Vec3::splat(0.5)).any() || hi.cmplt(Vec3::splat(-0.5)).any() {
        return false;
    }
    let normal = edges[0].cross(edges[1]);
    let r = 0.5 * (normal.x.abs() + normal.y.abs() + normal.z.abs());
    normal.dot(v0).abs() <= r
}

/// Voxelizes world-space `triangles` into a grid of `resolution`³ cells placed by
/// `grid_from_world`: every cell of each triangle's bounding box is tested.
pub fn voxelize(triangles: &[Triangle], resolution: u32, grid_from_world: Affine3A) -> VoxelGrid {
    let mut grid = VoxelGrid::new(resolution, grid_from_world);
    let last = resolution as i32 - 1;
    for t in triangles {
        let [a, b, c] = t.vertices.map(|p| grid_from_world.transform_point3(p));
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            continue;
        }
        let lo = a.min(b.min(c)).floor();
        let hi = a.max(b.max(c)).floor();
        if hi.min_element() < 0.0 || lo.max_element() > last as f32 {
            continue;
        }
        let lo = lo
            .as_ivec3()
            .clamp(bevy::math::IVec3::ZERO, bevy::math::IVec3::splat(last));
        let hi = hi
            .as_ivec3()
            .clamp(bevy::math::IVec3::ZERO, bevy::math::IVec3::splat(last));
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let centre = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
                    if triangle_overlaps_cell(a - centre, b - centre, c - centre) {
                        grid.set([x, y, z]);
                    }
                }
            }
        }
    }
    grid
}

const GOLDEN_RATIO_FRACTION: f32 = 0.618_034;

/// The hash of the world-space noise cell holding `p`.
pub fn cell_hash(p: Vec3, cell: f32) -> u32 {
    let c = (p / cell).floor();
    pcg_hash((c.x as i32) as u32 ^ pcg_hash((c.y as i32) as u32 ^ pcg_hash((c.z as i32) as u32)))
}

fn unit_float(h: u32) -> f32 {
    (h >> 8) as f32 / 16_777_216.0
}

/// Ray `i` of `count` around +Z: a spiral over the cone of half-angle acos(cos_spread), uniform
/// in solid angle, shifted by the jitter (j1, j2).
pub fn ray_direction(i: u32, count: u32, cos_spread: f32, j1: f32, j2: f32) -> Vec3 {
    let cos_theta = 1.0 - (i as f32 + j1) / count as f32 * (1.0 - cos_spread);
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * (i as f32 * GOLDEN_RATIO_FRACTION + j2).fract();
    Vec3::new(phi.cos() * sin_theta, phi.sin() * sin_theta, cos_theta)
}

/// 1 / v per component, with ±1e30 for components that are 0, as `voxel_ao.wgsl` does it.
fn safe_inverse(v: Vec3) -> Vec3 {
    let one = |x: f32| {
        if x.abs() < 1e-20 {
            if x < 0.0 { -1e30 } else { 1e30 }
        } else {
            1.0 / x
        }
    };
    Vec3::new(one(v.x), one(v.y), one(v.z))
}

/// World distance along the ray to where it has travelled
/// [`VoxelAoVolume::HIT_DEPTH`] cells through occupied cells in a row, walking every cell it
/// crosses (Amanatides & Woo 1987), exactly as `first_hit_cells` in `voxel_ao.wgsl`; `None`
/// when that lies beyond `reach`.
pub fn first_hit_cells(grid: &VoxelGrid, origin: Vec3, direction: Vec3, reach: f32) -> Option<f32> {
    let g0 = grid.grid_from_world.transform_point3(origin);
    let gd = grid.grid_from_world.transform_vector3(direction);
    let inverse = safe_inverse(gd);
    let n = grid.resolution as f32;
    let t0 = -g0 * inverse;
    let t1 = (Vec3::splat(n) - g0) * inverse;
    let (near, far) = (t0.min(t1), t0.max(t1));
    let mut t = near.max_element().max(0.0);
    let end = far.min_element().min(reach);
    if t > end {
        return None;
    }
    let last = grid.resolution as i32 - 1;
    let start = (g0 + gd * t).floor();
    let mut cell = [start.x, start.y, start.z].map(|c| (c as i32).clamp(0, last));
    let step = [gd.x, gd.y, gd.z].map(|d| {
        if d > 0.0 {
            1
        } else if d < 0.0 {
            -1
        } else {
            0
        }
    });
    let boundary = Vec3::new(
        cell[0] as f32 + if gd.x > 0.0 { 1.0 } else { 0.0 },
        cell[1] as f32 + if gd.y > 0.0 { 1.0 } else { 0.0 },
        cell[2] as f32 + if gd.z > 0.0 { 1.0 } else { 0.0 },
    );
    let mut next = (boundary - g0) * inverse;
    let delta = inverse.abs();
    let grid_per_metre = gd.length();
    let mut inside = 0.0;
    for _ in 0..3 * grid.resolution + 3 {
        if grid.occupied(cell) {
            let exit = next.min_element().min(end);
            let through = (exit - t) * grid_per_metre;
            if inside + through >= VoxelAoVolume::HIT_DEPTH {
                return Some(t + (VoxelAoVolume::HIT_DEPTH - inside) / grid_per_metre);
            }
            inside += through;
        } else {
            inside = 0.0;
        }
        let axis = if next.x <= next.y && next.x <= next.z {
            0
        } else if next.y <= next.z {
            1
        } else {
            2
        };
        t = next[axis];
        next[axis] += delta[axis];
        cell[axis] += step[axis];
        if t > end || cell.iter().any(|c| *c < 0 || *c > last) {
            return None;
        }
    }
    None
}

/// What a camera brings to a volume's rays.
#[derive(Clone, Copy, Debug)]
pub struct VoxelCamera<'a> {
    /// The camera's radius R, metres: the reach of volumes without a d_max of their own.
    pub radius: f32,
    /// Under `FarFieldBlend::CountOnce`, the near field's reach, metres, and the ND-buffer
    /// whose held geometry within it is left to the near field (with whether its back layer
    /// counts); `None` where the voxels count every hit.
    pub count_once: Option<(f32, &'a NdBuffer, &'a ViewMatrices, bool)>,
}

/// Occlusion of the surface at `p` with unit normal `n` in one volume (eq. 4, normalized by the
/// cosines; 0 = open, 1 = enclosed at distance 0), in the two channels of `voxel_ao.wgsl`: hits
/// within the near field's reach the ND-buffer does not hold, and the rest as a share of the
/// rays those leave open.
pub fn volume_occlusion(
    grid: &VoxelGrid,
    rays: &VoxelRays,
    camera: &VoxelCamera,
    p: Vec3,
    n: Vec3,
) -> [f32; 2] {
    let reach = rays.reach(camera.radius);
    let g = grid.grid_from_world.transform_point3(p);
    let size = Vec3::splat(grid.resolution as f32);
    let margin = (reach + rays.bias) / rays.cell;
    if g.cmplt(-margin).any() || g.cmpgt(size + margin).any() {
        return [0.0, 0.0];
    }
    let h = cell_hash(p, rays.noise_cell);
    let (j1, j2, j3) = (
        unit_float(pcg_hash(h)),
        unit_float(pcg_hash(h.wrapping_add(1))),
        unit_float(pcg_hash(h.wrapping_add(2))),
    );
    let frame = tangent_frame(n);
    let origin = p + n * rays.bias;
    let (mut occlusion, mut cosines, mut near_blocked) = ([0.0f32; 2], 0.0f32, 0.0f32);
    for i in 0..rays.rays {
        let local = ray_direction(i, rays.rays, rays.cos_spread, j1, j2);
        let direction = frame * local;
        cosines += local.z;
        let hit = match rays.march {
            VoxelMarch::Cells => first_hit_cells(grid, origin, direction, reach),
            VoxelMarch::Steps(steps) => (0..steps)
                .map(|s| reach * (s as f32 + j3) / steps as f32)
                .find(|t| grid.occupied_at(origin + direction * *t)),
        };
        let Some(t) = hit else {
            continue;
        };
        let weight = match rays.falloff {
            VoxelFalloff::Wendland => wendland(t, reach),
            VoxelFalloff::None => 1.0,
        } * local.z;
        match camera.count_once {
            Some((near_radius, nd, view, use_back)) if t < near_radius => {
                occlusion[0] +=
                    weight * (1.0 - nd.holds(view, use_back, origin + direction * t, rays.bias));
                near_blocked += local.z;
            }
            _ => occlusion[1] += weight,
        }
    }
    [
        if cosines > 0.0 {
            occlusion[0] / cosines
        } else {
            0.0
        },
        if cosines - near_blocked > 0.0 {
            occlusion[1] / (cosines - near_blocked)
        } else {
            0.0
        },
    ]
}

/// The half-resolution AO map of `voxels/voxel_ao.wgsl`: texel (i, j) is the largest occlusion
/// over `volumes` at full-resolution pixel (2i, 2j), per channel; row-major, `(w + 1) / 2` ×
/// `(h + 1) / 2`.
pub fn voxel_ao_map(
    nd: &NdBuffer,
    view: &ViewMatrices,
    volumes: &[(VoxelGrid, VoxelRays)],
    camera: &VoxelCamera,
) -> Vec<[f32; 2]> {
    let (w, h) = (nd.width, nd.height);
    let (lw, lh) = (w.div_ceil(2), h.div_ceil(2));
    let mut out = vec![[0.0; 2]; (lw * lh) as usize];
    for ly in 0..lh {
        for lx in 0..lw {
            let (x, y) = ((lx * 2).min(w - 1) as i32, (ly * 2).min(h - 1) as i32);
            let Some(t) = nd.texel(false, x, y).filter(|t| t.depth > 0.0) else {
                continue;
            };
            let p = view.world_position(x, y, w, h, t.depth);
            out[(ly * lw + lx) as usize] = volumes
                .iter()
                .map(|(grid, rays)| volume_occlusion(grid, rays, camera, p, t.normal))
                .fold([0.0f32, 0.0], |a, b| [a[0].max(b[0]), a[1].max(b[1])]);
        }
    }
    out
}

#[cfg(test)]
mod tests;

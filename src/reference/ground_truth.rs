//! Ray-traced ground-truth ambient occlusion (eq. 1 of the papers): for the surface a camera
//! sees at each pixel centre, the cosine-weighted fraction of hemisphere rays that hit nothing
//! within `radius`. 1 = open; pixels that see no geometry read 1.

use bevy::math::{Vec3, Vec4, Vec4Swizzles};

use super::nd_buffer::ViewMatrices;
use super::sampling::pcg_hash;
use crate::geometry::bvh::Bvh;

/// How to trace a ground-truth image.
#[derive(Clone, Copy, Debug)]
pub struct GroundTruthSettings {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Rays longer than this do not count as hits (metres).
    pub radius: f32,
    /// Hemisphere rays per pixel; rounded down to a square number for stratification.
    pub rays_per_pixel: u32,
}

/// The primary ray through the centre of pixel (x, y): origin on the near plane, unit direction.
pub fn camera_ray(view: &ViewMatrices, x: u32, y: u32, width: u32, height: u32) -> (Vec3, Vec3) {
    let u = (x as f32 + 0.5) / width as f32 * 2.0 - 1.0;
    let v = 1.0 - (y as f32 + 0.5) / height as f32 * 2.0;
    let unproject = |depth: f32| {
        let p = view.world_from_clip * Vec4::new(u, v, depth, 1.0);
        p.xyz() / p.w
    };
    let near = unproject(1.0);
    let far = unproject(1e-3);
    (near, (far - near).normalize())
}

/// Whether the primary ray of each pixel meets a triangle, row-major: the pixels that show
/// geometry, over which errors against ground truth are measured.
pub fn geometry_mask(bvh: &Bvh, view: &ViewMatrices, width: u32, height: u32) -> Vec<bool> {
    (0..width * height)
        .map(|i| {
            let (origin, direction) = camera_ray(view, i % width, i / width, width, height);
            bvh.closest_hit(origin, direction, 0.0, f32::INFINITY)
                .is_some()
        })
        .collect()
}

/// Visibility of every pixel, row-major. Uses every available core.
pub fn ground_truth_visibility(
    bvh: &Bvh,
    view: &ViewMatrices,
    settings: &GroundTruthSettings,
) -> Vec<f32> {
    let (w, h) = (settings.width, settings.height);
    let mut out = vec![1.0; (w * h) as usize];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let rows_per_chunk = (h as usize).div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        for (chunk_index, chunk) in out.chunks_mut(rows_per_chunk * w as usize).enumerate() {
            scope.spawn(move || {
                for (i, value) in chunk.iter_mut().enumerate() {
                    let index = chunk_index * rows_per_chunk * w as usize + i;
                    let (x, y) = ((index % w as usize) as u32, (index / w as usize) as u32);
                    *value = pixel_visibility(bvh, view, settings, x, y);
                }
            });
        }
    });
    out
}

/// Visibility of one pixel.
pub fn pixel_visibility(
    bvh: &Bvh,
    view: &ViewMatrices,
    settings: &GroundTruthSettings,
    x: u32,
    y: u32,
) -> f32 {
    let (origin, direction) = camera_ray(view, x, y, settings.width, settings.height);
    let Some(hit) = bvh.closest_hit(origin, direction, 0.0, f32::INFINITY) else {
        return 1.0;
    };
    let triangle = &bvh.triangles()[hit.triangle];
    let p = origin + direction * hit.t;
    let mut face = triangle.face_normal().normalize();
    if face.dot(direction) > 0.0 {
        face = -face;
    }
    let (u, v) = hit.uv;
    let mut n = triangle
        .normals
        .map(|[a, b, c]| (a * (1.0 - u - v) + b * u + c * v).normalize_or_zero())
        .filter(|n| *n != Vec3::ZERO)
        .unwrap_or(face);
    if n.dot(face) < 0.0 {
        n = -n;
    }
    let eps = 1e-4 * p.abs().max_element().max(1.0);
    let start = p + face * eps;
    let (t1, t2) = n.any_orthonormal_pair();
    let side = (settings.rays_per_pixel as f32).sqrt().floor().max(1.0) as u32;
    let seed = pcg_hash(x.wrapping_mul(7919) ^ pcg_hash(y.wrapping_add(0x9e37)));
    let mut open = 0u32;
    for i in 0..side * side {
        // Stratified, jittered cosine-weighted sample (Malley's method).
        let h1 = pcg_hash(seed ^ (2 * i));
        let h2 = pcg_hash(seed ^ (2 * i + 1) ^ 0x5bd1_e995);
        let s1 = ((i % side) as f32 + h1 as f32 / u32::MAX as f32) / side as f32;
        let s2 = ((i / side) as f32 + h2 as f32 / u32::MAX as f32) / side as f32;
        let r = s1.sqrt();
        let phi = std::f32::consts::TAU * s2;
        let local_z = (1.0 - s1).max(0.0).sqrt();
        let dir = t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + n * local_z;
        if !bvh.any_hit(start, dir, 0.0, settings.radius) {
            open += 1;
        }
    }
    open as f32 / (side * side) as f32
}

/// Occlusion (0 = open) of the surface point `p` with unit normal `n` by `bvh`: the
/// cosine-weighted share of `count` hemisphere rays that meet a triangle within `reach`. The
/// directions lie on a spiral, each at its own elevation, so that small caps are measured finely;
/// `p` should lie just off its own surface.
pub fn point_occlusion(bvh: &Bvh, p: Vec3, n: Vec3, reach: f32, count: u32) -> f32 {
    let (t1, t2) = n.any_orthonormal_pair();
    let mut hit = 0u32;
    for i in 0..count {
        let u = (i as f32 + 0.5) / count as f32;
        let phi = std::f32::consts::TAU * (i as f32 * 0.618_034).fract();
        let r = u.sqrt();
        let d = t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + n * (1.0 - u).sqrt();
        hit += u32::from(bvh.any_hit(p, d, 0.0, reach));
    }
    hit as f32 / count.max(1) as f32
}

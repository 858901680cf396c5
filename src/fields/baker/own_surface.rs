//! The object's own surface beyond the near field's reach: under count-once the near field shades
//! the object's own surface only within `near_field_radius`, so grid points next to the surface
//! also store what the object blocks of their nearest surface point's hemisphere between that
//! reach and R (see the `fields` module docs, "Its own surface beyond the near field's reach").

use bevy::math::Vec3;

use crate::geometry::bvh::Bvh;

/// How the grid points next to the surface sample the surface's own hemisphere.
pub(super) struct OwnSurface<'a> {
    /// Cosine-weighted directions about +z.
    pub hemisphere: &'a [Vec3],
    /// Grid points this close to the surface sample it, mesh units.
    pub within: f32,
    /// Sample nothing (the field has no near reach below its reach).
    pub skip: bool,
}

/// `count` directions over the hemisphere about +z with density cos θ / π: a Fibonacci lattice
/// on the unit disc lifted onto the hemisphere (Malley's method).
pub(super) fn cosine_hemisphere(count: u32) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..count)
        .map(|i| {
            let r = ((i as f32 + 0.5) / count as f32).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - r * r).max(0.0).sqrt())
        })
        .collect()
}

/// At surface point `at` with unit normal `n` (on the side to sample): of the hemisphere's
/// directions that meet nothing within `near`, the share that meets the object within `reach`.
/// This is what ground truth counts on the surface beyond the near field's reach, as the
/// probability compose's independent join expects (`share_beyond` on the GPU).
pub(super) fn beyond_near(
    bvh: &Bvh,
    hemisphere: &[Vec3],
    at: Vec3,
    n: Vec3,
    near: f32,
    reach: f32,
) -> f32 {
    let (t1, t2) = n.any_orthonormal_pair();
    // Off the surface by a hair, so the ray does not meet the triangle it starts on.
    let origin = at + n * (1e-4 * (1.0 + at.abs().max_element()));
    let (mut open, mut beyond) = (0u32, 0u32);
    for h in hemisphere {
        let d = t1 * h.x + t2 * h.y + n * h.z;
        match bvh.closest_hit(origin, d, 0.0, reach) {
            Some(hit) if hit.t < near => {}
            Some(hit) if hit.t < reach => {
                open += 1;
                beyond += 1;
            }
            _ => open += 1,
        }
    }
    if open == 0 {
        0.0
    } else {
        beyond as f32 / open as f32
    }
}

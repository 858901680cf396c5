//! What one grid point of a field stores, and the rays from it that find it.

use bevy::math::Vec3;

use super::axes::AxisHemispheres;
use super::own_surface::{OwnSurface, beyond_near};
use crate::geometry::bvh::Bvh;

/// What one grid point stores.
#[derive(Clone, Copy, Default)]
pub(super) struct Cell {
    /// Occlusion a and mean occluded direction, hits within the reach.
    pub far: [f32; 4],
    /// The same within the near reach.
    pub near: [f32; 4],
    /// Signed distance to the surface.
    pub signed_distance: f32,
    /// Mean offset to the near hits.
    pub near_offset: Vec3,
    /// The own surface's share beyond the near reach and its normal.
    pub own_surface: [f32; 4],
    /// The cone's corrections on the axis hemispheres, within the reach then the near reach.
    pub axes: [f32; 12],
}

/// The distances a grid point's rays count within, mesh units.
pub(super) struct SampleDistances {
    /// Hits count within this (∞: at any distance).
    pub reach: f32,
    /// The near part counts hits within this.
    pub near: f32,
    /// The signed distance of a point whose rays meet nothing.
    pub miss: f32,
}

/// Occlusion (eq. 2: the blocked fraction of all directions) and average occluded direction at
/// `p`, for hits within `reach` and within `near`; the signed distance to the surface (the
/// nearest hit, negative where most hits meet back faces: inside a closed object or behind a
/// one-sided one; `miss` where nothing is hit) and the mean offset to the near hits: a point on
/// (or within) the part of the object the near rays meet. Outside the object and within
/// `own.within` of its surface, the nearest hit stands for the nearest surface point, and its
/// hemisphere on this point's side is sampled beyond the near reach ([`beyond_near`]); `axes`
/// turns the hits into the cone's corrections.
pub(super) fn sample(
    bvh: &Bvh,
    directions: &[Vec3],
    own: &OwnSurface,
    axes: &AxisHemispheres,
    p: Vec3,
    distances: &SampleDistances,
) -> Cell {
    let &SampleDistances { reach, near, miss } = distances;
    let (mut far_count, mut near_count) = (0u32, 0u32);
    let (mut far_sum, mut near_sum) = (Vec3::ZERO, Vec3::ZERO);
    let (mut far_axes, mut near_axes) = ([0.0f32; 6], [0.0f32; 6]);
    let (mut nearest, mut near_offset, mut back, mut front) =
        (f32::INFINITY, Vec3::ZERO, 0u32, 0u32);
    // The nearest hit's point and its triangle's unit normal turned towards `p`.
    let mut nearest_surface = (Vec3::ZERO, Vec3::ZERO);
    for &d in directions {
        let Some(hit) = bvh.closest_hit(p, d, 0.0, f32::INFINITY) else {
            continue;
        };
        let normal = bvh.triangles()[hit.triangle]
            .face_normal()
            .normalize_or_zero();
        if hit.t < nearest {
            nearest = hit.t;
            let side = if normal.dot(d) > 0.0 { -normal } else { normal };
            nearest_surface = (p + d * hit.t, side);
        }
        if normal.dot(d) > 0.0 {
            back += 1;
        } else {
            front += 1;
        }
        if hit.t < reach {
            far_count += 1;
            far_sum += d;
            AxisHemispheres::add(&mut far_axes, d);
        }
        if hit.t < near {
            near_count += 1;
            near_sum += d;
            near_offset += d * hit.t;
            AxisHemispheres::add(&mut near_axes, d);
        }
    }
    let rays = directions.len() as f32;
    let cone = |count: u32, sum: Vec3| {
        let d = sum.normalize_or_zero();
        [count as f32 / rays, d.x, d.y, d.z]
    };
    let (far, near_cone) = (cone(far_count, far_sum), cone(near_count, near_sum));
    let far_error = axes.cone_error(&far_axes, far);
    let near_error = axes.cone_error(&near_axes, near_cone);
    let distance = if nearest.is_finite() { nearest } else { miss };
    let (at, side) = nearest_surface;
    // Points inside the object are never read: the lookup takes the grid points outside (a
    // point inside a box, under its bottom face, would see the box's inside from there).
    let inside = back > front;
    let own_surface = if own.skip || inside || nearest > own.within || side == Vec3::ZERO {
        [0.0; 4]
    } else {
        let share = beyond_near(bvh, own.hemisphere, at, side, near, reach);
        [share, side.x, side.y, side.z]
    };
    Cell {
        far,
        near: near_cone,
        axes: std::array::from_fn(|k| {
            if k < 6 {
                far_error[k]
            } else {
                near_error[k - 6]
            }
        }),
        signed_distance: if back > front { -distance } else { distance },
        near_offset: if near_count > 0 {
            near_offset / near_count as f32
        } else {
            Vec3::ZERO
        },
        own_surface,
    }
}

//! AO field occlusion (Malmer et al. 2005, §3.2–3.3) on the CPU, exactly as `fields/fields.wgsl`
//! evaluates it: trilinear interpolation between cell centres over the corners outside the
//! object, the fade on the object's own surface (where the receiver faces the way it does) and its
//! own share beyond the near reach there,
//! 2a or the clipped cone (T_clip, through [`cap_occlusion`], with its axis corrections) per
//! occluder, split into the near
//! field's share and the rest, visibilities multiplied.

use bevy::math::{Affine3A, Vec3, Vec4};

use super::nd_buffer::{NdBuffer, ViewMatrices};
use crate::fields::AoFieldData;
use crate::fields::join::{field_joins, object_bounds};
use crate::geometry::cap::{cap_occlusion, share_beyond};
use crate::geometry::union::occluder_union;
use crate::settings::FieldShading;

/// The interpolated content of a field at one point.
#[derive(Clone, Copy, Debug, Default)]
pub struct FieldSample {
    /// Occlusion a and average occluded direction (mesh space), hits within the reach.
    pub far: Vec4,
    /// The same within the near reach.
    pub near: Vec4,
    /// Mean offset to the points the near rays meet, mesh units.
    pub near_offset: Vec3,
    /// Signed distance to the object's surface, mesh units.
    pub signed_distance: f32,
    /// On the object's own surface, the share of its hemisphere blocked beyond the near reach.
    pub own_surface: f32,
    /// How far the receiver lies along the object's surface there: 1 where its normal is the
    /// surface's (either side, the signed distance's gradient), 0 where it stands across it (a
    /// wall standing on a floor).
    pub along: f32,
    /// The cone's errors on the axis hemispheres +x, −x, +y, −y, +z, −z within the reach, then
    /// within the near reach ([`AoFieldData::axes`]).
    pub axes: [f32; 12],
}

/// Own-surface grid points whose surface normal is this close to the receiver's count.
const SAME_SIDE: f32 = 0.5;
/// The receiver lies along the object's surface (its own) where the cosine between its normal and
/// the surface's is above `ALONG`, and across it (another surface touching the object) below
/// `SIDEWAYS`; a smooth step between.
const SIDEWAYS: f32 = 0.3;
const ALONG: f32 = 0.7;

/// `field` at grid coordinates `uvw` ∈ [0, 1]³, for a receiver with mesh-space unit normal `n`.
pub fn sample_field(field: &AoFieldData, uvw: Vec3, n: Vec3) -> FieldSample {
    let r = field.resolution.as_vec3();
    let g = (uvw * r - 0.5).clamp(Vec3::ZERO, r - 1.0);
    let i0 = g.floor().as_uvec3();
    let i1 = (i0 + 1).min(field.resolution - 1);
    let f = g - i0.as_vec3();
    let mut out = FieldSample::default();
    let (mut outside, mut facing) = (0.0, 0.0);
    // The signed distance's gradient, per grid unit.
    let mut gradient = Vec3::ZERO;
    for corner in 0..8u32 {
        let pick = |bit: u32| corner & bit != 0;
        let c = [
            if pick(1) { i1.x } else { i0.x },
            if pick(2) { i1.y } else { i0.y },
            if pick(4) { i1.z } else { i0.z },
        ];
        let w3 = [
            if pick(1) { f.x } else { 1.0 - f.x },
            if pick(2) { f.y } else { 1.0 - f.y },
            if pick(4) { f.z } else { 1.0 - f.z },
        ];
        let w = w3[0] * w3[1] * w3[2];
        let i = field.index(c[0], c[1], c[2]);
        let [signed, ox, oy, oz] = field.distances[i];
        out.signed_distance += w * signed;
        let [own, sx, sy, sz] = field.own_surface[i];
        let same_side = Vec3::new(sx, sy, sz).dot(n) > SAME_SIDE;
        if same_side {
            facing += w;
            out.own_surface += w * own;
        }
        // d w / d g per axis: the corner's weight along the two other axes, signed by its side.
        let side = |bit: u32| if pick(bit) { 1.0 } else { -1.0 };
        gradient += signed
            * Vec3::new(
                side(1) * w3[1] * w3[2],
                side(2) * w3[0] * w3[2],
                side(4) * w3[0] * w3[1],
            );
        if signed > 0.0 {
            outside += w;
            out.far += w * Vec4::from_array(field.cells[i]);
            out.near += w * Vec4::from_array(field.near_cells[i]);
            out.near_offset += w * Vec3::new(ox, oy, oz);
            for (sum, value) in out.axes.iter_mut().zip(field.axes[i]) {
                *sum += w * value;
            }
        }
    }
    if outside > 0.0 {
        out.far /= outside;
        out.near /= outside;
        out.near_offset /= outside;
        for sum in &mut out.axes {
            *sum /= outside;
        }
    }
    if facing > 0.0 {
        out.own_surface /= facing;
    }
    // Per mesh unit: a grid unit spans 2 half_extent / resolution along each axis.
    let normal = (gradient * r / (2.0 * field.half_extent)).normalize_or_zero();
    out.along = if normal == Vec3::ZERO {
        1.0
    } else {
        smoothstep_between(SIDEWAYS, ALONG, normal.dot(n).abs())
    };
    out
}

fn smoothstep_between(low: f32, high: f32, x: f32) -> f32 {
    smoothstep(high - low, x - low)
}

fn smoothstep(edge: f32, x: f32) -> f32 {
    let t = (x / edge).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The two parts of the share of ambient light one occluder's field blocks at world position
/// `p` with unit normal `n`: the part within `near` metres where `held(point, tolerance)` says
/// the ND-buffer does not hold its occluders, and the share of the rest (see
/// [`share_beyond`]) with, on the object's own surface, the share it blocks of its own
/// hemisphere beyond `near`; `near` ≤ 0: everything in the second, and nothing of the own
/// surface. (0, 0) outside its grid box.
pub fn occluder_occlusion(
    field: &AoFieldData,
    world_from_mesh: Affine3A,
    p: Vec3,
    n: Vec3,
    shading: FieldShading,
    near: f32,
    held: &dyn Fn(Vec3, f32) -> f32,
) -> [f32; 2] {
    let mesh = world_from_mesh.inverse().transform_point3(p);
    let uvw = (mesh - (field.center - field.half_extent)) / (2.0 * field.half_extent);
    if uvw.min_element() < 0.0 || uvw.max_element() > 1.0 {
        return [0.0, 0.0];
    }
    let mesh_normal = (world_from_mesh.matrix3.transpose() * n).normalize_or_zero();
    let s = sample_field(field, uvw, mesh_normal);
    // Only the object's own surface fades; another surface touching it keeps the full value.
    let fade = 1.0 - s.along * (1.0 - smoothstep(field.own_surface_fade(), s.signed_distance));
    // The axis corrections, weighted by the squared components of the mesh-space normal.
    let correction = |axes: &[f32]| {
        (0..3)
            .map(|k| {
                let c = mesh_normal[k];
                c * c
                    * if c >= 0.0 {
                        axes[2 * k]
                    } else {
                        axes[2 * k + 1]
                    }
            })
            .sum::<f32>()
    };
    let cone = |c: Vec4, axes: &[f32]| match shading {
        FieldShading::OcclusionOnly => (2.0 * c.x).min(1.0),
        FieldShading::Cone => {
            let axis = world_from_mesh.matrix3 * Vec3::new(c.y, c.z, c.w);
            let length2 = axis.length_squared();
            let cos_beta = if length2 > 1e-12 {
                axis.dot(n) / length2.sqrt()
            } else {
                0.0
            };
            (cap_occlusion(1.0 - 2.0 * c.x.clamp(0.0, 1.0), cos_beta) + correction(axes))
                .clamp(0.0, 1.0)
        }
    };
    let all = cone(s.far, &s.axes[..6]) * fade;
    if near <= 0.0 {
        return [0.0, all];
    }
    let inner = cone(s.near, &s.axes[6..]) * fade;
    let at = p + world_from_mesh.matrix3 * s.near_offset;
    [
        inner * (1.0 - held(at, 0.1 * near)),
        (share_beyond(all, inner) + s.own_surface * (1.0 - fade)).min(1.0),
    ]
}

/// Combined occlusion of `occluders` at every pixel of the front layer of `nd`, as compose
/// joins it with the near field off: per part 1 − Π(1 − o_i), but for the fields that join by
/// their union there ([`field_joins`]), then the two parts as independent occluders. `near` and
/// `use_back` as the view's count-once settings (0: none).
pub fn field_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    occluders: &[(&AoFieldData, Affine3A)],
    shading: FieldShading,
    near: f32,
    use_back: bool,
) -> Vec<f32> {
    let held = |x: Vec3, tolerance: f32| nd.holds(view, use_back, x, tolerance);
    let bounds: Vec<_> = occluders
        .iter()
        .map(|(field, transform)| object_bounds(field, *transform))
        .collect();
    let joins = field_joins(&bounds);
    nd.per_receiver(view, |receiver| {
        let (p, n) = (receiver.world_position, receiver.texel.normal);
        let (mut open, mut union_open, mut largest) = ([1.0f32; 2], 1.0f32, 0.0f32);
        for ((field, transform), join) in occluders.iter().zip(&joins) {
            let parts = occluder_occlusion(field, *transform, p, n, shading, near, &held);
            open[0] *= 1.0 - parts[0];
            open[1] *= 1.0 - parts[1];
            if join.joins_at(p) {
                let both = 1.0 - (1.0 - parts[0]) * (1.0 - parts[1]);
                union_open *= 1.0 - both;
                largest = largest.max(both);
            }
        }
        let [a, b] = occluder_union([1.0 - open[0], 1.0 - open[1]], union_open, largest);
        1.0 - (1.0 - a) * (1.0 - b)
    })
}

//! AO field occlusion (Malmer et al. 2005, §3.2–3.3) on the CPU, exactly as `fields/fields.wgsl`
//! evaluates it: trilinear interpolation between cell centres, 2a or T_clip(a, cos β) per
//! occluder, visibilities multiplied.

use bevy::math::{Affine3A, Vec3};

use super::nd_buffer::{NdBuffer, ViewMatrices};
use crate::fields::AoFieldData;
use crate::fields::t_clip::t_clip;
use crate::settings::FieldShading;

/// Occlusion a and average occluded direction (mesh space) of `field` at grid coordinates
/// `uvw` ∈ [0, 1]³.
pub fn sample_field(field: &AoFieldData, uvw: Vec3) -> (f32, Vec3) {
    let r = field.resolution.as_vec3();
    let g = (uvw * r - 0.5).clamp(Vec3::ZERO, r - 1.0);
    let i0 = g.floor().as_uvec3();
    let i1 = (i0 + 1).min(field.resolution - 1);
    let f = g - i0.as_vec3();
    let cell = |x: u32, y: u32, z: u32| field.cells[field.index(x, y, z)];
    let mix = |a: [f32; 4], b: [f32; 4], t: f32| -> [f32; 4] {
        [0, 1, 2, 3].map(|k| a[k] + (b[k] - a[k]) * t)
    };
    let c00 = mix(cell(i0.x, i0.y, i0.z), cell(i1.x, i0.y, i0.z), f.x);
    let c10 = mix(cell(i0.x, i1.y, i0.z), cell(i1.x, i1.y, i0.z), f.x);
    let c01 = mix(cell(i0.x, i0.y, i1.z), cell(i1.x, i0.y, i1.z), f.x);
    let c11 = mix(cell(i0.x, i1.y, i1.z), cell(i1.x, i1.y, i1.z), f.x);
    let c = mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
    (c[0], Vec3::new(c[1], c[2], c[3]))
}

/// The share of ambient light one occluder's field blocks at world position `p` with unit
/// normal `n`; 0 outside its grid box.
pub fn occluder_occlusion(
    field: &AoFieldData,
    world_from_mesh: Affine3A,
    p: Vec3,
    n: Vec3,
    shading: FieldShading,
    t_clip_table: &[f32],
) -> f32 {
    let mesh = world_from_mesh.inverse().transform_point3(p);
    let uvw = (mesh - (field.center - field.half_extent)) / (2.0 * field.half_extent);
    if uvw.min_element() < 0.0 || uvw.max_element() > 1.0 {
        return 0.0;
    }
    let (a, d) = sample_field(field, uvw);
    match shading {
        FieldShading::OcclusionOnly => (2.0 * a).min(1.0),
        FieldShading::Cone => {
            let axis = world_from_mesh.matrix3 * d;
            let length2 = axis.length_squared();
            let cos_beta = if length2 > 1e-12 {
                axis.dot(n) / length2.sqrt()
            } else {
                0.0
            };
            t_clip(t_clip_table, a, cos_beta)
        }
    }
}

/// Combined occlusion 1 − Π(1 − o_i) of `occluders` at every pixel of the front layer of `nd`.
pub fn field_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    occluders: &[(&AoFieldData, Affine3A)],
    shading: FieldShading,
    t_clip_table: &[f32],
) -> Vec<f32> {
    let mut out = vec![0.0; (nd.width * nd.height) as usize];
    for y in 0..nd.height as i32 {
        for x in 0..nd.width as i32 {
            let Some(texel) = nd.texel(false, x, y) else {
                continue;
            };
            if texel.depth <= 0.0 || texel.normal == Vec3::ZERO {
                continue;
            }
            let p = view.world_position(x, y, nd.width, nd.height, texel.depth);
            let visibility: f32 = occluders
                .iter()
                .map(|(field, transform)| {
                    1.0 - occluder_occlusion(
                        field,
                        *transform,
                        p,
                        texel.normal,
                        shading,
                        t_clip_table,
                    )
                })
                .product();
            out[(y as u32 * nd.width + x as u32) as usize] = 1.0 - visibility;
        }
    }
    out
}

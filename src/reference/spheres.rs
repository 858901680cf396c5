//! Far-field occlusion of sphere occluders (Shanmugam & Arikan 2007, eq. 2–3 and 5) on the CPU,
//! exactly as `spheres/splat.wgsl` evaluates it.

use super::nd_buffer::{NdBuffer, ViewMatrices};
use super::near_field::sphere_occlusion;
use crate::spheres::{OccluderSpheres, far_field_reach};

/// Summed far-field occlusion (not clamped) of every pixel of the front layer of `nd`,
/// row-major: each sphere adds A_ψ at every surface point within its reach d_far.
pub fn far_field_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    occluders: &[OccluderSpheres],
) -> Vec<f32> {
    let spheres: Vec<_> = occluders
        .iter()
        .flat_map(|o| {
            o.spheres
                .iter()
                .map(|s| (s.center, s.radius, far_field_reach(s.radius, o.epsilon)))
        })
        .collect();
    let mut out = vec![0.0; (nd.width * nd.height) as usize];
    for y in 0..nd.height as i32 {
        for x in 0..nd.width as i32 {
            let Some(texel) = nd.texel(false, x, y) else {
                continue;
            };
            if texel.depth <= 0.0 || texel.normal == bevy::math::Vec3::ZERO {
                continue;
            }
            let p = view.world_position(x, y, nd.width, nd.height, texel.depth);
            out[(y as u32 * nd.width + x as u32) as usize] = spheres
                .iter()
                .filter(|(center, _, reach)| p.distance(*center) <= *reach)
                .map(|(center, radius, _)| sphere_occlusion(*center, *radius, p, texel.normal))
                .sum();
        }
    }
    out
}

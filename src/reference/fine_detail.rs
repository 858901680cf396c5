//! The fine-detail term on the CPU, step for step as `shaders/fine_detail.wgsl` computes it for
//! the ray march and the blur, and as `filter/upsample.wgsl` adds it between the texels.

use bevy::math::{IVec2, Vec3};

use super::filter::{UPSAMPLE_NORMAL_SUPPORT, UPSAMPLE_REACH, UPSAMPLE_WINDOW, wendland};
use super::nd_buffer::{NdBuffer, ViewMatrices};
#[cfg(doc)]
use crate::filter::settings::AoBlur;

/// The fine-detail term's sides, in the order `shaders/fine_detail.wgsl` numbers them.
pub const FINE_DETAIL_SIDES: [IVec2; 4] = [IVec2::X, IVec2::NEG_X, IVec2::Y, IVec2::NEG_Y];

/// The fine-detail term ([`AoBlur::detail_reach`], `fine_detail` in `shaders/fine_detail.wgsl`)
/// as the blur's Y pass adds it: [`fine_detail_sides`] over all four sides.
pub fn fine_detail(nd: &NdBuffer, view: &ViewMatrices, reach: u32, radius: f32) -> Vec<f32> {
    fine_detail_sides(nd, view, reach, radius, &FINE_DETAIL_SIDES)
}

/// The fine-detail term over `sides` (of [`FINE_DETAIL_SIDES`]; the ray march adds one a frame
/// under accumulation): for each receiver of the front layer, the occlusion of the surfaces
/// within `reach` pixels along each side, the highest as a horizon (the sine of its elevation
/// above the tangent plane, falling to nothing at the reach's world size or at `radius`,
/// metres), the squares of the sides' sines averaged. 0 on the background.
pub fn fine_detail_sides(
    nd: &NdBuffer,
    view: &ViewMatrices,
    reach: u32,
    radius: f32,
    sides: &[IVec2],
) -> Vec<f32> {
    let reach_pixels = reach as i32;
    nd.per_receiver(view, |r| {
        let p = r.view_position;
        let footprint = view.pixel_world_size(-p.z, nd.height);
        let reach_world = detail_reach_world(reach, footprint, radius);
        let mut occlusion = 0.0;
        for &side in sides {
            let mut highest = 0.0f32;
            for k in 1..=reach_pixels {
                let q = r.pixel + side * k;
                let Some(texel) = nd.texel(false, q.x, q.y) else {
                    break;
                };
                if texel.depth <= 0.0 {
                    continue;
                }
                let v = view.view_position(q.x, q.y, nd.width, nd.height, texel.depth) - p;
                highest = highest.max(rise(v, r.view_normal, reach_world));
            }
            occlusion += highest * highest;
        }
        occlusion / sides.len() as f32
    })
}

/// The fine-detail term's reach in metres for a receiver `footprint` metres wide: `reach` pixels
/// and a half, at most `radius` (`detail_reach_world` in `shaders/fine_detail.wgsl`).
fn detail_reach_world(reach: u32, footprint: f32, radius: f32) -> f32 {
    ((reach as f32 + 0.5) * footprint).min(radius)
}

/// How far a surface point at `v` from a receiver (metres, view space) rises above the receiver's
/// tangent plane (unit view-space normal `n`), as the fine-detail term counts it: the sine of its
/// elevation, falling to nothing at `reach_world` metres; 0 at or past the reach (`rise` in
/// `shaders/fine_detail.wgsl`).
fn rise(v: Vec3, n: Vec3, reach_world: f32) -> f32 {
    let distance = v.length();
    if distance <= 0.0 || distance >= reach_world {
        return 0.0;
    }
    let t = distance / reach_world;
    v.dot(n) / distance * (1.0 - t * t)
}

/// How far below the surface of its bracketing texels a pixel must lie, in its footprints, for
/// [`sub_texel_detail`] to count at all (`SUNKEN_FROM` in `filter/upsample.wgsl`)...
const SUNKEN_FROM: f32 = 0.1;
/// ... and from how much deeper it counts in full (`SUNKEN_RAMP`).
const SUNKEN_RAMP: f32 = 0.4;

/// The fine-detail term of the pixels between a half-resolution buffer's texels (texel l computed
/// at pixel 2l), as the upsampling of accumulated ray-march occlusion adds it
/// (`sub_texel_detail` and `sunken` in `filter/upsample.wgsl`): for each pixel of a texel's 2 × 2
/// but the texel's own, the highest rise (the sine of the elevation, as in [`fine_detail`]) on
/// each side over the texels the upsampling blends for it (those within 2.5 pixels), each weighted
/// by the normal weight w_n, the squares of the four sides averaged; scaled by how far the pixel
/// lies below the surface of its bracketing texels (their positions averaged as bilinear
/// filtering weighs them), 0 within a tenth of a footprint and 1 from half a footprint. 0 at the
/// texels' own pixels (their term is the march's), where a bracketing texel is off the buffer or
/// on the background, and on the background. The shader reads the texels' depth and normal from
/// the temporal history, whose normals are 8-bit.
pub fn sub_texel_detail(nd: &NdBuffer, view: &ViewMatrices, reach: u32, radius: f32) -> Vec<f32> {
    let (lw, lh) = (nd.width.div_ceil(2) as i32, nd.height.div_ceil(2) as i32);
    // Texel l's view position and world normal; `None` off the buffer and on the background.
    let texel = |l: IVec2| {
        if l.x < 0 || l.y < 0 || l.x >= lw || l.y >= lh {
            return None;
        }
        let q = l * 2;
        let t = nd.texel(false, q.x, q.y).filter(|t| t.depth > 0.0)?;
        Some((
            view.view_position(q.x, q.y, nd.width, nd.height, t.depth),
            t.normal,
        ))
    };
    nd.per_receiver(view, |r| {
        let own = r.pixel / 2;
        let quad = r.pixel - own * 2;
        if quad == IVec2::ZERO {
            return 0.0;
        }
        let footprint = view.pixel_world_size(-r.view_position.z, nd.height);
        let corners: &[(i32, i32)] = match (quad.x, quad.y) {
            (1, 0) => &[(0, 0), (1, 0)],
            (0, 1) => &[(0, 0), (0, 1)],
            _ => &[(0, 0), (1, 0), (0, 1), (1, 1)],
        };
        let bracket: Option<Vec<Vec3>> = corners
            .iter()
            .map(|(i, j)| texel(own + IVec2::new(*i, *j)).map(|(p, _)| p))
            .collect();
        let Some(bracket) = bracket else {
            return 0.0;
        };
        let spanned = bracket.iter().sum::<Vec3>() / bracket.len() as f32;
        let depth = (spanned - r.view_position).dot(r.view_normal) / footprint;
        let sunken = ((depth - SUNKEN_FROM) / SUNKEN_RAMP).clamp(0.0, 1.0);
        let reach_world = detail_reach_world(reach, footprint, radius);
        let mut highest = [0.0f32; 4];
        for (i, j) in UPSAMPLE_WINDOW {
            let l = own + IVec2::new(i, j);
            if ((l * 2 - r.pixel).length_squared() as f32).sqrt() >= UPSAMPLE_REACH {
                continue;
            }
            let Some((p, normal)) = texel(l) else {
                continue;
            };
            let agreement = 1.0 - r.texel.normal.dot(normal);
            let rise = rise(p - r.view_position, r.view_normal, reach_world)
                * wendland(agreement, UPSAMPLE_NORMAL_SUPPORT);
            for (side, h) in FINE_DETAIL_SIDES.iter().zip(&mut highest) {
                if (l * 2 - r.pixel).dot(*side) > 0 {
                    *h = h.max(rise);
                }
            }
        }
        sunken * highest.iter().map(|h| h * h).sum::<f32>() / FINE_DETAIL_SIDES.len() as f32
    })
}

/// `occlusion` (row-major, the size of `nd`) with the fine-detail term of `reach` pixels
/// multiplied in, as the blur's Y pass does for the ray march: 1 − (1 − occlusion)(1 − min(
/// intensity · detail, 1)).
pub fn with_fine_detail(
    occlusion: &[f32],
    nd: &NdBuffer,
    view: &ViewMatrices,
    reach: u32,
    radius: f32,
    intensity: f32,
) -> Vec<f32> {
    occlusion
        .iter()
        .zip(fine_detail(nd, view, reach, radius))
        .map(|(o, d)| join_fine_detail(*o, d, intensity))
        .collect()
}

/// `occlusion` with the fine-detail term `detail` (scaled by `intensity`) joined as an
/// independent occluder, 1 − (1 − occlusion)(1 − min(intensity · detail, 1)): `with_fine_detail`
/// in `shaders/fine_detail.wgsl`.
pub fn join_fine_detail(occlusion: f32, detail: f32, intensity: f32) -> f32 {
    1.0 - (1.0 - occlusion) * (1.0 - (intensity * detail).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::filter::tests::{step_edge, two_planes};

    #[test]
    fn fine_detail_sees_only_what_rises_above_the_tangent_plane() {
        // A step 3 cm deep instead of 3 m, so the near half lies within the term's reach.
        let (_, mut nd, view) = step_edge();
        let (w, h) = (nd.width, nd.height);
        for i in 0..(w * h) as usize {
            let x = i as u32 % w;
            nd.front[i].depth = 0.1 / if x < w / 2 { 1.0 } else { 1.03 };
        }
        let detail = fine_detail(&nd, &view, 6, 10.0);
        let at = |x: u32| detail[(h / 2 * w + x) as usize];
        // Flat, facing the camera: every neighbour lies in the tangent plane.
        assert_eq!(at(2), 0.0);
        assert_eq!(at(w - 3), 0.0);
        // The near side of the step sees the far side below its tangent plane.
        assert_eq!(at(w / 2 - 1), 0.0);
        // Beside the step, on the far side, the near side rises above it: one side of four.
        let first = at(w / 2);
        assert!(first > 0.005 && first < 0.25, "{first}");
        // Further off, the step is lower in the sky and then out of reach.
        assert!(at(w / 2 + 2) < first);
        assert_eq!(at(w / 2 + 7), 0.0);
        // Within R only: a reach cut to 1 cm leaves nothing.
        assert!(fine_detail(&nd, &view, 6, 0.01).iter().all(|d| *d == 0.0));
        let darker = with_fine_detail(&vec![0.5; detail.len()], &nd, &view, 6, 10.0, 1.0);
        let i = (h / 2 * w + w / 2) as usize;
        assert!((darker[i] - (1.0 - 0.5 * (1.0 - first))).abs() < 1e-6);
    }

    #[test]
    fn pixels_between_texels_see_a_groove_the_texels_straddle() {
        // A plane 1 m away facing the camera (pixels 6.8 cm wide there), with a groove a pixel
        // wide down column 9, which no texel (computed at even columns) shows: 5 cm deep, then
        // 0.5 cm.
        let (w, h) = (32u32, 16u32);
        let groove = |depth: f32| two_planes((w, h), |x| x != 9, 1.0, 1.0 + depth);
        let at = |d: &[f32], x: u32, y: u32| d[(y * w + x) as usize];
        let (mut nd, view) = groove(0.05);
        let detail = sub_texel_detail(&nd, &view, 6, 10.0);
        // In the groove, the texels on both sides rise above it.
        let deep = at(&detail, 9, 6);
        assert!(deep > 0.05 && deep < 0.5, "{deep}");
        assert!(at(&detail, 9, 7) > 0.05, "{}", at(&detail, 9, 7));
        // On the plane, beside the groove or away from it, nothing rises.
        for x in [7, 8, 10, 11, 20] {
            assert_eq!(at(&detail, x, 7), 0.0, "column {x}");
        }
        // A texel's own pixel keeps the march's term: none added.
        assert_eq!(at(&detail, 10, 6), 0.0);
        // Within R only.
        assert!(
            sub_texel_detail(&nd, &view, 6, 0.001)
                .iter()
                .all(|d| *d == 0.0)
        );
        // A groove a fourteenth of a footprint deep is no deeper than a smooth surface's curve
        // lies between its texels: no term.
        let (shallow, _) = groove(0.005);
        let shallow = at(&sub_texel_detail(&shallow, &view, 6, 10.0), 9, 6);
        assert_eq!(shallow, 0.0);
        // The same rise from texels facing another way (a wall beside a floor, whose occlusion
        // the floor's texels hold already) counts for a twentieth at most.
        for (i, t) in nd.front.iter_mut().enumerate() {
            if i as u32 % w != 9 {
                t.normal = Vec3::X;
            }
        }
        let turned = at(&sub_texel_detail(&nd, &view, 6, 10.0), 9, 6);
        assert!(turned < deep * 0.05 * 0.05, "{turned} against {deep}");
    }
}

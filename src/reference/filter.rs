//! The cross-bilateral blur on the CPU, step for step as `filter/blur.wgsl` computes it.

use bevy::math::Vec4;

use super::nd_buffer::{NdBuffer, ViewMatrices};
use crate::filter::settings::AoBlur;

/// Distance in front of the camera for a reverse-Z depth (metres).
pub fn linear_depth(view: &ViewMatrices, depth: f32) -> f32 {
    let p = view.clip_from_view.inverse() * Vec4::new(0.0, 0.0, depth, 1.0);
    -p.z / p.w
}

/// Wendland's compactly supported kernel (Reinbothe et al. 2009, eq. 3).
pub fn wendland(t: f32, h: f32) -> f32 {
    if t > h {
        return 0.0;
    }
    let s = 1.0 - t / h;
    s * s * s * s * (4.0 * t / h + 1.0)
}

/// Full-resolution pixels within which `filter/upsample.wgsl` blends a texel: w_d of the texels
/// of the window farther away is under 0.03, and the shader skips them.
pub(super) const UPSAMPLE_REACH: f32 = 2.5;

/// Support of the upsampling's normal weight over 1 − cos of the angle between the normals
/// (`NORMAL_SUPPORT` in `shaders/joint_upsample.wgsl`, which says why).
pub(super) const UPSAMPLE_NORMAL_SUPPORT: f32 = 1.5;

/// Support of the upsampling's plane weight over a texel's distance from the pixel's tangent
/// plane, in the pixel's footprints (`PLANE_SUPPORT` in `shaders/joint_upsample.wgsl`, which
/// says why).
const UPSAMPLE_PLANE_SUPPORT: f32 = 2.0;

/// The texels `filter/upsample.wgsl` blends for a pixel (those within [`UPSAMPLE_REACH`]), as
/// offsets from the pixel's own texel.
pub(super) const UPSAMPLE_WINDOW: [(i32, i32); 9] = [
    (0, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// Joint bilateral upsampling of `low` (row-major, `(width + 1) / 2` × `(height + 1) / 2`, texel
/// (i, j) computed at full-resolution pixel (2i, 2j)) to the size of `nd`, as
/// `filter/upsample.wgsl` does it.
pub fn joint_bilateral_upsample(low: &[f32], nd: &NdBuffer, view: &ViewMatrices) -> Vec<f32> {
    let pairs: Vec<[f32; 2]> = low.iter().map(|v| [*v, 0.0]).collect();
    joint_bilateral_upsample_pair(&pairs, nd, view)
        .into_iter()
        .map(|v| v[0])
        .collect()
}

/// [`joint_bilateral_upsample`] of two-channel occlusion (`TWO_CHANNELS` in
/// `filter/upsample.wgsl`), both channels with the same weights.
pub fn joint_bilateral_upsample_pair(
    low: &[[f32; 2]],
    nd: &NdBuffer,
    view: &ViewMatrices,
) -> Vec<[f32; 2]> {
    let (w, h) = (nd.width as i32, nd.height as i32);
    let (lw, lh) = ((w + 1) / 2, (h + 1) / 2);
    let mut out = vec![[0.0; 2]; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let t = nd.front[(y * w + x) as usize];
            if t.depth <= 0.0 {
                continue;
            }
            let p = view.world_position(x, y, nd.width, nd.height, t.depth);
            let footprint = view.pixel_world_size(linear_depth(view, t.depth), nd.height);
            let nearest = ((x / 2).min(lw - 1), (y / 2).min(lh - 1));
            let v_x = low[(nearest.1 * lw + nearest.0) as usize];
            // The 3 × 3 texels around the pixel's own (texel l was computed at pixel 2l), its
            // own first, in the order the shader adds them.
            let (mut sum, mut weights) = ([0.0f32; 2], 0.0f32);
            for (i, j) in UPSAMPLE_WINDOW {
                let (lx, ly) = (nearest.0 + i, nearest.1 + j);
                let (qx, qy) = (lx * 2, ly * 2);
                if lx < 0 || ly < 0 || lx >= lw || ly >= lh || qx >= w || qy >= h {
                    continue;
                }
                let screen = (((x - qx) * (x - qx) + (y - qy) * (y - qy)) as f32).sqrt();
                if screen >= UPSAMPLE_REACH {
                    continue;
                }
                let q = nd.front[(qy * w + qx) as usize];
                if q.depth <= 0.0 {
                    continue;
                }
                let v_y = low[(ly * lw + lx) as usize];
                let q_p = view.world_position(qx, qy, nd.width, nd.height, q.depth);
                let weight = wendland(screen, 4.0)
                    * wendland(1.0 - t.normal.dot(q.normal), UPSAMPLE_NORMAL_SUPPORT)
                    * wendland(
                        t.normal.dot(q_p - p).abs(),
                        UPSAMPLE_PLANE_SUPPORT * footprint,
                    );
                sum[0] += weight * v_y[0];
                sum[1] += weight * v_y[1];
                weights += weight;
            }
            out[(y * w + x) as usize] = if weights > 0.0 {
                [sum[0] / weights, sum[1] / weights]
            } else {
                v_x
            };
        }
    }
    out
}

/// Blurs `occlusion` (row-major, the size of `nd`) along X then Y with the front layer's depth
/// and normals as the edge guide: the separable cross-bilateral filter of Bavoil & Sainz 2008,
/// with `blur`'s normal weight (`normal_sharpness` 0: depth alone, as the voxel term's blur).
pub fn cross_bilateral_blur(
    occlusion: &[f32],
    nd: &NdBuffer,
    view: &ViewMatrices,
    blur: &AoBlur,
) -> Vec<f32> {
    if blur.radius == 0 {
        return occlusion.to_vec();
    }
    let along_x = blur_pass(occlusion, nd, view, blur, (1, 0));
    blur_pass(&along_x, nd, view, blur, (0, 1))
}

fn blur_pass(
    input: &[f32],
    nd: &NdBuffer,
    view: &ViewMatrices,
    blur: &AoBlur,
    step: (i32, i32),
) -> Vec<f32> {
    let (radius, sharpness) = (blur.radius, blur.sharpness);
    let (w, h) = (nd.width as i32, nd.height as i32);
    let depths: Vec<f32> = nd.front.iter().map(|t| t.depth).collect();
    let linear: Vec<f32> = depths
        .iter()
        .map(|&d| if d > 0.0 { linear_depth(view, d) } else { 0.0 })
        .collect();
    let sigma = (radius as f32 + 1.0) * 0.5;
    let falloff = 1.0 / (2.0 * sigma * sigma);
    let radius = radius as i32;
    let mut out = vec![0.0; input.len()];
    for y in 0..h {
        for x in 0..w {
            let center = (y * w + x) as usize;
            if depths[center] <= 0.0 {
                continue;
            }
            let z0 = linear[center];
            let n0 = nd.front[center].normal;
            let (mut sum, mut weights) = (0.0f32, 0.0f32);
            for i in -radius..=radius {
                let (qx, qy) = (x + step.0 * i, y + step.1 * i);
                if qx < 0 || qy < 0 || qx >= w || qy >= h {
                    continue;
                }
                let q = (qy * w + qx) as usize;
                if depths[q] <= 0.0 {
                    continue;
                }
                let dz = (linear[q] - z0) / z0 * sharpness;
                let bend = (1.0 - n0.dot(nd.front[q].normal)) * blur.normal_sharpness;
                let weight = (-((i * i) as f32) * falloff - dz * dz - bend * bend).exp();
                sum += weight * input[q];
                weights += weight;
            }
            out[center] = sum / weights;
        }
    }
    out
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::reference::nd_buffer::NdTexel;
    use bevy::math::{Mat4, Vec3};

    /// A `w` × `h` view of two planes facing the camera, without back faces: pixel columns where
    /// `near` holds show the one `near_z` metres away, the others the one `far_z` metres away.
    pub(in crate::reference) fn two_planes(
        (w, h): (u32, u32),
        near: impl Fn(u32) -> bool,
        near_z: f32,
        far_z: f32,
    ) -> (NdBuffer, ViewMatrices) {
        let view = ViewMatrices::new(
            Mat4::IDENTITY,
            Mat4::perspective_infinite_reverse_rh(1.0, w as f32 / h as f32, 0.1),
        );
        // Reverse-Z depth of a surface z metres away, under this projection's 0.1 m near plane.
        let front = (0..w * h)
            .map(|i| NdTexel {
                normal: Vec3::Z,
                depth: 0.1 / if near(i % w) { near_z } else { far_z },
            })
            .collect();
        let nd = NdBuffer {
            width: w,
            height: h,
            back: vec![NdTexel::default(); (w * h) as usize],
            front,
        };
        (nd, view)
    }

    /// A vertical depth edge: the left half is a near surface in a dark crease, the right half a
    /// far, open surface.
    pub(in crate::reference) fn step_edge() -> (Vec<f32>, NdBuffer, ViewMatrices) {
        let (w, h) = (32u32, 8u32);
        let near = |x: u32| x < w / 2;
        let (nd, view) = two_planes((w, h), near, 1.0, 4.0);
        let occlusion = (0..w * h)
            .map(|i| if near(i % w) { 0.8 } else { 0.0 })
            .collect();
        (occlusion, nd, view)
    }

    #[test]
    fn linear_depth_inverts_the_projection() {
        let (_, nd, view) = step_edge();
        assert!((linear_depth(&view, nd.front[0].depth) - 1.0).abs() < 1e-4);
        assert!((linear_depth(&view, nd.front[31].depth) - 4.0).abs() < 1e-3);
    }

    #[test]
    fn bilateral_blur_keeps_each_side_of_a_depth_edge() {
        let (occlusion, nd, view) = step_edge();
        let blur = |sharpness| AoBlur {
            radius: 8,
            accumulated_radius: 0,
            voxel_accumulated_radius: 0,
            sharpness,
            normal_sharpness: 0.0,
            detail_reach: 0,
        };
        let sharp = cross_bilateral_blur(&occlusion, &nd, &view, &blur(16.0));
        let plain = cross_bilateral_blur(&occlusion, &nd, &view, &blur(0.0));
        // First far pixel and last near pixel of a row.
        let (far, near) = (16usize, 15usize);
        assert!(sharp[far] < 0.01, "bled onto the far side: {}", sharp[far]);
        assert!(
            (sharp[near] - 0.8).abs() < 0.01,
            "bled onto the near side: {}",
            sharp[near]
        );
        // The same kernel without the depth term does bleed, so the test can see bleeding.
        assert!(
            plain[far] > 0.2 && plain[near] < 0.6,
            "{} {}",
            plain[far],
            plain[near]
        );
        // Away from the edge, a constant stays constant.
        assert!((sharp[0] - 0.8).abs() < 1e-6 && sharp[31].abs() < 1e-6);
    }

    /// A crease: one depth across the image, the normal turning 90° at its middle, dark on the
    /// left. The normal weight keeps each side; depth alone cannot see the crease.
    #[test]
    fn bilateral_blur_keeps_each_side_of_a_crease() {
        let (_, mut nd, view) = step_edge();
        let w = nd.width as usize;
        let depth = nd.front[0].depth;
        for (i, texel) in nd.front.iter_mut().enumerate() {
            texel.depth = depth;
            texel.normal = if i % w < w / 2 { Vec3::Z } else { Vec3::X };
        }
        let occlusion: Vec<f32> = (0..nd.front.len())
            .map(|i| if i % w < w / 2 { 0.8 } else { 0.0 })
            .collect();
        let blur = |normal_sharpness| AoBlur {
            radius: 8,
            normal_sharpness,
            ..AoBlur::default()
        };
        let kept = cross_bilateral_blur(&occlusion, &nd, &view, &blur(16.0));
        let bled = cross_bilateral_blur(&occlusion, &nd, &view, &blur(0.0));
        let (dark, open) = (w / 2 - 1, w / 2);
        assert!(
            (kept[dark] - 0.8).abs() < 1e-3 && kept[open] < 1e-3,
            "the normal weight let occlusion cross the crease: {} {}",
            kept[dark],
            kept[open]
        );
        assert!(
            bled[open] > 0.2,
            "without it the crease is crossed: {}",
            bled[open]
        );
    }

    #[test]
    fn wendland_kernel_shape() {
        assert_eq!(wendland(0.0, 2.0), 1.0);
        assert_eq!(wendland(2.0, 2.0), 0.0);
        assert_eq!(wendland(3.0, 2.0), 0.0);
        assert!(wendland(0.5, 2.0) > wendland(1.0, 2.0));
    }

    /// Two surfaces facing the camera 5 cm apart at 1 m, far inside any AO radius but several
    /// pixel footprints apart in depth (a fin's top over the floor between the fins): each pixel
    /// takes only the texels of its own surface, whichever lie in its window.
    #[test]
    fn upsampling_keeps_a_small_step_apart() {
        let (w, h) = (32u32, 120u32);
        let near = |x: u32| x < 15;
        let (nd, view) = two_planes((w, h), near, 1.0, 1.05);
        let (lw, lh) = (w.div_ceil(2), h.div_ceil(2));
        let low: Vec<f32> = (0..lw * lh)
            .map(|i| if near(2 * (i % lw)) { 0.8 } else { 0.0 })
            .collect();
        let up = joint_bilateral_upsample(&low, &nd, &view);
        for (i, v) in up.iter().enumerate() {
            let own = if near(i as u32 % w) { 0.8 } else { 0.0 };
            assert!(
                (v - own).abs() < 1e-5,
                "pixel {} took {v} across the step",
                i as u32 % w
            );
        }
    }

    #[test]
    fn upsampling_a_constant_keeps_it() {
        let (_, nd, view) = step_edge();
        let low = vec![0.3; 16 * 4];
        let up = joint_bilateral_upsample(&low, &nd, &view);
        assert!(up.iter().all(|v| (v - 0.3).abs() < 1e-6));
    }

    #[test]
    fn radius_zero_is_identity() {
        let (occlusion, nd, view) = step_edge();
        assert_eq!(
            cross_bilateral_blur(&occlusion, &nd, &view, &AoBlur::OFF),
            occlusion
        );
    }
}

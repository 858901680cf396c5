//! Horizon-based occlusion (Bavoil & Sainz 2008, all three modes) on the CPU, step for
//! step as `horizon/horizon.wgsl` computes it.

use bevy::math::{IVec2, Vec2, Vec3};

use super::nd_buffer::{NdBuffer, ViewMatrices};
use super::sampling::{HASH_TO_UNIT, pcg_hash};

/// Parameters of one evaluation, as the GPU uniform carries them.
#[derive(Clone, Copy, Debug)]
pub struct HorizonInputs {
    /// R, metres.
    pub radius: f32,
    /// Multiplier on the occlusion.
    pub intensity: f32,
    /// Directions per pixel.
    pub directions: u32,
    /// Most steps per direction.
    pub steps: u32,
    /// Angle bias, radians.
    pub angle_bias: f32,
    /// W0.
    pub attenuation: f32,
    /// Contrast.
    pub contrast: f32,
    /// 0 low, 1 normal, 2 high (`HorizonMode::shader_index`).
    pub mode: u32,
}

/// The tangent-plane vector one pixel along image direction `dir` covers (see the shader).
fn tangent_along(
    view: &ViewMatrices,
    pixel: IVec2,
    size: Vec2,
    dir: Vec2,
    p: Vec3,
    n: Vec3,
) -> Vec3 {
    let uv = (pixel.as_vec2() + 0.5 + dir) / size;
    let a = view.view_position_at(uv.x, uv.y, 1.0);
    let b = view.view_position_at(uv.x, uv.y, 0.5);
    let denominator = n.dot(b - a);
    if denominator.abs() < 1e-12 {
        let along = Vec3::new(dir.x, -dir.y, 0.0);
        return along - n * n.dot(along);
    }
    a + (b - a) * (n.dot(p - a) / denominator) - p
}

/// Occlusion (0 = open) of every pixel of the front layer of `nd`, row-major.
pub fn horizon_occlusion(nd: &NdBuffer, view: &ViewMatrices, inputs: &HorizonInputs) -> Vec<f32> {
    nd.per_pixel(|x, y| pixel_occlusion(nd, view, inputs, x, y))
}

/// Occlusion of one pixel.
pub fn pixel_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    inputs: &HorizonInputs,
    x: i32,
    y: i32,
) -> f32 {
    let (w, h) = (nd.width, nd.height);
    let Some(receiver) = nd.receiver(view, x, y) else {
        return 0.0;
    };
    let (pixel, p, n) = (receiver.pixel, receiver.view_position, receiver.view_normal);
    let radius_px = inputs.radius / view.pixel_world_size(-p.z, h);
    let steps = (radius_px as u32).clamp(1, inputs.steps);
    let step_px = radius_px / steps as f32;
    let hash = pcg_hash(x as u32 ^ pcg_hash(y as u32 ^ 0x68bc_21eb));
    let rotation = hash as f32 * HASH_TO_UNIT;
    let pixel_jitter = pcg_hash(hash) as f32 * HASH_TO_UNIT;

    let mut sum = 0.0;
    for i in 0..inputs.directions {
        let angle = (i as f32 + rotation) * std::f32::consts::TAU / inputs.directions as f32;
        let dir = Vec2::new(angle.cos(), angle.sin());
        let size = Vec2::new(w as f32, h as f32);
        let tangent = tangent_along(view, pixel, size, dir, p, n);
        let sin_tangent = (tangent.z / tangent.length().max(1e-6)).clamp(-1.0, 1.0);
        let mut sin_horizon = (sin_tangent.asin() + inputs.angle_bias)
            .min(std::f32::consts::FRAC_PI_2)
            .sin();
        let mut jitter = pixel_jitter;
        if inputs.mode == 0 {
            sin_horizon = -1.0;
        } else if inputs.mode == 2 {
            jitter = pcg_hash(hash ^ (i + 1).wrapping_mul(0x9e37_79b9)) as f32 * HASH_TO_UNIT;
            let q = pixel + (dir + 0.5).floor().as_ivec2();
            if q != pixel
                && let Some(t) = nd.texel(false, q.x, q.y)
                && t.depth > 0.0
            {
                let v = view.view_position(q.x, q.y, w, h, t.depth) - p;
                let r = v.length();
                if r > 0.0 && r < inputs.radius {
                    sin_horizon = sin_horizon.max(v.z / r);
                }
            }
        }
        let mut ao = 0.0;
        for k in 0..steps {
            let offset = dir * ((k as f32 + jitter) * step_px + 1.0);
            let q = pixel + (offset + 0.5).floor().as_ivec2();
            if q == pixel || q.x < 0 || q.y < 0 || q.x >= w as i32 || q.y >= h as i32 {
                continue;
            }
            let Some(t) = nd.texel(false, q.x, q.y) else {
                continue;
            };
            if t.depth <= 0.0 {
                continue;
            }
            let v = view.view_position(q.x, q.y, w, h, t.depth) - p;
            let r = v.length();
            if r >= inputs.radius || r <= 0.0 {
                continue;
            }
            let sin_elevation = v.z / r;
            if sin_elevation > sin_horizon {
                let x = r / inputs.radius;
                ao += inputs.attenuation * (1.0 - x * x) * (sin_elevation - sin_horizon);
                sin_horizon = sin_elevation;
            }
        }
        if inputs.mode == 0 {
            ao -= inputs.attenuation;
        }
        sum += ao;
    }
    (inputs.contrast * inputs.intensity * sum / inputs.directions as f32).clamp(0.0, 1.0)
}

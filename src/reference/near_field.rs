//! Near-field occlusion (Shanmugam & Arikan 2007, eq. 2–4) on the CPU, step for step as
//! `near_field/near_field.wgsl` computes it.

use bevy::math::{IVec2, Vec3};

use super::nd_buffer::{NdBuffer, ViewMatrices};
use super::sampling::{disk_sample, pixel_rotation};

/// A_ψ of Shanmugam & Arikan eq. 2–3 divided by π (fraction of cosine-weighted ambient light
/// that a sphere <center, radius> blocks at `receiver` with unit `normal`); 1 inside the sphere.
pub fn sphere_occlusion(center: Vec3, radius: f32, receiver: Vec3, normal: Vec3) -> f32 {
    let to_center = center - receiver;
    let distance = to_center.length();
    if distance <= radius {
        return 1.0;
    }
    let sin_theta = radius / distance;
    let cap = 2.0 * (1.0 - (1.0 - sin_theta * sin_theta).sqrt());
    (cap * normal.dot(to_center / distance).max(0.0)).min(1.0)
}

/// Parameters of one evaluation, as the GPU uniform carries them.
#[derive(Clone, Copy, Debug)]
pub struct NearFieldInputs {
    /// r_far, metres.
    pub radius: f32,
    /// Multiplier on the occlusion.
    pub intensity: f32,
    /// Most samples per pixel and layer.
    pub max_samples: u32,
    /// Fewest samples per pixel and layer.
    pub min_samples: u32,
    /// Whether the back-face layer takes part.
    pub back_layer: bool,
}

/// Occlusion (0 = open) of every pixel of `nd`, row-major.
pub fn near_field_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    inputs: &NearFieldInputs,
) -> Vec<f32> {
    nd.per_pixel(|x, y| pixel_occlusion(nd, view, inputs, x, y))
}

/// Occlusion of one pixel.
pub fn pixel_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    inputs: &NearFieldInputs,
    x: i32,
    y: i32,
) -> f32 {
    let (w, h) = (nd.width, nd.height);
    let Some(receiver) = nd.receiver(view, x, y) else {
        return 0.0;
    };
    let (p, n) = (receiver.world_position, receiver.texel.normal);
    let radius_px = inputs.radius / view.pixel_world_size(view.view_depth(p), h);
    let area = std::f32::consts::PI * radius_px * radius_px;
    let count = (area.min(4096.0).ceil() as u32).clamp(inputs.min_samples, inputs.max_samples);
    let sphere_scale = radius_px / (count as f32).sqrt();
    let rotation = pixel_rotation(x as u32, y as u32);
    let pixel = IVec2::new(x, y);

    let occluder = |q: IVec2, back: bool| -> f32 {
        let Some(t) = nd.texel(back, q.x, q.y) else {
            return 0.0;
        };
        if t.depth <= 0.0 {
            return 0.0;
        }
        let position = view.world_position(q.x, q.y, w, h, t.depth);
        let d = position.distance(p);
        if d >= inputs.radius || n.dot(position - p) <= 0.0 {
            return 0.0;
        }
        let radius =
            (view.pixel_world_size(view.view_depth(position), h) * sphere_scale).min(0.5 * d);
        sphere_occlusion(position - t.normal * radius, radius, p, n)
    };

    let mut open = 1.0;
    for i in 0..count {
        let offset = disk_sample(i, count, radius_px, rotation);
        let q = pixel + (offset + 0.5).floor().as_ivec2();
        if q == pixel || q.x < 0 || q.y < 0 || q.x >= w as i32 || q.y >= h as i32 {
            continue;
        }
        open *= 1.0 - occluder(q, false);
        if inputs.back_layer {
            open *= 1.0 - occluder(q, true);
        }
    }
    ((1.0 - open) * inputs.intensity).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_occlusion_limits() {
        let n = Vec3::Y;
        // Inside: fully closed.
        assert_eq!(sphere_occlusion(Vec3::Y * 0.5, 1.0, Vec3::ZERO, n), 1.0);
        // Below the horizon: nothing.
        assert_eq!(sphere_occlusion(-Vec3::Y * 3.0, 1.0, Vec3::ZERO, n), 0.0);
        // Small and far straight above: ≈ (r/d)², the exact cosine-weighted value.
        let a = sphere_occlusion(Vec3::Y * 10.0, 0.1, Vec3::ZERO, n);
        assert!((a - 1e-4).abs() < 1e-6, "{a}");
        // Falls off with distance and with the angle to the normal.
        let near = sphere_occlusion(Vec3::Y * 2.0, 0.5, Vec3::ZERO, n);
        let far = sphere_occlusion(Vec3::Y * 4.0, 0.5, Vec3::ZERO, n);
        let slanted = sphere_occlusion(
            Vec3::new(2.0, 2.0, 0.0).normalize() * 2.0,
            0.5,
            Vec3::ZERO,
            n,
        );
        assert!(near > far && near > slanted && slanted > 0.0);
    }
}

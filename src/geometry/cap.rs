//! The share of a receiver's ambient light a cone of directions blocks, exactly as
//! `shaders/cap_occlusion.wgsl` evaluates it: the cosine-weighted measure of a spherical cap of
//! angular radius σ, axis at angle θ from the normal, clipped by the tangent plane, over π.

use std::f32::consts::PI;

/// σ ≤ π/2, given by its cosine.
fn narrow_cap_occlusion(cos_sigma: f32, cos_theta: f32) -> f32 {
    let sin2_sigma = (1.0 - cos_sigma * cos_sigma).max(0.0);
    if cos_theta >= sin2_sigma.sqrt() {
        return sin2_sigma * cos_theta;
    }
    if cos_theta <= -sin2_sigma.sqrt() || sin2_sigma <= 0.0 {
        return 0.0;
    }
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let x = cos_sigma.max(0.0) / sin2_sigma.sqrt();
    let y = (-x * cos_theta / sin_theta.max(1e-7)).clamp(-1.0, 1.0);
    let s = sin_theta * (1.0 - y * y).max(0.0).sqrt();
    let integral = (cos_theta * y.acos() - x * s) * sin2_sigma + s.atan2(x);
    (integral / PI).clamp(0.0, 1.0)
}

/// The blocked share of ambient light for a cap of angular radius σ ∈ [0, π] (given by its
/// cosine) whose axis makes the angle θ (given by its cosine) with the receiver's normal.
pub fn cap_occlusion(cos_sigma: f32, cos_theta: f32) -> f32 {
    if cos_sigma >= 0.0 {
        narrow_cap_occlusion(cos_sigma, cos_theta)
    } else {
        1.0 - narrow_cap_occlusion(-cos_sigma, -cos_theta)
    }
}

/// Of two occlusions of one occluder, `inner` the part within the near field's reach and `all`
/// the whole: the share of the directions `inner` leaves open that the rest covers, exactly as
/// `share_beyond` in `shaders/cap_occlusion.wgsl`.
pub fn share_beyond(all: f32, inner: f32) -> f32 {
    ((all - inner) / (1.0 - inner).max(1e-4)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use bevy::math::Vec3;

    use super::*;

    /// The same share by stratified cosine-weighted directions around +z.
    fn numeric(cos_sigma: f32, cos_theta: f32) -> f32 {
        let n = 400;
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let axis = Vec3::new(sin_theta, 0.0, cos_theta);
        let mut inside = 0;
        for i in 0..n {
            for j in 0..n {
                let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let r = u.sqrt();
                let phi = 2.0 * PI * v;
                let w = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).sqrt());
                inside += usize::from(w.dot(axis) >= cos_sigma);
            }
        }
        inside as f32 / (n * n) as f32
    }

    #[test]
    fn closed_form_matches_numeric_integration() {
        let mut worst: f32 = 0.0;
        for s in 0..=12 {
            let sigma = s as f32 / 12.0 * PI;
            for t in 0..=16 {
                let cos_theta = t as f32 / 8.0 - 1.0;
                let exact = cap_occlusion(sigma.cos(), cos_theta);
                let numeric = numeric(sigma.cos(), cos_theta);
                worst = worst.max((exact - numeric).abs());
                assert!(
                    (exact - numeric).abs() < 0.004,
                    "σ {sigma}, cos θ {cos_theta}: closed form {exact}, numeric {numeric}"
                );
            }
        }
        println!("largest difference {worst}");
    }

    #[test]
    fn limits() {
        // Nothing blocks nothing, everything blocks everything.
        assert_eq!(cap_occlusion(1.0, 0.3), 0.0);
        assert!((cap_occlusion(-1.0, -0.4) - 1.0).abs() < 1e-6);
        // A hemisphere centred on the normal blocks it all; centred below, nothing; centred on
        // the horizon, half of the cosine-weighted light.
        assert!((cap_occlusion(0.0, 1.0) - 1.0).abs() < 1e-6);
        assert!(cap_occlusion(0.0, -1.0).abs() < 1e-6);
        assert!((cap_occlusion(0.0, 0.0) - 0.5).abs() < 1e-5);
        // Small caps above the horizon: sin²σ cos θ.
        let sigma: f32 = 0.2;
        assert!((cap_occlusion(sigma.cos(), 0.5) - sigma.sin().powi(2) * 0.5).abs() < 1e-6);
    }
}

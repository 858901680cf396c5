//! Sample patterns, bit-identical to `shaders/sampling.wgsl`.

use bevy::math::{Mat3, Vec2, Vec3};

pub use crate::geometry::hash::{HASH_TO_UNIT, pcg_hash};

const GOLDEN_ANGLE: f32 = 2.399_963_2;
const HASH_TO_ANGLE: f32 = 1.462_918_1e-9;
/// Per-pixel rotation of the sample pattern, radians in [0, 2π).
pub fn pixel_rotation(x: u32, y: u32) -> f32 {
    pcg_hash(x ^ pcg_hash(y)) as f32 * HASH_TO_ANGLE
}

/// Sample `i` of `count` on a Vogel spiral filling a disk of `radius` pixels.
pub fn disk_sample(i: u32, count: u32, radius: f32, rotation: f32) -> Vec2 {
    let r = radius * ((i as f32 + 0.5) / count as f32).sqrt();
    let angle = i as f32 * GOLDEN_ANGLE + rotation;
    Vec2::new(angle.cos(), angle.sin()) * r
}

/// An orthonormal frame around unit `n` (Duff et al. 2017): columns tangent, bitangent, normal.
/// `tangent_frame` in `shaders/math.wgsl` is the GPU twin.
pub fn tangent_frame(n: Vec3) -> Mat3 {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    Mat3::from_cols(
        Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        Vec3::new(b, s + n.y * n.y * a, -n.y),
        n,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spiral_stays_inside_the_disk_and_covers_it() {
        let count = 64;
        let samples: Vec<Vec2> = (0..count)
            .map(|i| disk_sample(i, count, 10.0, 0.3))
            .collect();
        assert!(samples.iter().all(|s| s.length() <= 10.0 + 1e-4));
        let mean = samples.iter().copied().sum::<Vec2>() / count as f32;
        assert!(mean.length() < 1.0, "spiral is lopsided: mean {mean}");
        let inner = samples
            .iter()
            .filter(|s| s.length() < 10.0 / 2f32.sqrt())
            .count();
        assert_eq!(
            inner, 32,
            "half the samples belong in the inner half of the area"
        );
    }

    #[test]
    fn rotations_are_spread() {
        let angles: Vec<f32> = (0..256).map(|i| pixel_rotation(i % 16, i / 16)).collect();
        assert!(
            angles
                .iter()
                .all(|a| (0.0..std::f32::consts::TAU).contains(a))
        );
        let mean = angles.iter().sum::<f32>() / angles.len() as f32;
        assert!(
            (mean - std::f32::consts::PI).abs() < 0.4,
            "mean rotation {mean}"
        );
    }
}

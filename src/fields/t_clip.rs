//! T_clip of Malmer et al. 2005, §3.3.1: the share of a receiver's ambient light that a cone of
//! occluded directions blocks once the receiver's tangent plane clips it, with the diffuse
//! cosine included. The cone holds the fraction `a` of the whole sphere of directions (aperture
//! α with (1 − cos α) / 2 = a) around its axis d; β is the angle between d and the receiver's
//! normal. Tabulated once, looked up with bilinear interpolation by the GPU pass and the CPU
//! twin alike.

use bevy::math::Vec3;

/// Table entries along `a` (0 to 1) and along cos β (−1 to 1).
pub const T_CLIP_SIZE: usize = 32;
/// Cosine-weighted hemisphere samples per entry, per axis (squared in total).
const SAMPLES: usize = 48;

/// The table, row-major: entry (i, j) for a = i / (N − 1) and cos β = 2 j / (N − 1) − 1.
pub fn t_clip_table() -> Vec<f32> {
    // Stratified cosine-weighted directions around +z: their share inside the cone is the
    // cosine-weighted fraction of the hemisphere the cone covers.
    let directions: Vec<Vec3> = (0..SAMPLES * SAMPLES)
        .map(|k| {
            let (u, v) = (
                ((k % SAMPLES) as f32 + 0.5) / SAMPLES as f32,
                ((k / SAMPLES) as f32 + 0.5) / SAMPLES as f32,
            );
            let r = u.sqrt();
            let phi = std::f32::consts::TAU * v;
            Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).max(0.0).sqrt())
        })
        .collect();
    let n = T_CLIP_SIZE;
    let mut table = vec![0.0; n * n];
    for i in 0..n {
        let a = i as f32 / (n - 1) as f32;
        let cos_alpha = 1.0 - 2.0 * a;
        for j in 0..n {
            let cos_beta = 2.0 * j as f32 / (n - 1) as f32 - 1.0;
            let axis = Vec3::new((1.0 - cos_beta * cos_beta).max(0.0).sqrt(), 0.0, cos_beta);
            let inside = directions
                .iter()
                .filter(|w| w.dot(axis) >= cos_alpha)
                .count();
            table[i * n + j] = inside as f32 / directions.len() as f32;
        }
    }
    table
}

/// Bilinear lookup of `table` at occlusion `a` and `cos_beta`, exactly as `fields.wgsl` does it.
pub fn t_clip(table: &[f32], a: f32, cos_beta: f32) -> f32 {
    let n = T_CLIP_SIZE;
    let x = a.clamp(0.0, 1.0) * (n - 1) as f32;
    let y = (cos_beta.clamp(-1.0, 1.0) * 0.5 + 0.5) * (n - 1) as f32;
    let (x0, y0) = (
        (x.floor() as usize).min(n - 2),
        (y.floor() as usize).min(n - 2),
    );
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let at = |i: usize, j: usize| table[i * n + j];
    let top = at(x0, y0) * (1.0 - fy) + at(x0, y0 + 1) * fy;
    let bottom = at(x0 + 1, y0) * (1.0 - fy) + at(x0 + 1, y0 + 1) * fy;
    top * (1.0 - fx) + bottom * fx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits() {
        let table = t_clip_table();
        // No cone blocks nothing; the whole sphere blocks everything.
        assert!(t_clip(&table, 0.0, 0.3) < 0.01);
        assert!(t_clip(&table, 1.0, -0.7) > 0.99);
        // Half the sphere, centred on the normal: the whole hemisphere.
        assert!(t_clip(&table, 0.5, 1.0) > 0.98);
        // Half the sphere, centred below the surface: nothing above it.
        assert!(t_clip(&table, 0.5, -1.0) < 0.02);
        // A small cone along the normal blocks sin²α of the cosine-weighted hemisphere.
        let a = 0.1;
        let cos_alpha: f32 = 1.0 - 2.0 * a;
        let expected = 1.0 - cos_alpha * cos_alpha;
        assert!((t_clip(&table, a, 1.0) - expected).abs() < 0.02);
        // More occlusion never lets more light through, and facing the cone blocks more.
        for k in 0..10 {
            let a = k as f32 / 10.0;
            assert!(t_clip(&table, a + 0.1, 0.2) >= t_clip(&table, a, 0.2) - 1e-4);
            assert!(t_clip(&table, a, 0.9) >= t_clip(&table, a, 0.1) - 1e-4);
        }
    }
}

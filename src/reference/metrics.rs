//! Image metrics between two AO images of the same size.

/// Root-mean-square difference over the pixels where `mask` is true (all pixels without a
/// mask). 0 when no pixel takes part.
pub fn rmse(a: &[f32], b: &[f32], mask: Option<&[bool]>) -> f32 {
    let (sum, count) = pairs(a, b, mask).fold((0.0f64, 0usize), |(s, c), (x, y)| {
        (s + ((x - y) as f64).powi(2), c + 1)
    });
    if count == 0 {
        0.0
    } else {
        (sum / count as f64).sqrt() as f32
    }
}

/// Mean of `a − b` over the masked pixels: positive when `a` is brighter (more open).
pub fn mean_bias(a: &[f32], b: &[f32], mask: Option<&[bool]>) -> f32 {
    let (sum, count) = pairs(a, b, mask).fold((0.0f64, 0usize), |(s, c), (x, y)| {
        (s + (x - y) as f64, c + 1)
    });
    if count == 0 {
        0.0
    } else {
        (sum / count as f64) as f32
    }
}

/// Largest absolute difference over the masked pixels.
pub fn max_abs_diff(a: &[f32], b: &[f32], mask: Option<&[bool]>) -> f32 {
    pairs(a, b, mask)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

/// Error in fine detail: the RMSE, over the masked pixels, between the high-frequency parts of
/// `a` and `b`, each image minus its Gaussian blur at σ = 2 pixels (`width` × `height`, row-major,
/// clamped at the borders). A blur that smears detail the truth has, or noise the truth lacks,
/// both raise it; an error spread evenly over a region does not.
pub fn high_frequency_error(
    a: &[f32],
    b: &[f32],
    width: u32,
    height: u32,
    mask: Option<&[bool]>,
) -> f32 {
    let (ha, hb) = (
        high_frequency(a, width, height),
        high_frequency(b, width, height),
    );
    rmse(&ha, &hb, mask)
}

/// `image` minus its Gaussian blur at σ = 2 pixels.
fn high_frequency(image: &[f32], width: u32, height: u32) -> Vec<f32> {
    const SIGMA: f32 = 2.0;
    let radius = (3.0 * SIGMA).ceil() as i32;
    let kernel: Vec<f32> = (-radius..=radius)
        .map(|i| (-((i * i) as f32) / (2.0 * SIGMA * SIGMA)).exp())
        .collect();
    let total: f32 = kernel.iter().sum();
    let (w, h) = (width as i32, height as i32);
    let pass = |input: &[f32], step: (i32, i32)| -> Vec<f32> {
        let mut out = vec![0.0; input.len()];
        for y in 0..h {
            for x in 0..w {
                let mut sum = 0.0;
                for (k, weight) in kernel.iter().enumerate() {
                    let i = k as i32 - radius;
                    let qx = (x + step.0 * i).clamp(0, w - 1);
                    let qy = (y + step.1 * i).clamp(0, h - 1);
                    sum += weight * input[(qy * w + qx) as usize];
                }
                out[(y * w + x) as usize] = sum / total;
            }
        }
        out
    };
    let blurred = pass(&pass(image, (1, 0)), (0, 1));
    image.iter().zip(blurred).map(|(v, b)| v - b).collect()
}

fn pairs<'a>(
    a: &'a [f32],
    b: &'a [f32],
    mask: Option<&'a [bool]>,
) -> impl Iterator<Item = (f32, f32)> + 'a {
    assert_eq!(a.len(), b.len(), "images differ in size");
    a.iter()
        .zip(b)
        .enumerate()
        .filter(move |(i, _)| mask.is_none_or(|m| m[*i]))
        .map(|(_, (x, y))| (*x, *y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        let a = [1.0, 0.5, 0.0, 1.0];
        let b = [1.0, 0.0, 0.0, 0.0];
        assert!((rmse(&a, &b, None) - (1.25f32 / 4.0).sqrt()).abs() < 1e-6);
        assert!((mean_bias(&a, &b, None) - 0.375).abs() < 1e-6);
        let mask = [true, true, false, false];
        assert!((rmse(&a, &b, Some(&mask)) - (0.125f32).sqrt()).abs() < 1e-6);
        assert_eq!(max_abs_diff(&a, &b, Some(&mask)), 0.5);
        assert_eq!(rmse(&a, &b, Some(&[false; 4])), 0.0);
    }

    #[test]
    fn high_frequency_error_sees_detail_not_offsets() {
        let (w, h) = (32u32, 32u32);
        let stripes: Vec<f32> = (0..w * h).map(|i| ((i % w) % 2) as f32).collect();
        let flat = vec![0.5; (w * h) as usize];
        let lifted: Vec<f32> = stripes.iter().map(|v| v * 0.5 + 0.25).collect();
        // A constant offset has no high frequency; blurring the stripes away loses all of it.
        assert!(high_frequency_error(&flat, &vec![0.9; flat.len()], w, h, None) < 1e-5);
        assert!(high_frequency_error(&flat, &stripes, w, h, None) > 0.4);
        let half = high_frequency_error(&lifted, &stripes, w, h, None);
        assert!(half > 0.2 && half < 0.3, "{half}");
    }
}

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
}

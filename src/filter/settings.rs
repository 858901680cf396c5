//! The settings of the cross-bilateral blur, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Default half-width of the cross-bilateral blur, pixels.
pub const DEFAULT_BLUR_RADIUS: u32 = 4;
/// Default depth sharpness of the cross-bilateral blur (no unit).
pub const DEFAULT_BLUR_SHARPNESS: f32 = 16.0;

/// Separable cross-bilateral blur of the occlusion buffer, X then Y (Bavoil & Sainz 2008,
/// "Cross Bilateral Filter"): a Gaussian in image space whose weights fall with the difference in
/// view depth, so occlusion does not bleed across silhouettes.
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct AoBlur {
    /// Half-width of the kernel; the kernel is `2 * radius + 1` pixels wide per pass and its
    /// Gaussian has σ = (radius + 1) / 2. Units: pixels. Valid: 0 (off) ..= 16.
    /// Default: [`DEFAULT_BLUR_RADIUS`].
    pub radius: u32,
    /// How fast a sample's weight falls with its depth difference, relative to the centre
    /// pixel's depth: weight × exp(−(sharpness · Δz / z)²). 0 is a plain Gaussian. No unit.
    /// Valid: ≥ 0. Default: [`DEFAULT_BLUR_SHARPNESS`].
    pub sharpness: f32,
}

impl Default for AoBlur {
    fn default() -> Self {
        Self {
            radius: DEFAULT_BLUR_RADIUS,
            sharpness: DEFAULT_BLUR_SHARPNESS,
        }
    }
}

impl AoBlur {
    /// Largest radius the blur accepts.
    pub const MAX_RADIUS: u32 = 16;

    /// No blur.
    pub const OFF: AoBlur = AoBlur {
        radius: 0,
        sharpness: DEFAULT_BLUR_SHARPNESS,
    };

    /// The same blur clamped into its valid ranges (a bad sharpness becomes the default).
    pub fn sanitized(&self) -> Self {
        Self {
            radius: self.radius.min(Self::MAX_RADIUS),
            sharpness: if self.sharpness.is_finite() && self.sharpness >= 0.0 {
                self.sharpness
            } else {
                DEFAULT_BLUR_SHARPNESS
            },
        }
    }
}

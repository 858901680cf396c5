//! The sample budget of the near-field pass, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Default most samples per receiver and layer (the budget of [`AoPreset::High`](crate::AoPreset::High)).
pub const DEFAULT_MAX_SAMPLES: u32 = 32;
/// Default fewest samples per receiver and layer.
pub const DEFAULT_MIN_SAMPLES: u32 = 4;

/// Parameters of the near-field pass (Shanmugam & Arikan 2007, §4.2).
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct NearFieldParams {
    /// Most neighbouring pixels gathered per receiver and layer. The count actually used
    /// scales with the projected r_far: one per pixel inside the projected disk at most
    /// (S&A fig. 4). Valid: 1..=256. Default: [`DEFAULT_MAX_SAMPLES`].
    pub max_samples: u32,
    /// Fewest neighbouring pixels gathered per receiver and layer, however small r_far
    /// projects. Valid: 1..=max_samples. Default: [`DEFAULT_MIN_SAMPLES`].
    pub min_samples: u32,
    /// Also gather occluders from the back-face layer (S&A §4.2: "the first two layers").
    /// Default: `true`.
    pub back_layer: bool,
}

impl Default for NearFieldParams {
    fn default() -> Self {
        Self {
            max_samples: DEFAULT_MAX_SAMPLES,
            min_samples: DEFAULT_MIN_SAMPLES,
            back_layer: true,
        }
    }
}

impl NearFieldParams {
    /// Most samples a parameter set may ask for.
    pub const MAX_SAMPLES: u32 = 256;

    /// The default parameters with another sample budget.
    pub fn with_max_samples(max_samples: u32) -> Self {
        Self {
            max_samples,
            ..Self::default()
        }
    }

    /// The same parameters clamped into their valid ranges.
    pub fn sanitized(&self) -> Self {
        let max_samples = self.max_samples.clamp(1, Self::MAX_SAMPLES);
        Self {
            max_samples,
            min_samples: self.min_samples.clamp(1, max_samples),
            back_layer: self.back_layer,
        }
    }
}

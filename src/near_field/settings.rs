//! The sample budget of the near-field pass, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Named parameter sets for the near-field pass, plus a custom form.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub enum AoQuality {
    /// At most 8 samples per pixel and layer.
    Low,
    /// At most 16 samples per pixel and layer.
    Medium,
    /// At most 32 samples per pixel and layer.
    #[default]
    High,
    /// At most 64 samples per pixel and layer.
    Ultra,
    /// Explicit parameters.
    Custom(NearFieldParams),
}

impl AoQuality {
    /// The presets in increasing cost.
    pub const PRESETS: [AoQuality; 4] = [
        AoQuality::Low,
        AoQuality::Medium,
        AoQuality::High,
        AoQuality::Ultra,
    ];

    /// The near-field parameters this preset stands for.
    pub fn params(&self) -> NearFieldParams {
        let max_samples = match self {
            AoQuality::Low => 8,
            AoQuality::Medium => 16,
            AoQuality::High => 32,
            AoQuality::Ultra => 64,
            AoQuality::Custom(params) => return params.sanitized(),
        };
        NearFieldParams {
            max_samples,
            ..NearFieldParams::default()
        }
    }

    /// Lower-case name (`low`, `medium`, `high`, `ultra`, `custom`).
    pub fn name(&self) -> &'static str {
        match self {
            AoQuality::Low => "low",
            AoQuality::Medium => "medium",
            AoQuality::High => "high",
            AoQuality::Ultra => "ultra",
            AoQuality::Custom(_) => "custom",
        }
    }

    /// The preset with this lower-case name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::PRESETS.into_iter().find(|q| q.name() == name)
    }
}

/// Parameters of the near-field pass (Shanmugam & Arikan 2007, §4.2).
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct NearFieldParams {
    /// Most neighbouring pixels gathered per receiver and layer. The count actually used
    /// scales with the projected r_far: one per pixel inside the projected disk at most
    /// (S&A fig. 4). Valid: 1..=256. Default: 32 (the `High` preset).
    pub max_samples: u32,
    /// Fewest neighbouring pixels gathered per receiver and layer, however small r_far
    /// projects. Valid: 1..=max_samples. Default: 4.
    pub min_samples: u32,
    /// Also gather occluders from the back-face layer (S&A §4.2: "the first two layers").
    /// Default: `true`.
    pub back_layer: bool,
}

impl Default for NearFieldParams {
    fn default() -> Self {
        Self {
            max_samples: 32,
            min_samples: 4,
            back_layer: true,
        }
    }
}

impl NearFieldParams {
    /// Most samples a custom parameter set may ask for.
    pub const MAX_SAMPLES: u32 = 256;

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

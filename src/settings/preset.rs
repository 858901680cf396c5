//! The one ladder of quality levels, from cheapest to most accurate.

use bevy::reflect::Reflect;

use super::{AoTechnique, DynamicAo, HorizonMode, HorizonParams, NearFieldParams, RayMarchParams};

/// A quality level: the sample budget of every technique at that level, and the technique and
/// resolution [`DynamicAo::from_preset`] picks for it (the one that measured the lowest error
/// for its cost). The table in the README gives each level's cost and error.
///
/// | level | picked technique | near field (samples) | horizon (dirs × steps, mode) | ray march (dirs × elevations × steps) |
/// |---|---|---|---|---|
/// | `Low` | horizon, half resolution | 8 | 4 × 4, low | 8 × 4 × 8 |
/// | `Medium` | horizon | 16 | 8 × 8, low | 8 × 4 × 8 |
/// | `High` (the default) | near field | 32 | 8 × 8, normal | 8 × 4 × 8 |
/// | `Ultra` | ray march | 64 | 8 × 8, high | 8 × 4 × 8 |
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Clone, Debug, PartialEq, Hash)]
pub enum AoPreset {
    /// Horizon-based AO, low mode, 4 directions × 4 steps, at half resolution.
    Low,
    /// Horizon-based AO, low mode, 8 directions × 8 steps, full resolution.
    Medium,
    /// Two-layer near-field AO, 32 samples per pixel and layer (the [`DynamicAo`] default).
    #[default]
    High,
    /// The ray-marched reference, 8 × 4 rays × 8 steps.
    Ultra,
}

impl AoPreset {
    /// Every level, from cheapest to most accurate.
    pub const ALL: [AoPreset; 4] = [
        AoPreset::Low,
        AoPreset::Medium,
        AoPreset::High,
        AoPreset::Ultra,
    ];

    /// Lower-case name (`low`, `medium`, `high`, `ultra`).
    pub fn name(self) -> &'static str {
        match self {
            AoPreset::Low => "low",
            AoPreset::Medium => "medium",
            AoPreset::High => "high",
            AoPreset::Ultra => "ultra",
        }
    }

    /// The level with this lower-case name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The technique this level runs.
    pub fn technique(self) -> AoTechnique {
        match self {
            AoPreset::Low | AoPreset::Medium => AoTechnique::Horizon,
            AoPreset::High => AoTechnique::NearField,
            AoPreset::Ultra => AoTechnique::RayMarch,
        }
    }

    /// The near-field sample budget of this level.
    pub fn near_field(self) -> NearFieldParams {
        NearFieldParams::with_max_samples(match self {
            AoPreset::Low => 8,
            AoPreset::Medium => 16,
            AoPreset::High => 32,
            AoPreset::Ultra => 64,
        })
    }

    /// The horizon-based AO budget of this level.
    pub fn horizon(self) -> HorizonParams {
        let (directions, steps, mode) = match self {
            AoPreset::Low => (4, 4, HorizonMode::Low),
            AoPreset::Medium => (8, 8, HorizonMode::Low),
            AoPreset::High => (8, 8, HorizonMode::Normal),
            AoPreset::Ultra => (8, 8, HorizonMode::High),
        };
        HorizonParams {
            directions,
            steps,
            mode,
            ..HorizonParams::default()
        }
    }

    /// The ray-march budget of this level: the reference keeps one budget at every level.
    pub fn ray_march(self) -> RayMarchParams {
        RayMarchParams::default()
    }

    /// Whether this level computes the occlusion at half resolution.
    pub fn half_resolution(self) -> bool {
        self == AoPreset::Low
    }
}

impl DynamicAo {
    /// Every technique's budget at this level, the technique and resolution the level picks,
    /// and the defaults for everything else.
    pub fn from_preset(preset: AoPreset) -> Self {
        Self {
            technique: preset.technique(),
            near_field: preset.near_field(),
            horizon: preset.horizon(),
            ray_march: preset.ray_march(),
            half_resolution: preset.half_resolution(),
            ..Self::default()
        }
    }
}

//! The one ladder of quality levels, from cheapest to most accurate.

use bevy::reflect::Reflect;

use super::{
    AoTechnique, AoTemporal, DynamicAo, HorizonMode, HorizonParams, NearFieldParams, RayMarchParams,
};

/// A quality level: the sample budget of every technique at that level, and the technique,
/// resolution and accumulation [`DynamicAo::from_preset`] picks for it (the one that measured the
/// lowest error for its cost). The README's table gives each level's GPU time next to Bevy's
/// SSAO, its converged error against ground truth and the frames it takes to converge.
///
/// | level | picked technique | near field (samples) | horizon (dirs × steps, mode) | ray march (dirs × elevations × steps) | half resolution | accumulated |
/// |---|---|---|---|---|---|---|
/// | `Low` | ray march | 8 | 4 × 4, low | 1 × 1 × 4 | yes | yes |
/// | `Medium` | ray march | 16 | 8 × 8, low | 1 × 1 × 8 | yes | yes |
/// | `High` (the default) | ray march | 32 | 8 × 8, normal | 2 × 1 × 6 | yes | yes |
/// | `Ultra` | ray march | 64 | 8 × 8, high | 2 × 2 × 8 | yes | yes |
///
/// Half resolution applies above [`DynamicAo::small_viewport_pixels`] (240 × 180); smaller
/// viewports run every level at full resolution.
///
/// The ray march counts what ground truth counts (cosine-weighted rays that hit within R), so
/// its average over frames converges to the ground truth the ND-buffer can show; a handful of
/// rays per pixel and frame at half resolution, accumulated, cost less than Bevy's SSAO. Every
/// level accumulates, and marches one texel of two each frame
/// ([`RayMarchParams::checkerboard`](crate::RayMarchParams::checkerboard)), so each texel gets
/// its rays every other frame: without accumulation the noise needs the blur, whose full-resolution passes
/// cost more than the whole of `High` on a CPU rasterizer (README, preset table). For a still noise pattern without
/// motion vectors, set [`DynamicAo::temporal`] to [`AoTemporal::OFF`] and give the technique a
/// budget that suffices in one frame.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Clone, Debug, PartialEq, Hash)]
pub enum AoPreset {
    /// Ray march, 1 ray of 4 steps per frame at half resolution, accumulated: the cheapest level,
    /// with about 1.1–1.2 × `Medium`'s converged error.
    Low,
    /// Ray march, 1 ray of 8 steps per frame at half resolution, accumulated.
    Medium,
    /// Ray march, 2 × 1 rays of 6 steps per frame at half resolution, accumulated (the
    /// [`DynamicAo`] default).
    #[default]
    High,
    /// Ray march, 2 × 2 rays of 8 steps per frame at half resolution, accumulated.
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

    /// The technique this level runs (every level runs the ray march, with its own budget).
    pub fn technique(self) -> AoTechnique {
        AoTechnique::RayMarch
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

    /// The ray-march budget of this level, per frame.
    pub fn ray_march(self) -> RayMarchParams {
        let (directions, elevations, steps) = match self {
            AoPreset::Low => (1, 1, 4),
            AoPreset::Medium => (1, 1, 8),
            AoPreset::High => (2, 1, 6),
            AoPreset::Ultra => (2, 2, 8),
        };
        RayMarchParams {
            directions,
            elevations,
            steps,
            ..RayMarchParams::default()
        }
    }

    /// Whether this level computes the occlusion at half resolution (every level does: at full
    /// resolution the same rays cost about four times as much). Viewports up to
    /// [`DynamicAo::small_viewport_pixels`] run at full resolution all the same.
    pub fn half_resolution(self) -> bool {
        true
    }

    /// Whether this level accumulates over frames, and how (every level does: see the type's
    /// doc).
    pub fn temporal(self) -> AoTemporal {
        AoTemporal::ON
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
            temporal: preset.temporal(),
            ..Self::default()
        }
    }
}

//! The parameters of horizon-based AO, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Parameters of horizon-based AO (Bavoil & Sainz 2008, "Horizon-Based Ambient Occlusion").
/// The radius is [`DynamicAo::radius`](crate::DynamicAo::radius).
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct HorizonParams {
    /// Image-space directions per pixel, randomly rotated per pixel. Valid: 1..=32. Default: 8.
    pub directions: u32,
    /// Most steps per direction; fewer where the projected radius covers fewer pixels.
    /// Valid: 1..=32. Default: 8.
    pub steps: u32,
    /// Raises the tangent plane by this angle, hiding creases of coarse tessellation.
    /// Units: radians. Valid: 0..π/2. Default: 0.1.
    pub angle_bias: f32,
    /// W0: scale of the per-sample attenuation W0 · W(r/R), W(x) = 1 − x². No unit.
    /// Valid: ≥ 0. Default: 1.
    pub attenuation: f32,
    /// Scale on the integrated occlusion. No unit. Valid: ≥ 0. Default: 1.
    pub contrast: f32,
    /// Which of the whitepaper's three modes. Default: [`HorizonMode::Normal`].
    pub mode: HorizonMode,
}

/// The three modes of horizon-based AO (Bavoil & Sainz 2008).
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq, Hash)]
pub enum HorizonMode {
    /// No normals: the horizon is integrated over the whole sphere (from straight down) and the
    /// lower half, one unit of W0 per direction, is subtracted.
    Low,
    /// The hemisphere around the per-pixel normal: each direction starts at the elevation of the
    /// tangent plane.
    #[default]
    Normal,
    /// As `Normal`, with a more accurate starting horizon and less banding: each direction starts
    /// at the higher of the tangent plane and the surface one pixel away along it (the depth
    /// buffer's own tangent, which hides the facets of coarse meshes), and the step offsets are
    /// jittered per direction rather than per pixel.
    High,
}

impl HorizonMode {
    /// Every mode, from cheapest to most accurate.
    pub const ALL: [HorizonMode; 3] = [HorizonMode::Low, HorizonMode::Normal, HorizonMode::High];

    /// The value the shaders and `reference::horizon` take: 0 low, 1 normal, 2 high.
    pub fn shader_index(self) -> u32 {
        match self {
            HorizonMode::Low => 0,
            HorizonMode::Normal => 1,
            HorizonMode::High => 2,
        }
    }
}

impl Default for HorizonParams {
    fn default() -> Self {
        Self {
            directions: 8,
            steps: 8,
            angle_bias: 0.1,
            attenuation: 1.0,
            contrast: 1.0,
            mode: HorizonMode::Normal,
        }
    }
}

impl HorizonParams {
    /// The same parameters clamped into their valid ranges; bad floats become defaults.
    pub fn sanitized(&self) -> Self {
        let d = Self::default();
        let valid = |v: f32, max: f32, default: f32| {
            if v.is_finite() && (0.0..=max).contains(&v) {
                v
            } else {
                default
            }
        };
        Self {
            directions: self.directions.clamp(1, 32),
            steps: self.steps.clamp(1, 32),
            angle_bias: valid(self.angle_bias, 1.5, d.angle_bias),
            attenuation: valid(self.attenuation, f32::MAX, d.attenuation),
            contrast: valid(self.contrast, f32::MAX, d.contrast),
            mode: self.mode,
        }
    }
}

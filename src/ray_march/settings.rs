//! The parameters of the ray-marched reference, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Parameters of the ray-marched reference (Bavoil & Sainz 2008, "Ray-Marched Ambient
/// Occlusion"): `directions × elevations` cosine-weighted rays around the normal, each
/// marched in `steps` equal steps over the radius R ([`DynamicAo::radius`](crate::DynamicAo::radius)). A step is blocked
/// where it lies behind the front layer and in front of the back-face layer (or, where no back
/// face was drawn, less than R behind the front layer). Under temporal accumulation the rays'
/// rotation, elevations and step offsets move every frame, so the default 2 rays of 6 steps
/// per frame add up to many more; without it, give it [`RayMarchParams::REFERENCE`] or more.
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct RayMarchParams {
    /// Azimuths around the normal, randomly rotated per pixel. Valid: 1..=64. Default: 2.
    pub directions: u32,
    /// Elevations per azimuth, stratified for a cosine-weighted hemisphere. Valid: 1..=64.
    /// Default: 1.
    pub elevations: u32,
    /// Samples per ray. Valid: 1..=64. Default: 6.
    pub steps: u32,
}

impl Default for RayMarchParams {
    fn default() -> Self {
        Self {
            directions: 2,
            elevations: 1,
            steps: 6,
        }
    }
}

impl RayMarchParams {
    /// 8 × 4 rays of 8 steps: enough in a single frame, the in-engine reference the CPU twin
    /// is checked against.
    pub const REFERENCE: RayMarchParams = RayMarchParams {
        directions: 8,
        elevations: 4,
        steps: 8,
    };

    /// The same parameters clamped into their valid ranges.
    pub fn sanitized(&self) -> Self {
        Self {
            directions: self.directions.clamp(1, 64),
            elevations: self.elevations.clamp(1, 64),
            steps: self.steps.clamp(1, 64),
        }
    }
}

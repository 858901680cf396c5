//! The parameters of the ray-marched reference, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Parameters of the ray-marched reference (Bavoil & Sainz 2008, "Ray-Marched Ambient
/// Occlusion"): `directions × elevations` cosine-weighted rays around the normal, each
/// marched in `steps` equal steps over the radius R ([`DynamicAo::radius`](crate::DynamicAo::radius)). A step is blocked
/// where it lies behind the front layer and in front of the back-face layer (or, where no back
/// face was drawn, less than R behind the front layer).
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct RayMarchParams {
    /// Azimuths around the normal, randomly rotated per pixel. Valid: 1..=64. Default: 8.
    pub directions: u32,
    /// Elevations per azimuth, stratified for a cosine-weighted hemisphere. Valid: 1..=64.
    /// Default: 4.
    pub elevations: u32,
    /// Samples per ray. Valid: 1..=64. Default: 8.
    pub steps: u32,
}

impl Default for RayMarchParams {
    fn default() -> Self {
        Self {
            directions: 8,
            elevations: 4,
            steps: 8,
        }
    }
}

impl RayMarchParams {
    /// The same parameters clamped into their valid ranges.
    pub fn sanitized(&self) -> Self {
        Self {
            directions: self.directions.clamp(1, 64),
            elevations: self.elevations.clamp(1, 64),
            steps: self.steps.clamp(1, 64),
        }
    }
}

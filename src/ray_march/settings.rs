//! The parameters of the ray-marched reference, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Parameters of the ray-marched reference (Bavoil & Sainz 2008, "Ray-Marched Ambient
/// Occlusion"): `directions × elevations` cosine-weighted rays around the normal, each
/// marched in `steps` steps of R / `steps` ([`DynamicAo::radius`](crate::DynamicAo::radius)), the last at R itself. A step is blocked
/// where it lies behind the front layer and less than `thickness × R` behind the back-face
/// layer (or, where no back face was drawn, less than R behind the front layer). Under temporal accumulation the rays'
/// rotation, elevations and step offsets move every frame, so the default 2 rays of 6 steps
/// per frame add up to many more, and by default each frame marches half the texels
/// ([`RayMarchParams::checkerboard`]); without it, give it [`RayMarchParams::REFERENCE`] or more.
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
    /// How far behind the back-face layer a step still counts as blocked, as a fraction of the
    /// ray march's reach: R, or [`DynamicAo::near_field_radius`](crate::DynamicAo::near_field_radius)
    /// where far-field terms count the rest.
    /// The layer holds only the nearest back face of each pixel, and most models are shells: an
    /// outer and an inner surface millimetres apart (DamagedHelmet's), or meshes that overlap.
    /// Behind that inner surface the ND-buffer cannot tell air from solid; counted as air, rays
    /// that pass under a model's overhang or into the parts of a character hidden behind its
    /// front read as open, and floors around models came out too light. At 0.15 the default's
    /// RMSE against the CPU ray tracer fell on every scene we measure, at R = 0.73 m and 2 m
    /// (BENCHMARKS.md, "Thickness behind the back layer"). 0 counts everything behind the
    /// back-face layer as air. On the project's skinned walker, whose limbs are closed solids
    /// with air between them, it raised the error by 2% alone and by up to 10% joined to the
    /// far field at 0.75 m. Behind a two-sided sheet (a polygon with a double-sided material,
    /// whose back face the layer holds at its front's depth) the layer tells nothing, and a step
    /// counts as blocked up to R behind it, whatever this value, as where no back face was drawn.
    /// No unit. Valid: 0..=1. Default: [`DEFAULT_RAY_MARCH_THICKNESS`].
    pub thickness: f32,
    /// Under temporal accumulation, march one texel of two each frame, in a checkerboard that
    /// alternates, so each texel is marched every other frame. The march costs about half as
    /// much; a texel's history gains a sample every other frame, so the occlusion takes twice
    /// the frames to converge (the history still averages up to
    /// [`AoTemporal::max_frames`](crate::AoTemporal::max_frames) samples). A texel skipped this
    /// frame keeps its reprojected history, or takes its four neighbours' values where it has
    /// none (a disocclusion). In motion, the shadow of a moving occluder trails about three
    /// times as far as when every texel is marched every frame (BENCHMARKS.md, "Measured
    /// again"): turn it off where fast motion matters more than the march's cost. No effect
    /// without accumulation. Default: `true`.
    pub checkerboard: bool,
}

/// Default [`RayMarchParams::thickness`]: a fraction of R, no unit.
pub const DEFAULT_RAY_MARCH_THICKNESS: f32 = 0.15;

impl Default for RayMarchParams {
    fn default() -> Self {
        Self {
            directions: 2,
            elevations: 1,
            steps: 6,
            thickness: DEFAULT_RAY_MARCH_THICKNESS,
            checkerboard: true,
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
        thickness: DEFAULT_RAY_MARCH_THICKNESS,
        checkerboard: false,
    };

    /// The same parameters clamped into their valid ranges.
    pub fn sanitized(&self) -> Self {
        Self {
            directions: self.directions.clamp(1, 64),
            elevations: self.elevations.clamp(1, 64),
            steps: self.steps.clamp(1, 64),
            thickness: if self.thickness.is_nan() {
                DEFAULT_RAY_MARCH_THICKNESS
            } else {
                self.thickness.clamp(0.0, 1.0)
            },
            checkerboard: self.checkerboard,
        }
    }
}

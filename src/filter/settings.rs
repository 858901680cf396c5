//! The settings of the cross-bilateral blur, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Default half-width of the cross-bilateral blur without temporal accumulation, pixels.
pub const DEFAULT_BLUR_RADIUS: u32 = 4;
/// Default half-width of the cross-bilateral blur under temporal accumulation, pixels: none.
pub const DEFAULT_ACCUMULATED_BLUR_RADIUS: u32 = 0;
/// Default half-width of the voxel term's blur under temporal accumulation, pixels.
pub const DEFAULT_VOXEL_ACCUMULATED_BLUR_RADIUS: u32 = 1;
/// Default depth sharpness of the cross-bilateral blur (no unit).
pub const DEFAULT_BLUR_SHARPNESS: f32 = 16.0;
/// Default normal sharpness of the cross-bilateral blur (no unit).
pub const DEFAULT_BLUR_NORMAL_SHARPNESS: f32 = 16.0;
/// Default reach of the fine-detail term joined with the ray march's occlusion, pixels.
pub const DEFAULT_BLUR_DETAIL_REACH: u32 = 6;

/// Separable cross-bilateral blur of the occlusion buffer, X then Y (Bavoil & Sainz 2008,
/// "Cross Bilateral Filter"): a Gaussian in image space whose weights fall with the difference in
/// view depth, so occlusion does not bleed across silhouettes, and with the angle between the
/// front layer's normals, so it does not bleed across creases, panel lines and thin parts either.
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct AoBlur {
    /// Half-width of the kernel without temporal accumulation (the voxel term's too, where it
    /// does not accumulate); the kernel is `2 * radius + 1` pixels wide per pass and its Gaussian
    /// has σ = (radius + 1) / 2. Units: pixels. Valid: 0 (off) ..= 16. Default: [`DEFAULT_BLUR_RADIUS`].
    pub radius: u32,
    /// Half-width of the image-space occlusion's kernel under temporal accumulation
    /// ([`AoTemporal`](crate::AoTemporal)). By default the blur does not run there: the history
    /// already averages the noise it would (converged error against ground truth within 0.0013
    /// of the blurred one on our scenes), and its two full-resolution passes cost more than every
    /// other pass of the default together (on lavapipe about 20 ms a frame at 640×480 against
    /// 15 ms; BENCHMARKS.md, "The default runs no blur"). Units: pixels. Valid: 0 (off) ..= 16.
    /// Default: [`DEFAULT_ACCUMULATED_BLUR_RADIUS`].
    pub accumulated_radius: u32,
    /// Half-width of the voxel term's kernel under temporal accumulation. Its rays turn every
    /// frame, so the history averages their noise; what a blur still hides is the grid's steps,
    /// and at `radius` (4) it also smears the occlusion of a model's facets and creases. One
    /// pixel lowered the converged error against ground truth at R = 2 m (the Fox on a floor
    /// 0.0261 → 0.0224, 160×120) and cost the filter 0.6× its time on lavapipe (BENCHMARKS.md,
    /// "The voxel term's blur under accumulation"). Units: pixels. Valid: 0 (off) ..= 16.
    /// Default: [`DEFAULT_VOXEL_ACCUMULATED_BLUR_RADIUS`].
    pub voxel_accumulated_radius: u32,
    /// How fast a sample's weight falls with its depth difference, relative to the centre
    /// pixel's depth: weight × exp(−(sharpness · Δz / z)²). 0 is a plain Gaussian. No unit.
    /// Valid: ≥ 0. Default: [`DEFAULT_BLUR_SHARPNESS`].
    pub sharpness: f32,
    /// How fast a sample's weight falls with the angle between its normal and the centre
    /// pixel's (the front layer's, normal maps included): weight × exp(−(normal_sharpness ·
    /// (1 − cos θ))²). At 16 a sample at 20° keeps 39% of its weight and one at 45° none to
    /// speak of; 0 weighs by depth alone, as Bavoil & Sainz do. The image-space occlusion's blur
    /// only: the voxel term's weighs by depth alone (its error is the grid's steps, which run
    /// across surfaces). No unit. Valid: ≥ 0. Default: [`DEFAULT_BLUR_NORMAL_SHARPNESS`].
    pub normal_sharpness: f32,
    /// Reach of the fine-detail term, pixels: the ray march's occlusion is joined with the
    /// occlusion of the surfaces within this many pixels along the pixel's row and column, read
    /// from the front layer at full resolution (the highest of them on each side, as a horizon,
    /// cosine-weighted, falling to nothing at the reach or at R). Grooves, panel lines and
    /// creases narrower than the ray march's steps are what the rays step over; this term
    /// restores them (BENCHMARKS.md, "The blur restores fine detail"). Under temporal
    /// accumulation the ray march adds it itself, one of the four sides a frame, and the history
    /// averages the four (a sixteenth of the reads of all four sides a frame at full resolution),
    /// and at half resolution the upsampling adds it to the pixels between the march's texels
    /// that lie below the surface those texels span, over the texels around them (a groove a
    /// pixel wide that no texel shows); without accumulation the blur's last pass adds all four, where the blur runs (`radius`
    /// above 0). It applies to the ray march only (the other techniques sample the front layer
    /// near the pixel themselves). 0 turns it off. Units: pixels. Valid: 0 ..=
    /// [`AoBlur::MAX_DETAIL_REACH`]. Default: [`DEFAULT_BLUR_DETAIL_REACH`].
    pub detail_reach: u32,
}

impl Default for AoBlur {
    fn default() -> Self {
        Self {
            radius: DEFAULT_BLUR_RADIUS,
            accumulated_radius: DEFAULT_ACCUMULATED_BLUR_RADIUS,
            voxel_accumulated_radius: DEFAULT_VOXEL_ACCUMULATED_BLUR_RADIUS,
            sharpness: DEFAULT_BLUR_SHARPNESS,
            normal_sharpness: DEFAULT_BLUR_NORMAL_SHARPNESS,
            detail_reach: DEFAULT_BLUR_DETAIL_REACH,
        }
    }
}

impl AoBlur {
    /// Largest radius the blur accepts.
    pub const MAX_RADIUS: u32 = 16;
    /// Largest reach of the fine-detail term accepted, pixels.
    pub const MAX_DETAIL_REACH: u32 = 16;

    /// No blur.
    pub const OFF: AoBlur = AoBlur {
        radius: 0,
        accumulated_radius: 0,
        voxel_accumulated_radius: 0,
        sharpness: DEFAULT_BLUR_SHARPNESS,
        normal_sharpness: DEFAULT_BLUR_NORMAL_SHARPNESS,
        detail_reach: DEFAULT_BLUR_DETAIL_REACH,
    };

    /// Half-width of the voxel term's kernel, pixels: [`AoBlur::voxel_accumulated_radius`] where
    /// the voxel term accumulates over frames, else [`AoBlur::radius`].
    pub fn voxel_radius(&self, accumulating: bool) -> u32 {
        match accumulating {
            true => self.voxel_accumulated_radius,
            false => self.radius,
        }
    }

    /// The same blur clamped into its valid ranges (a bad sharpness becomes the default).
    pub fn sanitized(&self) -> Self {
        let valid = |value: f32, default| {
            if value.is_finite() && value >= 0.0 {
                value
            } else {
                default
            }
        };
        Self {
            radius: self.radius.min(Self::MAX_RADIUS),
            accumulated_radius: self.accumulated_radius.min(Self::MAX_RADIUS),
            voxel_accumulated_radius: self.voxel_accumulated_radius.min(Self::MAX_RADIUS),
            sharpness: valid(self.sharpness, DEFAULT_BLUR_SHARPNESS),
            normal_sharpness: valid(self.normal_sharpness, DEFAULT_BLUR_NORMAL_SHARPNESS),
            detail_reach: self.detail_reach.min(Self::MAX_DETAIL_REACH),
        }
    }
}

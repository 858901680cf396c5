//! The settings of temporal accumulation, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Default most frames a pixel's history averages.
pub const DEFAULT_TEMPORAL_FRAMES: u32 = 16;

/// Temporal accumulation of the image-space occlusion and the voxel term: the sample pattern (the
/// voxel rays' too) moves every frame
/// along a low-discrepancy sequence, and each frame's result is averaged with the pixel's
/// history, found where the pixel was last frame through Bevy's motion vectors (so moving,
/// skinned and morphed meshes reproject correctly). A history whose depth or normal does not
/// match the pixel (a disocclusion) is dropped, and a history far from the mean of this frame's
/// values around the pixel is clamped toward it (no ghost trails). With it on, the image-space
/// blur takes [`AoBlur::accumulated_radius`](crate::AoBlur::accumulated_radius), by default
/// none (the voxel term's [`AoBlur::voxel_accumulated_radius`](crate::AoBlur::voxel_accumulated_radius),
/// by default one pixel), and the ray march adds the fine-detail term itself, a side a frame.
///
/// On by default: the default technique traces 2 rays per texel every other frame (its
/// checkerboard) and relies on it to reach the error of many more (see [`AoPreset`](crate::AoPreset)). Turn it off for a static
/// noise pattern without motion vectors, and give the technique a budget that suffices in one
/// frame, with the blur on (every preset accumulates).
///
/// Turning it on adds Bevy's `MotionVectorPrepass` to the camera (where an image-space technique
/// or a voxel volume needs it), which stays when accumulation is turned off again (taking it away
/// from a running camera stopped its rendering in our tests). It does not need Bevy's temporal
/// anti-aliasing, and works beside it on the same camera: with Bevy's
/// `TemporalAntiAliasing` the converged error rises by 0.001–0.003 on average over the places in
/// TAA's 8-frame jitter cycle where the accumulation can start, by 0.005 at the worst
/// (`cargo test --test gpu accumulation_works_with_bevys`).
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct AoTemporal {
    /// Accumulate over frames. Default: `true`.
    pub enabled: bool,
    /// Most frames a pixel's history averages: the noise falls as 1/√frames up to this, and a
    /// change in the scene takes about this many frames to settle where the clamp does not catch
    /// it. Under the ray march's [checkerboard](crate::RayMarchParams::checkerboard) a texel
    /// gains a sample every other frame, and this counts samples: the history spans twice as many
    /// frames. At 32 a still view's grain falls further (its flicker by a third) and the
    /// converged error with it, at no cost per frame, while a stale shadow fades more slowly
    /// (the trail behind moving occluders about a tenth longer in the temporal bench;
    /// BENCHMARKS.md, "How many samples a history averages"): worth it where the camera mostly
    /// holds still. Valid: 1..=64. Default: [`DEFAULT_TEMPORAL_FRAMES`].
    pub max_frames: u32,
    /// Drop every pixel's history on the next frame (set it on a camera cut); the plugin sets it
    /// back to `false`. The history is also dropped when the view's size or its other settings
    /// change. Default: `false`.
    pub reset: bool,
}

impl Default for AoTemporal {
    fn default() -> Self {
        Self::ON
    }
}

impl AoTemporal {
    /// Most frames a history may average.
    pub const MAX_FRAMES: u32 = 64;

    /// Accumulation on, with the default history length (the default).
    pub const ON: AoTemporal = AoTemporal {
        enabled: true,
        max_frames: DEFAULT_TEMPORAL_FRAMES,
        reset: false,
    };

    /// Accumulation off: each frame's occlusion is used as it is (the sample pattern stands
    /// still, and no motion vectors are needed).
    pub const OFF: AoTemporal = AoTemporal {
        enabled: false,
        ..Self::ON
    };

    /// The history length actually used.
    pub fn frames(&self) -> u32 {
        self.max_frames.clamp(1, Self::MAX_FRAMES)
    }
}

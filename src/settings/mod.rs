//! The camera component, the technique it runs, how near and far field join, and the presets.

use bevy::ecs::component::Component;
use bevy::ecs::reflect::ReflectComponent;
use bevy::math::UVec2;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

// Each technique's settings live in its folder; they are named here too, beside the component
// that holds them.
pub use crate::fields::settings::FieldShading;
pub use crate::filter::settings::{
    AoBlur, DEFAULT_ACCUMULATED_BLUR_RADIUS, DEFAULT_BLUR_DETAIL_REACH,
    DEFAULT_BLUR_NORMAL_SHARPNESS, DEFAULT_BLUR_RADIUS, DEFAULT_BLUR_SHARPNESS,
    DEFAULT_VOXEL_ACCUMULATED_BLUR_RADIUS,
};
pub use crate::horizon::settings::{HorizonMode, HorizonParams};
pub use crate::near_field::settings::{DEFAULT_MAX_SAMPLES, DEFAULT_MIN_SAMPLES, NearFieldParams};
pub use crate::ray_march::settings::{DEFAULT_RAY_MARCH_THICKNESS, RayMarchParams};
pub use crate::temporal::settings::{AoTemporal, DEFAULT_TEMPORAL_FRAMES};
pub use preset::AoPreset;

mod preset;

/// Default world-space AO radius r_far, in metres.
pub const DEFAULT_RADIUS: f32 = 0.75;
/// Default reach of the image-space technique when far-field terms take part, metres: beyond it
/// the far field counts every occluder (see [`DynamicAo::near_field_radius`]).
pub const DEFAULT_NEAR_FIELD_RADIUS: f32 = 0.5;
/// Default multiplier applied to the summed occlusion (no unit).
pub const DEFAULT_INTENSITY: f32 = 1.0;
/// Default [`DynamicAo::small_viewport_pixels`]: 240 × 180. Above it, at half resolution, every
/// scene of the README's error table reads at most 0.29× Bevy's SSAO High's RMSE (the heat sink
/// and DamagedHelmet close up, 240 × 180, R = 0.73 m), and the AO passes cost 0.43–0.46× Bevy's
/// (256 × 192); at full resolution they cost 1.1–1.3× Bevy's at 240 × 180 and 1.3× at 320 × 240.
/// At 200 × 150 half resolution reads 0.33× on the heat sink (BENCHMARKS.md, "Half resolution
/// from 240 × 180 up").
pub const DEFAULT_SMALL_VIEWPORT_PIXELS: u32 = 240 * 180;
/// The blur's half-width under accumulation on a viewport that [`DynamicAo::half_resolution`]
/// asked to halve and [`DynamicAo::small_viewport_pixels`] kept at full resolution, where
/// [`AoBlur::accumulated_radius`] is 0, pixels. At half resolution the upsampling averages the
/// texels within 2.5 pixels of each pixel; at full resolution nothing would, and the rays'
/// noise stays (converged at 160 × 120, `toasters.glb` read 0.0234 RMSE and 0.0185
/// high-frequency error without it, 0.0157 and 0.0089 with it).
pub const SMALL_VIEWPORT_BLUR_RADIUS: u32 = 1;
/// Dynamic ambient occlusion for a 3D camera.
///
/// Put it on a `Camera3d`. It brings Bevy's depth and normal prepasses (through
/// [`ScreenSpaceAmbientOcclusion`], whose output texture is where the result goes, so Bevy's PBR
/// lighting applies it to ambient and indirect light only). Bevy's own SSAO pass is switched off
/// on that camera unless [`AoTechnique::BevySsao`] is chosen.
///
/// MSAA cameras get AO from every technique but [`AoTechnique::BevySsao`] (which Bevy runs
/// only on `Msaa::Off` cameras; with MSAA on it logs a warning and the camera renders without
/// AO): the passes read sample 0 of each pixel of the multisampled prepass. Cameras with a
/// viewport (split screen) and cameras rendering to an image work as any other.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone, Debug, PartialEq)]
#[require(ScreenSpaceAmbientOcclusion)]
pub struct DynamicAo {
    /// Which technique computes the occlusion. Default: [`AoTechnique::RayMarch`] (the
    /// technique of [`AoPreset::High`]).
    pub technique: AoTechnique,
    /// Parameters of [`AoTechnique::NearField`]: its sample budget and whether the back-face
    /// layer occludes. Default: [`NearFieldParams::default`] (the budget of [`AoPreset::High`]).
    pub near_field: NearFieldParams,
    /// R: the distance every term measures occlusion within. The result estimates what a ray
    /// tracer measures: the share of the cosine-weighted hemisphere whose rays hit geometry
    /// closer than R. Occluders farther than this are ignored by every technique (r_far of
    /// Shanmugam & Arikan eq. 4 for the near field, the reach of sphere occluders, the extent of
    /// baked AO fields, the ray length in voxel volumes).
    /// Units: metres (world units). Valid: > 0. Default: [`DEFAULT_RADIUS`].
    pub radius: f32,
    /// How far the image-space technique reaches when far-field terms take part under
    /// [`FarFieldBlend::CountOnce`]: it counts the occluders within `min(radius,
    /// near_field_radius)` that the ND-buffer shows, and the far-field terms count everything
    /// else within `radius`: occluders beyond this distance, and nearer ones the ND-buffer does
    /// not hold (off-screen, or hidden behind both of its layers). Image-space AO loses accuracy
    /// with distance (each of its samples stands for a patch that grows with it, and its contact
    /// shadows overlap); far-field proxies do not. With every mesh an occluder, a reach of 0.5 m
    /// measured lower error than 0.75 m on every scene of `cargo bench --bench far_field`, at
    /// R = 0.75 m and 2 m alike (0.35 m lower still on most, but not on characters in voxels).
    /// Joined to the default's ray march, voxel volumes of fine cells gain from a shorter reach
    /// (0.25 m: lower on 15 of 20 rows, higher on models with detail finer than a cell), spheres
    /// and fields do not (BENCHMARKS.md, "The near field's reach joined to the voxels").
    /// With no far-field occluder in the scene, or another blend, the image-space technique
    /// reaches the whole `radius`. Give every mesh that should occlude beyond this
    /// distance a far-field occluder (or cover it with a voxel volume).
    /// Units: metres. Valid: > 0. Default: [`DEFAULT_NEAR_FIELD_RADIUS`].
    pub near_field_radius: f32,
    /// Multiplier on the summed occlusion before clamping to [0, 1]. No unit.
    /// Valid: ≥ 0. Default: [`DEFAULT_INTENSITY`] (the formula as published).
    pub intensity: f32,
    /// Parameters of [`AoTechnique::Horizon`]. Default: [`HorizonParams::default`].
    pub horizon: HorizonParams,
    /// Parameters of [`AoTechnique::RayMarch`]. Default: [`RayMarchParams::default`].
    pub ray_march: RayMarchParams,
    /// Cross-bilateral blur of the occlusion (Bavoil & Sainz 2008). Default: [`AoBlur::default`].
    pub blur: AoBlur,
    /// Temporal accumulation of the image-space occlusion. Default: [`AoTemporal::default`]
    /// (on, as every [`AoPreset`] has it).
    pub temporal: AoTemporal,
    /// Compute the occlusion at half resolution in each axis and bring it back to full
    /// resolution with a joint bilateral upsampling over normals and the distance from each
    /// pixel's tangent plane (Reinbothe et al. 2009, eq. 5–7, over the texels of the 3 × 3 around
    /// each pixel's own within 2.5 pixels of it; [`crate::filter`] says where it departs from
    /// the paper); the blur, where it runs, then runs at full resolution. The sphere and field
    /// splats follow it (each texel evaluates one pixel of its 2 × 2; compose upsamples them
    /// over normals and positions). Default: `true` (as [`AoPreset::High`] has it). Viewports
    /// of at most [`small_viewport_pixels`](Self::small_viewport_pixels) run at full resolution
    /// all the same ([`half_resolution_at`](Self::half_resolution_at)).
    pub half_resolution: bool,
    /// Viewports of at most this many pixels (width × height) compute the occlusion at full
    /// resolution even where [`half_resolution`](Self::half_resolution) is on, and under
    /// accumulation blur it by [`SMALL_VIEWPORT_BLUR_RADIUS`] where
    /// [`AoBlur::accumulated_radius`] is 0, in place of the upsampling's averaging. There a
    /// half-resolution texel is too coarse for the detail a model shows (at 160 × 120 a heat
    /// sink's 8 mm fins read an RMSE of 0.068 against ground truth at half resolution, 0.044 at
    /// full; README, "Cost and error"). The price is the cost: at full resolution the passes
    /// cost about what half resolution's do on a viewport of four times as many pixels, more
    /// than Bevy's SSAO High does on the same one. Raise it where detail matters more than
    /// cost on larger views; `0` keeps half resolution at every size. Units: pixels. Default: [`DEFAULT_SMALL_VIEWPORT_PIXELS`]
    /// (240 × 180).
    pub small_viewport_pixels: u32,
    /// Add the far-field occlusion of every [`SphereOccluder`](crate::spheres::SphereOccluder)'s
    /// proxies in the scene (Shanmugam & Arikan 2007, §5), also from occluders that are
    /// off-screen or hidden. Works with every technique except [`AoTechnique::BevySsao`] (whose result Bevy
    /// writes itself); with [`AoTechnique::Off`] the far field is the whole occlusion.
    /// Default: `true` (a scene without sphere occluders costs one cleared buffer).
    pub spheres: bool,
    /// How the far field joins the image-space term. Default: [`FarFieldBlend::CountOnce`]:
    /// every occluder counted once.
    pub far_field_blend: FarFieldBlend,
    /// Add the occlusion of every [`AoField`](crate::fields::AoField) occluder (Malmer et al.
    /// 2005), also from occluders that are off-screen or hidden; it joins the far field. Not with
    /// [`AoTechnique::BevySsao`]. Default: `true`.
    pub fields: bool,
    /// How AO fields shade a receiver. Default: [`FieldShading::Cone`].
    pub field_shading: FieldShading,
    /// Add the occlusion sampled in the grids of every
    /// [`VoxelAoVolume`](crate::voxels::VoxelAoVolume) (Reinbothe et al. 2009), revoxelized every
    /// frame, so hidden, off-screen and deforming geometry inside a volume darkens what it
    /// surrounds; it joins the far field. Not with [`AoTechnique::BevySsao`]. Default: `true`.
    pub voxels: bool,
    /// Replace the lit image with the AO buffer (visibility, white = open), full screen.
    /// Default: `false`.
    pub debug_view: bool,
    /// Draw the back-face layer of rigid meshes of more than
    /// [`COARSE_BACK_FACES_ABOVE`](crate::nd_buffer::COARSE_BACK_FACES_ABOVE) triangles from a copy of a
    /// quarter of their triangles or fewer, clustered on a grid of about twice their mean edge.
    /// The layer bounds the solid behind the visible surface; a copy that strays by a cell moves
    /// it by less than the margin its readers already allow
    /// ([`RayMarchParams::thickness`] × R). Where the layer carries normals (the near field) and
    /// for skinned or morph-target meshes, the full mesh is drawn. Default: `true`.
    pub coarse_back_faces: bool,
}

impl Default for DynamicAo {
    fn default() -> Self {
        Self {
            technique: AoTechnique::default(),
            near_field: NearFieldParams::default(),
            radius: DEFAULT_RADIUS,
            near_field_radius: DEFAULT_NEAR_FIELD_RADIUS,
            intensity: DEFAULT_INTENSITY,
            horizon: HorizonParams::default(),
            ray_march: RayMarchParams::default(),
            blur: AoBlur::default(),
            temporal: AoTemporal::default(),
            half_resolution: true,
            small_viewport_pixels: DEFAULT_SMALL_VIEWPORT_PIXELS,
            spheres: true,
            far_field_blend: FarFieldBlend::CountOnce,
            fields: true,
            field_shading: FieldShading::Cone,
            voxels: true,
            debug_view: false,
            coarse_back_faces: true,
        }
    }
}

impl DynamicAo {
    /// The same settings with another technique.
    pub fn with_technique(mut self, technique: AoTechnique) -> Self {
        self.technique = technique;
        self
    }

    /// The same settings with other near-field parameters.
    pub fn with_near_field(mut self, near_field: NearFieldParams) -> Self {
        self.near_field = near_field;
        self
    }

    /// The same settings with other horizon-based AO parameters.
    pub fn with_horizon(mut self, horizon: HorizonParams) -> Self {
        self.horizon = horizon;
        self
    }

    /// The same settings with other ray-march parameters.
    pub fn with_ray_march(mut self, ray_march: RayMarchParams) -> Self {
        self.ray_march = ray_march;
        self
    }

    /// The same settings with another blur.
    pub fn with_blur(mut self, blur: AoBlur) -> Self {
        self.blur = blur;
        self
    }

    /// The same settings with another radius (metres).
    pub fn with_radius(mut self, radius: f32) -> Self {
        self.radius = radius;
        self
    }

    /// Whether these settings give AO on an MSAA camera: every technique but Bevy's SSAO does.
    pub fn works_with_msaa(&self) -> bool {
        self.technique != AoTechnique::BevySsao
    }

    /// Frames a still camera's image-space history takes to fill: 0 without accumulation,
    /// [`AoTemporal::max_frames`] samples otherwise, which span twice the frames where the ray
    /// march's [checkerboard](RayMarchParams::checkerboard) adds one to a texel every other frame.
    /// Twice this shows the accumulated occlusion converged.
    pub fn history_frames(&self) -> u32 {
        if !self.temporal.enabled {
            return 0;
        }
        self.temporal.frames() * if self.marches_checkerboard() { 2 } else { 1 }
    }

    /// Whether the ray march runs, accumulated, marching one texel of two each frame
    /// ([`RayMarchParams::checkerboard`]).
    pub fn marches_checkerboard(&self) -> bool {
        self.technique == AoTechnique::RayMarch
            && self.temporal.enabled
            && self.ray_march.checkerboard
    }

    /// The radius actually used: non-finite or non-positive values fall back to the default.
    pub fn effective_radius(&self) -> f32 {
        if self.radius.is_finite() && self.radius > 0.0 {
            self.radius
        } else {
            DEFAULT_RADIUS
        }
    }

    /// The near-field radius actually used: non-finite or non-positive values fall back to the
    /// default.
    pub fn effective_near_field_radius(&self) -> f32 {
        if self.near_field_radius.is_finite() && self.near_field_radius > 0.0 {
            self.near_field_radius
        } else {
            DEFAULT_NEAR_FIELD_RADIUS
        }
    }

    /// What is out of range in these settings and what is used instead, one line each (empty
    /// when every value is valid). The plugin logs each line once per camera.
    pub fn problems(&self) -> Vec<String> {
        let used = (
            self.effective_radius(),
            self.effective_near_field_radius(),
            self.effective_intensity(),
            self.near_field.sanitized(),
            self.horizon.sanitized(),
            self.ray_march.sanitized(),
            self.blur.sanitized(),
            self.temporal.frames(),
        );
        // Compared as printed: a NaN differs from any replacement, as it should.
        let values: [(&str, &dyn std::fmt::Debug, &dyn std::fmt::Debug); 8] = [
            ("radius", &self.radius, &used.0),
            ("near_field_radius", &self.near_field_radius, &used.1),
            ("intensity", &self.intensity, &used.2),
            ("near_field", &self.near_field, &used.3),
            ("horizon", &self.horizon, &used.4),
            ("ray_march", &self.ray_march, &used.5),
            ("blur", &self.blur, &used.6),
            ("temporal.max_frames", &self.temporal.max_frames, &used.7),
        ];
        values
            .into_iter()
            .filter_map(|(name, set, used)| {
                let (set, used) = (format!("{set:?}"), format!("{used:?}"));
                (set != used).then(|| format!("{name} {set} is out of range; using {used}"))
            })
            .collect()
    }

    /// Whether a viewport of `size` pixels computes the occlusion at half resolution:
    /// [`half_resolution`](Self::half_resolution) is on and the viewport has more than
    /// [`small_viewport_pixels`](Self::small_viewport_pixels) pixels.
    pub fn half_resolution_at(&self, size: UVec2) -> bool {
        self.half_resolution
            && u64::from(size.x) * u64::from(size.y) > u64::from(self.small_viewport_pixels)
    }

    /// The intensity actually used: non-finite or negative values fall back to the default.
    pub fn effective_intensity(&self) -> f32 {
        if self.intensity.is_finite() && self.intensity >= 0.0 {
            self.intensity
        } else {
            DEFAULT_INTENSITY
        }
    }
}

/// How near-field (image-space) and far-field (spheres, AO fields, voxel volumes) occlusion
/// combine.
///
/// An occluder on screen and close by is seen by both the image-space technique and the far-field
/// proxies, so adding the two terms counts it twice (on our test scenes that made the image worse
/// than the near field alone). [`CountOnce`](Self::CountOnce) gives every occluder to one term:
/// the image-space technique counts what the ND-buffer shows within
/// [`DynamicAo::near_field_radius`], the far-field terms count the rest.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq, Hash)]
pub enum FarFieldBlend {
    /// Each occluder counted once: the far-field terms leave out the occluders the ND-buffer
    /// holds (on screen, in front of or between its two layers) within the near field's reach,
    /// and the two terms join as independent occluders, 1 − (1 − near)(1 − far).
    #[default]
    CountOnce,
    /// near + far, clamped to 1, with the far field counting every occluder (Shanmugam & Arikan
    /// 2007, §6): occluders in view count twice.
    Add,
    /// max(near, far), with the far field counting every occluder: never counts an occluder
    /// twice, but two different occluders of one pixel only count once.
    Max,
}

impl FarFieldBlend {
    /// The value the compose shader switches on.
    pub(crate) fn shader_index(self) -> u32 {
        match self {
            FarFieldBlend::Add => 0,
            FarFieldBlend::Max => 1,
            FarFieldBlend::CountOnce => 2,
        }
    }

    /// Every blend with the name `ao_capture --far-blend` takes for it.
    pub const ALL: [(&'static str, FarFieldBlend); 3] = [
        ("count-once", FarFieldBlend::CountOnce),
        ("add", FarFieldBlend::Add),
        ("max", FarFieldBlend::Max),
    ];

    /// The blend with this command-line name, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
    }
}

/// The technique that computes a camera's ambient occlusion.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq, Hash)]
pub enum AoTechnique {
    /// No image-space occlusion; the far field of sphere occluders still applies when
    /// [`DynamicAo::spheres`] is on (with it off, visibility is 1 everywhere).
    Off,
    /// Image-space near-field AO from the two-layer ND-buffer (Shanmugam & Arikan 2007, §4).
    NearField,
    /// Horizon-based AO on the front layer (Bavoil & Sainz 2008).
    Horizon,
    /// Rays marched through both ND-buffer layers (Bavoil & Sainz 2008): cosine-weighted rays
    /// that count a hit within R, what a ray tracer measures. With a few rays per frame,
    /// accumulated over frames, it is the default (see [`AoPreset`]).
    #[default]
    RayMarch,
    /// Bevy's built-in SSAO, left running unchanged (for comparison).
    BevySsao,
}

impl AoTechnique {
    /// Every technique with the name `ao_capture --technique` takes for it.
    pub const ALL: [(&'static str, AoTechnique); 5] = [
        ("none", AoTechnique::Off),
        ("near-field", AoTechnique::NearField),
        ("horizon", AoTechnique::Horizon),
        ("ray-march", AoTechnique::RayMarch),
        ("bevy-ssao", AoTechnique::BevySsao),
    ];

    /// The technique with this command-line name, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
    }

    /// Whether this is one of the plugin's image-space techniques (near field, horizon, ray
    /// march): the ones temporal accumulation, half resolution and the blur apply to.
    pub fn is_image_space(self) -> bool {
        matches!(
            self,
            AoTechnique::NearField | AoTechnique::Horizon | AoTechnique::RayMarch
        )
    }

    /// The command-line name of this technique.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, t)| *t == self)
            .map(|(n, _)| *n)
            .unwrap_or("none")
    }
}

#[cfg(test)]
mod documented_defaults;
#[cfg(test)]
mod tests;

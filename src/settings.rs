//! The camera component and its quality presets.

use bevy::ecs::component::Component;
use bevy::ecs::reflect::ReflectComponent;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Default world-space AO radius r_far, in metres.
pub const DEFAULT_RADIUS: f32 = 0.75;
/// Default reach of the image-space technique when far-field terms take part, metres: beyond it
/// the far field counts every occluder (see [`DynamicAo::near_field_radius`]).
pub const DEFAULT_NEAR_FIELD_RADIUS: f32 = 0.5;
/// Default multiplier applied to the summed occlusion (no unit).
pub const DEFAULT_INTENSITY: f32 = 1.0;
/// Default half-width of the cross-bilateral blur, pixels.
pub const DEFAULT_BLUR_RADIUS: u32 = 4;
/// Default depth sharpness of the cross-bilateral blur (no unit).
pub const DEFAULT_BLUR_SHARPNESS: f32 = 16.0;

/// Dynamic ambient occlusion for a 3D camera.
///
/// Put it on a `Camera3d`. It brings Bevy's depth and normal prepasses (through
/// [`ScreenSpaceAmbientOcclusion`], whose output texture is where the result goes, so Bevy's PBR
/// lighting applies it to ambient and indirect light only). Bevy's own SSAO pass is switched off
/// on that camera unless [`AoTechnique::BevySsao`] is chosen.
///
/// The camera must use `Msaa::Off`; on an MSAA camera the plugin logs a warning and renders
/// without AO.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone, Debug, PartialEq)]
#[require(ScreenSpaceAmbientOcclusion)]
pub struct DynamicAo {
    /// Which technique computes the occlusion. Default: [`AoTechnique::NearField`].
    pub technique: AoTechnique,
    /// Sample budget of the near-field pass. Default: [`AoQuality::High`].
    pub quality: AoQuality,
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
    /// Compute the occlusion at half resolution in each axis and bring it back to full
    /// resolution with a joint bilateral upsampling over normals, positions and AO (Reinbothe et
    /// al. 2009, eq. 5–7); the blur then runs at full resolution. Default: `false`.
    pub half_resolution: bool,
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
}

impl Default for DynamicAo {
    fn default() -> Self {
        Self {
            technique: AoTechnique::default(),
            quality: AoQuality::default(),
            radius: DEFAULT_RADIUS,
            near_field_radius: DEFAULT_NEAR_FIELD_RADIUS,
            intensity: DEFAULT_INTENSITY,
            horizon: HorizonParams::default(),
            ray_march: RayMarchParams::default(),
            blur: AoBlur::default(),
            half_resolution: false,
            spheres: true,
            far_field_blend: FarFieldBlend::CountOnce,
            fields: true,
            field_shading: FieldShading::Cone,
            voxels: true,
            debug_view: false,
        }
    }
}

impl DynamicAo {
    /// A complete configuration: technique and parameters chosen together, from cheapest to
    /// most accurate. The table in the README gives each one's cost and error.
    pub fn from_preset(preset: AoPreset) -> Self {
        let base = Self::default();
        match preset {
            AoPreset::Low => Self {
                technique: AoTechnique::Horizon,
                horizon: HorizonParams {
                    directions: 4,
                    steps: 4,
                    mode: HorizonMode::Low,
                    ..HorizonParams::default()
                },
                half_resolution: true,
                ..base
            },
            AoPreset::Medium => Self {
                technique: AoTechnique::Horizon,
                horizon: HorizonParams {
                    mode: HorizonMode::Low,
                    ..HorizonParams::default()
                },
                ..base
            },
            AoPreset::High => Self {
                technique: AoTechnique::NearField,
                quality: AoQuality::High,
                ..base
            },
            AoPreset::Ultra => Self {
                technique: AoTechnique::RayMarch,
                ..base
            },
        }
    }

    /// The same settings with another technique.
    pub fn with_technique(mut self, technique: AoTechnique) -> Self {
        self.technique = technique;
        self
    }

    /// The same settings with another quality preset.
    pub fn with_quality(mut self, quality: AoQuality) -> Self {
        self.quality = quality;
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

    /// The intensity actually used: non-finite or negative values fall back to the default.
    pub fn effective_intensity(&self) -> f32 {
        if self.intensity.is_finite() && self.intensity >= 0.0 {
            self.intensity
        } else {
            DEFAULT_INTENSITY
        }
    }
}

/// Separable cross-bilateral blur of the occlusion buffer, X then Y (Bavoil & Sainz 2008,
/// "Cross Bilateral Filter"): a Gaussian in image space whose weights fall with the difference in
/// view depth, so occlusion does not bleed across silhouettes.
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct AoBlur {
    /// Half-width of the kernel; the kernel is `2 * radius + 1` pixels wide per pass and its
    /// Gaussian has σ = (radius + 1) / 2. Units: pixels. Valid: 0 (off) ..= 16.
    /// Default: [`DEFAULT_BLUR_RADIUS`].
    pub radius: u32,
    /// How fast a sample's weight falls with its depth difference, relative to the centre
    /// pixel's depth: weight × exp(−(sharpness · Δz / z)²). 0 is a plain Gaussian. No unit.
    /// Valid: ≥ 0. Default: [`DEFAULT_BLUR_SHARPNESS`].
    pub sharpness: f32,
}

impl Default for AoBlur {
    fn default() -> Self {
        Self {
            radius: DEFAULT_BLUR_RADIUS,
            sharpness: DEFAULT_BLUR_SHARPNESS,
        }
    }
}

impl AoBlur {
    /// Largest radius the blur accepts.
    pub const MAX_RADIUS: u32 = 16;

    /// No blur.
    pub const OFF: AoBlur = AoBlur {
        radius: 0,
        sharpness: DEFAULT_BLUR_SHARPNESS,
    };

    /// The same blur clamped into its valid ranges (a bad sharpness becomes the default).
    pub fn sanitized(&self) -> Self {
        Self {
            radius: self.radius.min(Self::MAX_RADIUS),
            sharpness: if self.sharpness.is_finite() && self.sharpness >= 0.0 {
                self.sharpness
            } else {
                DEFAULT_BLUR_SHARPNESS
            },
        }
    }
}

/// Complete configurations for [`DynamicAo::from_preset`].
#[derive(Reflect, Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[reflect(Clone, Debug, PartialEq, Hash)]
pub enum AoPreset {
    /// Horizon-based AO, low mode, 4 directions × 4 steps, at half resolution.
    Low,
    /// Horizon-based AO, low mode, 8 directions × 8 steps, full resolution.
    Medium,
    /// Two-layer near-field AO, 32 samples per pixel and layer (the [`DynamicAo`] default).
    High,
    /// The ray-marched reference, 8 × 4 rays × 8 steps.
    Ultra,
}

impl AoPreset {
    /// Every preset, from cheapest to most accurate.
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
}

/// How an AO field turns its stored occlusion into the share of a receiver's ambient light it
/// blocks (Malmer et al. 2005).
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq, Hash)]
pub enum FieldShading {
    /// The cone of occluded directions clipped by the receiver's tangent plane, with the
    /// diffuse cosine: T_clip(a, cos β) (§3.3.1). Also right on the object's own surface.
    #[default]
    Cone,
    /// Twice the blocked share of the sphere, 2a (§3.2): cheaper, ignores the receiver's
    /// normal, and darkens the object's own surface.
    OcclusionOnly,
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
    #[default]
    NearField,
    /// Horizon-based AO on the front layer (Bavoil & Sainz 2008).
    Horizon,
    /// Brute-force rays marched through both ND-buffer layers: the in-engine reference.
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

    /// The command-line name of this technique.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, t)| *t == self)
            .map(|(n, _)| *n)
            .unwrap_or("none")
    }
}

/// Parameters of horizon-based AO (Bavoil & Sainz 2008, "Horizon-Based Ambient Occlusion").
/// The radius is [`DynamicAo::radius`].
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

/// Parameters of the ray-marched reference (Bavoil & Sainz 2008, "Ray-Marched Ambient
/// Occlusion"): `directions × rays_per_direction` cosine-weighted rays around the normal, each
/// marched in `steps` equal steps over the radius R ([`DynamicAo::radius`]). A step is blocked
/// where it lies behind the front layer and in front of the back-face layer (or, where no back
/// face was drawn, less than R behind the front layer).
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct RayMarchParams {
    /// Azimuths around the normal, randomly rotated per pixel. Valid: 1..=64. Default: 8.
    pub directions: u32,
    /// Elevations per azimuth, stratified for a cosine-weighted hemisphere. Valid: 1..=64.
    /// Default: 4.
    pub rays_per_direction: u32,
    /// Samples per ray. Valid: 1..=64. Default: 8.
    pub steps: u32,
}

impl Default for RayMarchParams {
    fn default() -> Self {
        Self {
            directions: 8,
            rays_per_direction: 4,
            steps: 8,
        }
    }
}

impl RayMarchParams {
    /// The same parameters clamped into their valid ranges.
    pub fn sanitized(&self) -> Self {
        Self {
            directions: self.directions.clamp(1, 64),
            rays_per_direction: self.rays_per_direction.clamp(1, 64),
            steps: self.steps.clamp(1, 64),
        }
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_match_the_documentation() {
        let ao = DynamicAo::default();
        assert_eq!(ao.radius, DEFAULT_RADIUS);
        assert_eq!(ao.near_field_radius, DEFAULT_NEAR_FIELD_RADIUS);
        assert_eq!(ao.far_field_blend, FarFieldBlend::CountOnce);
        assert_eq!(ao.intensity, DEFAULT_INTENSITY);
        assert_eq!(ao.technique, AoTechnique::NearField);
        assert_eq!(ao.quality, AoQuality::High);
        assert_eq!(AoQuality::High.params(), NearFieldParams::default());
        assert_eq!(ao.blur.radius, DEFAULT_BLUR_RADIUS);
        assert_eq!(ao.horizon, HorizonParams::default());
        assert_eq!(ao.horizon.sanitized(), HorizonParams::default());
        assert_eq!(ao.blur.sharpness, DEFAULT_BLUR_SHARPNESS);
        assert!(!ao.debug_view);
    }

    #[test]
    fn high_preset_is_the_default() {
        assert_eq!(DynamicAo::from_preset(AoPreset::High), DynamicAo::default());
        let techniques: Vec<AoTechnique> = AoPreset::ALL
            .iter()
            .map(|p| DynamicAo::from_preset(*p).technique)
            .collect();
        assert_eq!(
            techniques,
            [
                AoTechnique::Horizon,
                AoTechnique::Horizon,
                AoTechnique::NearField,
                AoTechnique::RayMarch
            ]
        );
    }

    #[test]
    fn presets_grow_in_cost() {
        let samples: Vec<u32> = AoQuality::PRESETS
            .iter()
            .map(|q| q.params().max_samples)
            .collect();
        assert!(samples.windows(2).all(|w| w[0] < w[1]), "{samples:?}");
    }

    #[test]
    fn bad_values_fall_back() {
        let ao = DynamicAo {
            radius: f32::NAN,
            intensity: -1.0,
            ..default()
        };
        assert_eq!(ao.effective_radius(), DEFAULT_RADIUS);
        assert_eq!(ao.effective_intensity(), DEFAULT_INTENSITY);
        let p = AoQuality::Custom(NearFieldParams {
            max_samples: 0,
            min_samples: 99,
            back_layer: false,
        })
        .params();
        assert_eq!((p.max_samples, p.min_samples), (1, 1));
        let blur = AoBlur {
            radius: 99,
            sharpness: f32::NAN,
        }
        .sanitized();
        assert_eq!(blur.radius, AoBlur::MAX_RADIUS);
        assert_eq!(blur.sharpness, DEFAULT_BLUR_SHARPNESS);
    }

    #[test]
    fn names_round_trip() {
        for (name, t) in AoTechnique::ALL {
            assert_eq!(AoTechnique::from_name(name), Some(t));
            assert_eq!(t.name(), name);
        }
        for q in AoQuality::PRESETS {
            assert_eq!(AoQuality::from_name(q.name()), Some(q));
        }
        assert_eq!(AoTechnique::from_name("nope"), None);
    }

    fn default<T: Default>() -> T {
        T::default()
    }
}

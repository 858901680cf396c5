//! The command line of `ao_capture`.

use std::path::PathBuf;

use bevy_dynamic_ao::voxels::VoxelFalloff;
use bevy_dynamic_ao::{
    AoBlur, AoPreset, AoTechnique, AoTemporal, DynamicAo, FarFieldBlend, RayMarchParams,
};

use crate::common::{parse_between, parse_number};
pub use crate::far_terms::FarTerm;

pub const USAGE: &str = "usage: ao_capture --scene FILE.glb --width W --height H --radius R \
--technique NAME [--preset low|medium|high|ultra] [--blur PIXELS] [--accumulated-blur PIXELS] [--voxel-accumulated-blur PIXELS] [--blur-sharpness S] [--blur-normal-sharpness S] [--blur-detail PIXELS] [--thickness F] [--full-back-faces] [--half-res] [--far-blend count-once|add|max] [--near-field-radius M] \
[--voxel-falloff none|wendland] [--frames N] [--time SECONDS] [--temporal|--no-temporal] [--history-frames N] [--msaa 1|4] [--timings] --out-ao AO.png [--out-color COLOR.png] [--compare SIDE_BY_SIDE.png] [--out-truth TRUTH.png]
       ao_capture --technique list";

/// Largest image side every wgpu adapter supports (`max_texture_dimension_2d` default), pixels.
const MAX_SIZE: u32 = 8192;

/// Every name `--technique` takes: the plugin's techniques, each far-field term alone, and each
/// image-space technique with a far-field term added.
pub fn technique_names() -> Vec<String> {
    let mut names: Vec<String> = std::iter::once(DEFAULT_TECHNIQUE)
        .chain(AoTechnique::ALL.iter().map(|(n, _)| *n))
        .map(str::to_string)
        .collect();
    names.extend(FarTerm::ALL.map(|term| term.name().to_string()));
    names.extend(FarTerm::ALL.map(|term| format!("{DEFAULT_TECHNIQUE}+{}", term.name())));
    for (name, technique) in AoTechnique::ALL {
        if !matches!(technique, AoTechnique::Off | AoTechnique::BevySsao) {
            names.extend(FarTerm::ALL.map(|term| format!("{name}+{}", term.name())));
        }
    }
    names
}

/// What `--technique default` or `default+TERM` asks for: the far-field term, if any; `None`
/// for any other name.
fn parse_default(name: &str) -> Option<Option<FarTerm>> {
    match name.split_once('+') {
        None => (name == DEFAULT_TECHNIQUE).then_some(None),
        Some((DEFAULT_TECHNIQUE, far)) => FarTerm::from_name(far).map(Some),
        Some(_) => None,
    }
}

/// What a technique name asks for: the image-space technique and the far-field term.
fn parse_technique(name: &str) -> Option<(AoTechnique, Option<FarTerm>)> {
    if let Some(term) = FarTerm::from_name(name) {
        return Some((AoTechnique::Off, Some(term)));
    }
    let (base, far) = match name.split_once('+') {
        Some((base, far)) => (base, Some(far)),
        None => (name, None),
    };
    let technique = AoTechnique::from_name(base)?;
    match far {
        None => Some((technique, None)),
        Some(_) if matches!(technique, AoTechnique::Off | AoTechnique::BevySsao) => None,
        Some(far) => Some((technique, Some(FarTerm::from_name(far)?))),
    }
}

/// The `--technique` name of what `DynamicAo::from_preset(--preset)` runs (with the default
/// preset, what `DynamicAo::default()` runs).
pub const DEFAULT_TECHNIQUE: &str = "default";

/// What one capture does.
#[derive(Clone, Debug)]
pub struct Options {
    pub scene: PathBuf,
    pub width: u32,
    pub height: u32,
    /// World-space AO radius, metres.
    pub radius: f32,
    pub technique: AoTechnique,
    /// `--technique default` (or `default+TERM`): everything as `DynamicAo::from_preset(preset)`
    /// sets it (with the far-field term).
    pub default_technique: bool,
    /// The far-field term, if any.
    pub far: Option<FarTerm>,
    /// How the far-field term joins the image-space one.
    pub far_blend: FarFieldBlend,
    /// Reach of the image-space technique where a far-field term counts the rest
    /// (`DynamicAo::near_field_radius`), metres.
    pub near_field_radius: f32,
    /// Distance falloff of the voxel volume's hits.
    pub voxel_falloff: VoxelFalloff,
    /// The level of every technique's sample budget.
    pub preset: AoPreset,
    /// Half-width of the cross-bilateral blur without accumulation, pixels (0 = off).
    pub blur: u32,
    /// Half-width of the cross-bilateral blur under accumulation (`AoBlur::accumulated_radius`),
    /// pixels (0 = off).
    pub accumulated_blur: u32,
    /// Half-width of the voxel term's blur under accumulation
    /// (`AoBlur::voxel_accumulated_radius`), pixels (0 = off).
    pub voxel_accumulated_blur: u32,
    /// Depth sharpness of the cross-bilateral blur (`AoBlur::sharpness`, no unit).
    pub blur_sharpness: f32,
    /// Normal sharpness of the cross-bilateral blur (`AoBlur::normal_sharpness`, no unit).
    pub blur_normal_sharpness: f32,
    /// Reach of the blur's fine-detail term (`AoBlur::detail_reach`), pixels (0 = off).
    pub blur_detail: u32,
    /// How far behind the back-face layer the ray march's steps count as blocked, a fraction of
    /// R (`RayMarchParams::thickness`).
    pub thickness: f32,
    /// Draw the back-face layer from every mesh as it is, without coarse copies
    /// (`DynamicAo::coarse_back_faces` off).
    pub full_back_faces: bool,
    /// Compute the occlusion at half resolution and upsample it, at every size
    /// (`DynamicAo::small_viewport_pixels` 0).
    pub half_resolution: bool,
    /// Frames rendered with a still camera before the capture, counted from the frame the scene
    /// is ready (default: 4, or where the occlusion is accumulated twice
    /// `DynamicAo::history_frames`, so the capture shows it converged).
    pub frames: u32,
    /// Animation time of the scene's first animation, seconds.
    pub time: f32,
    /// Accumulate the image-space occlusion over the frames: the level's choice, or
    /// `--temporal` / `--no-temporal`; `--history-frames` sets `AoTemporal::max_frames`.
    pub temporal: AoTemporal,
    /// Print the mean GPU time of the AO passes and of all passes after the capture.
    pub timings: bool,
    /// The camera's MSAA samples per pixel (1 = off).
    pub msaa: u32,
    pub out_ao: PathBuf,
    pub out_color: Option<PathBuf>,
    /// Where the CPU ray tracer's visibility at the same view goes.
    pub out_truth: Option<PathBuf>,
    /// Where ours, Bevy's SSAO and no AO go, lit, side by side.
    pub compare: Option<PathBuf>,
}

impl Options {
    /// The technique as `--technique` names it.
    pub fn technique_name(&self) -> String {
        let far = self.far.map(FarTerm::name);
        match (self.technique, far) {
            _ if self.default_technique => match far {
                Some(far) => format!("{DEFAULT_TECHNIQUE}+{far}"),
                None => DEFAULT_TECHNIQUE.into(),
            },
            (AoTechnique::Off, Some(far)) => far.into(),
            (technique, Some(far)) => format!("{}+{far}", technique.name()),
            (technique, None) => technique.name().into(),
        }
    }

    /// `Ok(None)`: a listing or help was printed, nothing to render.
    pub fn parse(args: impl IntoIterator<Item = String>) -> Result<Option<Self>, String> {
        let (mut scene, mut width, mut height, mut radius, mut technique) =
            (None, None, None, None, None);
        let (mut preset, mut frames, mut time) = (AoPreset::default(), None, 0.0f32);
        let mut blur = AoBlur::default().radius;
        let mut accumulated_blur = AoBlur::default().accumulated_radius;
        let mut voxel_accumulated_blur = AoBlur::default().voxel_accumulated_radius;
        let mut blur_sharpness = AoBlur::default().sharpness;
        let mut blur_normal_sharpness = AoBlur::default().normal_sharpness;
        let mut blur_detail = AoBlur::default().detail_reach;
        let mut thickness = RayMarchParams::default().thickness;
        let mut half_resolution = false;
        let mut full_back_faces = false;
        let (mut default_technique, mut timings, mut temporal) = (false, false, None);
        let mut far_blend = FarFieldBlend::default();
        let mut near_field_radius = DynamicAo::default().near_field_radius;
        let mut voxel_falloff = VoxelFalloff::default();
        let (mut out_ao, mut out_color, mut compare) = (None, None, None);
        let mut out_truth = None;
        let mut msaa = 1;
        let mut history_frames = None;
        let mut args = args.into_iter();
        while let Some(flag) = args.next() {
            let mut value = || args.next().ok_or_else(|| format!("{flag} needs a value"));
            match flag.as_str() {
                "--scene" => scene = Some(PathBuf::from(value()?)),
                "--width" => width = Some(parse_number("--width", &value()?, 1u32)?),
                "--height" => height = Some(parse_number("--height", &value()?, 1u32)?),
                "--radius" => {
                    let text = value()?;
                    radius = Some(
                        text.parse::<f32>()
                            .ok()
                            .filter(|r| r.is_finite() && *r > 0.0)
                            .ok_or(format!("--radius takes a positive number, got '{text}'"))?,
                    );
                }
                "--technique" => {
                    let name = value()?;
                    if name == "list" {
                        for name in technique_names() {
                            println!("{name}");
                        }
                        return Ok(None);
                    }
                    let default_far = parse_default(&name);
                    default_technique = default_far.is_some();
                    if let Some(far) = default_far {
                        technique = Some((AoTechnique::default(), far));
                        continue;
                    }
                    technique = Some(parse_technique(&name).ok_or(format!(
                        "unknown technique '{name}' (known: {})",
                        technique_names().join(", ")
                    ))?);
                }
                "--preset" => {
                    let name = value()?;
                    preset = AoPreset::from_name(&name).ok_or(format!(
                        "unknown preset '{name}' (known: low, medium, high, ultra)"
                    ))?;
                }
                "--half-res" => half_resolution = true,
                "--timings" => timings = true,
                "--temporal" => temporal = Some(AoTemporal::ON),
                "--no-temporal" => temporal = Some(AoTemporal::OFF),
                "--history-frames" => {
                    history_frames =
                        Some(parse_between(&flag, &value()?, 1, AoTemporal::MAX_FRAMES)?);
                }
                "--far-blend" => {
                    let name = value()?;
                    far_blend = FarFieldBlend::from_name(&name).ok_or(format!(
                        "--far-blend takes count-once, add or max, got '{name}'"
                    ))?;
                }
                "--near-field-radius" => {
                    let text = value()?;
                    near_field_radius = text
                        .parse::<f32>()
                        .ok()
                        .filter(|r| r.is_finite() && *r > 0.0)
                        .ok_or(format!(
                            "--near-field-radius takes a positive number, got '{text}'"
                        ))?;
                }
                "--voxel-falloff" => {
                    voxel_falloff = match value()?.as_str() {
                        "none" => VoxelFalloff::None,
                        "wendland" => VoxelFalloff::Wendland,
                        other => {
                            return Err(format!(
                                "--voxel-falloff takes none or wendland, got '{other}'"
                            ));
                        }
                    }
                }
                "--frames" => frames = Some(parse_number("--frames", &value()?, 1u32)?),
                "--blur" => blur = parse_between(&flag, &value()?, 0, AoBlur::MAX_RADIUS)?,
                "--accumulated-blur" => {
                    accumulated_blur = parse_between(&flag, &value()?, 0, AoBlur::MAX_RADIUS)?;
                }
                "--voxel-accumulated-blur" => {
                    voxel_accumulated_blur =
                        parse_between(&flag, &value()?, 0, AoBlur::MAX_RADIUS)?;
                }
                "--blur-sharpness" => {
                    blur_sharpness = parse_number("--blur-sharpness", &value()?, 0.0f32)?;
                    if blur_sharpness.is_infinite() {
                        return Err("--blur-sharpness takes a finite number".to_string());
                    }
                }
                "--blur-normal-sharpness" => {
                    blur_normal_sharpness =
                        parse_number("--blur-normal-sharpness", &value()?, 0.0f32)?;
                    if blur_normal_sharpness.is_infinite() {
                        return Err("--blur-normal-sharpness takes a finite number".to_string());
                    }
                }
                "--blur-detail" => {
                    blur_detail = parse_between(&flag, &value()?, 0, AoBlur::MAX_DETAIL_REACH)?;
                }
                // A fraction of R.
                "--thickness" => thickness = parse_between(&flag, &value()?, 0.0, 1.0)?,
                "--full-back-faces" => full_back_faces = true,
                "--time" => {
                    let text = value()?;
                    time = text
                        .parse::<f32>()
                        .ok()
                        .filter(|t| t.is_finite() && *t >= 0.0)
                        .ok_or(format!(
                            "--time takes a number of seconds ≥ 0, got '{text}'"
                        ))?;
                }
                "--msaa" => {
                    let text = value()?;
                    msaa = text
                        .parse::<u32>()
                        .ok()
                        .filter(|n| [1, 4].contains(n))
                        .ok_or(format!(
                            "--msaa takes 1 or 4 samples (the counts every GPU supports), \
                             got '{text}'"
                        ))?;
                }
                "--out-ao" => out_ao = Some(PathBuf::from(value()?)),
                "--out-color" => out_color = Some(PathBuf::from(value()?)),
                "--out-truth" => out_truth = Some(PathBuf::from(value()?)),
                "--compare" => compare = Some(PathBuf::from(value()?)),
                "--help" | "-h" => {
                    println!("{USAGE}");
                    return Ok(None);
                }
                other => return Err(format!("unknown argument '{other}' (see --help)")),
            }
        }
        let missing = |name: &str| format!("{name} is required (see --help)");
        for (flag, value) in [("--width", width), ("--height", height)] {
            if value.is_some_and(|v| v > MAX_SIZE) {
                return Err(format!(
                    "{flag} is at most {MAX_SIZE} pixels (a GPU texture limit)"
                ));
            }
        }
        if msaa > 1 && compare.is_some() {
            return Err(
                "--compare needs --msaa 1: Bevy's SSAO does not run on MSAA cameras".into(),
            );
        }
        if msaa > 1 && technique.is_some_and(|(t, _)| t == AoTechnique::BevySsao) {
            return Err(
                "bevy-ssao needs --msaa 1: Bevy's SSAO does not run on MSAA cameras".into(),
            );
        }
        let scene = scene.ok_or_else(|| missing("--scene"))?;
        if !scene.is_file() {
            return Err(format!("scene file {} not found", scene.display()));
        }
        // Bevy's asset server wants an absolute folder to load from.
        let scene =
            std::fs::canonicalize(&scene).map_err(|e| format!("{}: {e}", scene.display()))?;
        let image_technique = technique.map(|(t, _)| match default_technique {
            true => preset.technique(),
            false => t,
        });
        let temporal = AoTemporal {
            max_frames: history_frames.unwrap_or(preset.temporal().max_frames),
            ..temporal.unwrap_or(preset.temporal())
        };
        Ok(Some(Options {
            scene,
            width: width.ok_or_else(|| missing("--width"))?,
            height: height.ok_or_else(|| missing("--height"))?,
            radius: radius.ok_or_else(|| missing("--radius"))?,
            technique: image_technique.ok_or_else(|| missing("--technique"))?,
            default_technique,
            timings,
            msaa,
            temporal,
            far: technique.and_then(|(_, far)| far),
            far_blend,
            near_field_radius,
            voxel_falloff,
            preset,
            blur,
            accumulated_blur,
            voxel_accumulated_blur,
            blur_sharpness,
            blur_normal_sharpness,
            blur_detail,
            thickness,
            full_back_faces,
            half_resolution,
            frames: frames.unwrap_or_else(|| {
                let ao = DynamicAo {
                    technique: image_technique.unwrap_or_default(),
                    ray_march: preset.ray_march(),
                    temporal,
                    ..DynamicAo::default()
                };
                match ao.history_frames() {
                    0 => 4,
                    history => 2 * history,
                }
            }),
            time,
            out_ao: out_ao.ok_or_else(|| missing("--out-ao"))?,
            out_color,
            out_truth,
            compare,
        }))
    }
}

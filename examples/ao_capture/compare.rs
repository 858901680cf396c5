//! `--compare FILE.png`: the capture's lit image beside the same view with Bevy's SSAO (High) and
//! with no AO, side by side in one PNG. Two more cameras follow the scene's camera (children of
//! it, with its projection), each rendering into an image of its own.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};

/// White pixels between the images.
const GAP: u32 = 4;

/// One captured image: width, height and RGBA8 rows.
type Shot = (u32, u32, Vec<u8>);

/// The three images of a comparison and where they go.
pub struct Compare {
    out: PathBuf,
    /// Ours, Bevy's SSAO, no AO.
    targets: [Handle<Image>; 3],
    shots: Arc<Mutex<[Option<Shot>; 3]>>,
}

impl Compare {
    /// Spawns the Bevy's-SSAO and no-AO cameras under `camera`, which renders ours into `ours`;
    /// `lit` is what every camera gets besides (tonemapping, ambient light).
    pub fn spawn_peers(
        commands: &mut Commands,
        images: &mut Assets<Image>,
        camera: Entity,
        projection: Projection,
        ours: Handle<Image>,
        size: UVec2,
        lit: impl Bundle + Clone,
        out: PathBuf,
    ) -> Self {
        let mut targets = [ours, Handle::default(), Handle::default()];
        for (order, target) in targets.iter_mut().enumerate().skip(1) {
            *target = images.add(Image::new_target_texture(
                size.x,
                size.y,
                TextureFormat::Rgba8UnormSrgb,
                None,
            ));
            let mut peer = commands.spawn((
                Camera3d::default(),
                Camera {
                    order: order as isize,
                    ..default()
                },
                projection.clone(),
                Transform::IDENTITY,
                RenderTarget::Image(target.clone().into()),
                Msaa::Off,
                lit.clone(),
                ChildOf(camera),
            ));
            if order == 1 {
                peer.insert(ScreenSpaceAmbientOcclusion::default());
            }
        }
        Self {
            out,
            targets,
            shots: Arc::new(Mutex::new([None, None, None])),
        }
    }

    /// Takes the three pictures of this frame.
    pub fn capture(&self, commands: &mut Commands) {
        for (i, target) in self.targets.iter().enumerate() {
            let shots = self.shots.clone();
            commands.spawn(Screenshot::image(target.clone())).observe(
                move |shot: On<ScreenshotCaptured>| {
                    let shot = match shot.image.clone().try_into_dynamic() {
                        Ok(image) => {
                            let rgba = image.to_rgba8();
                            (rgba.width(), rgba.height(), rgba.into_raw())
                        }
                        // An empty image: `finish` reports it.
                        Err(_) => (0, 0, Vec::new()),
                    };
                    shots.lock().unwrap_or_else(|p| p.into_inner())[i] = Some(shot);
                },
            );
        }
    }

    /// `None` while a picture is missing; then writes them side by side (and ours alone to
    /// `ours_alone`, the `--out-color` file, which one screenshot of the target serves) and says
    /// how it went.
    pub fn finish(&self, ours_alone: Option<&PathBuf>) -> Option<Result<(), String>> {
        let shots = self.shots.lock().unwrap_or_else(|p| p.into_inner());
        let shots: Vec<&Shot> = shots.iter().map(Option::as_ref).collect::<Option<_>>()?;
        if shots.iter().any(|(w, h, _)| *w == 0 || *h == 0) {
            return Some(Err("a comparison image could not be read".into()));
        }
        if let Some(path) = ours_alone {
            let (w, h, rgba) = shots[0];
            if let Err(err) = write_rgba(path, *w, *h, rgba) {
                return Some(Err(err));
            }
        }
        let height = shots.iter().map(|(_, h, _)| *h).max().unwrap_or(0);
        let width = shots.iter().map(|(w, _, _)| *w).sum::<u32>() + GAP * 2;
        let mut data = vec![255u8; (width * height * 4) as usize];
        let mut left = 0;
        for (w, h, rgba) in shots {
            for y in 0..*h {
                let row = &rgba[(y * w * 4) as usize..((y + 1) * w * 4) as usize];
                let start = ((y * width + left) * 4) as usize;
                data[start..start + row.len()].copy_from_slice(row);
            }
            left += w + GAP;
        }
        Some(write_rgba(&self.out, width, height, &data))
    }
}

fn write_rgba(path: &PathBuf, width: u32, height: u32, data: &[u8]) -> Result<(), String> {
    let fail = |err: &dyn std::fmt::Display| format!("cannot write {}: {err}", path.display());
    let file = std::fs::File::create(path).map_err(|e| fail(&e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| fail(&e))?;
    writer.write_image_data(data).map_err(|e| fail(&e))
}

/// What every camera of a capture gets so that its lit image shows the AO: filmic tonemapping and
/// ambient light (the light AO darkens) as most of the light.
pub fn lit() -> (Tonemapping, AmbientLight) {
    (
        Tonemapping::AcesFitted,
        AmbientLight {
            brightness: 1_200.0,
            ..default()
        },
    )
}

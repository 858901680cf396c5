//! Cost against error: every preset of ours and every level of Bevy's SSAO, placed by the GPU
//! time of their AO passes (from the timing rows of the same run) and their error against the
//! CPU ray tracer, drawn as one SVG.
//!
//! Error as `presets_converge` measures it: RMSE of visibility over the pixels that show
//! geometry, 160×120, against 256 cosine-weighted rays per pixel counting hits within
//! R = 0.73 m (Bevy's own radius), mean over the three ground-truth scenes; our presets once
//! converged with a still camera (32 frames after a dropped history), Bevy's SSAO after 4 frames.
//!
//! The same run keeps the images of the default and of Bevy's SSAO High beside the ground truth,
//! and renders one more scene, a floor with a wall just outside the view, every mesh a
//! `SphereOccluder`: [`write_grid`] puts them side by side for the README.

use std::error::Error;
use std::path::Path;

use bevy::pbr::ScreenSpaceAmbientOcclusionQualityLevel;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::metrics::rmse;
use plotters::prelude::*;

use crate::harness::{BEVY_SSAO_RADIUS, Gpu, HEIGHT, WIDTH};
use crate::scenes;

/// Frames a capture of ours counts as converged: twice the frames the default history spans.
fn converged_frames() -> u32 {
    2 * DynamicAo::default().history_frames()
}

/// Bevy's SSAO levels, cheapest first.
pub const BEVY_LEVELS: [ScreenSpaceAmbientOcclusionQualityLevel; 4] = [
    ScreenSpaceAmbientOcclusionQualityLevel::Low,
    ScreenSpaceAmbientOcclusionQualityLevel::Medium,
    ScreenSpaceAmbientOcclusionQualityLevel::High,
    ScreenSpaceAmbientOcclusionQualityLevel::Ultra,
];

/// One configuration on the plot.
pub struct Point {
    /// The timing row's name ("preset high", "Bevy SSAO High").
    pub name: String,
    /// Ours (a preset) or Bevy's.
    pub ours: bool,
    /// GPU time of the AO passes, ms.
    pub ms: f64,
    /// Mean RMSE over the scenes.
    pub rmse: f32,
}

/// What [`measure`] found.
pub struct Measured {
    /// Mean RMSE over the scenes of every preset and every Bevy SSAO level, by the names the
    /// timing rows carry, and whether it is ours.
    pub errors: Vec<(String, bool, f32)>,
    /// Per scene: the default's visibility, Bevy's SSAO High's and the ground truth.
    pub images: Vec<[Vec<f32>; 3]>,
}

/// Mean RMSE over the ground-truth scenes of every preset and every Bevy SSAO level, and the
/// images of the default and Bevy's SSAO High beside the truth.
pub fn measure() -> Measured {
    let mut sums: Vec<(String, bool, f32)> = AoPreset::ALL
        .iter()
        .map(|preset| (format!("preset {}", preset.name()), true, 0.0))
        .chain(
            BEVY_LEVELS
                .iter()
                .map(|level| (format!("Bevy SSAO {level:?}"), false, 0.0)),
        )
        .collect();
    let mut images = Vec::new();
    let all = scenes::all();
    for (scene_name, scene) in &all {
        let bvh = scene.bvh();
        let mut gpu = Gpu::new(scene, DynamicAo::default().with_radius(BEVY_SSAO_RADIUS));
        let first = gpu.frame(4);
        let truth = first.ground_truth(&bvh, BEVY_SSAO_RADIUS);
        let mask = first.geometry_mask();
        let mut errors = Vec::new();
        let mut ours = Vec::new();
        let mut bevy = Vec::new();
        for preset in AoPreset::ALL {
            gpu.set_ao(|ao| {
                *ao = DynamicAo::from_preset(preset).with_radius(BEVY_SSAO_RADIUS);
                ao.temporal.reset = true;
            });
            // The read-back copies the frame rendered after it is asked for.
            let frame = gpu.frame(converged_frames() - 1);
            errors.push(rmse(&frame.visibility, &truth, Some(&mask)));
            if preset == AoPreset::default() {
                ours = frame.visibility;
            }
        }
        gpu.set_ao(|ao| ao.technique = AoTechnique::BevySsao);
        for level in BEVY_LEVELS {
            gpu.set_bevy_ssao_level(level);
            let frame = gpu.frame(4);
            errors.push(rmse(&frame.visibility, &truth, Some(&mask)));
            if level == ScreenSpaceAmbientOcclusionQualityLevel::High {
                bevy = frame.visibility;
            }
        }
        eprintln!("{scene_name}: RMSE {errors:.4?}");
        for (sum, error) in sums.iter_mut().zip(errors) {
            sum.2 += error / all.len() as f32;
        }
        images.push([ours, bevy, truth]);
    }
    images.push(off_screen());
    Measured {
        errors: sums,
        images,
    }
}

/// A floor seen from above with a wall just outside the right edge of the view, every mesh a
/// `SphereOccluder`: the default (joined by its far field), Bevy's SSAO High and the truth, at
/// the default radius.
fn off_screen() -> [Vec<f32>; 3] {
    let mut scene = scenes::wall_beside_view();
    scene.occluders = (0..scene.meshes.len())
        .map(|mesh| (mesh, SphereOccluder::default()))
        .collect();
    let bvh = scene.bvh();
    let ao = DynamicAo::default();
    let radius = ao.radius;
    let mut gpu = Gpu::new(&scene, ao);
    let ours = gpu.frame(converged_frames());
    let truth = ours.ground_truth(&bvh, radius);
    gpu.set_ao(|ao| ao.technique = AoTechnique::BevySsao);
    let bevy = gpu.frame(4);
    [ours.visibility, bevy.visibility, truth]
}

/// Writes `rows` of images (each `WIDTH` × `HEIGHT` visibility) as one 16-bit grayscale PNG,
/// 4 white pixels between images.
pub fn write_grid(path: &Path, rows: &[[Vec<f32>; 3]]) -> Result<(), Box<dyn Error>> {
    const GAP: usize = 4;
    let (w, h) = (WIDTH as usize, HEIGHT as usize);
    let width = 3 * w + 2 * GAP;
    let height = rows.len() * h + rows.len().saturating_sub(1) * GAP;
    let mut grid = vec![1.0; width * height];
    for (r, row) in rows.iter().enumerate() {
        for (c, image) in row.iter().enumerate() {
            for y in 0..h {
                let start = (r * (h + GAP) + y) * width + c * (w + GAP);
                grid[start..start + w].copy_from_slice(&image[y * w..(y + 1) * w]);
            }
        }
    }
    bevy_dynamic_ao::reference::png16::write_visibility_png(
        path,
        width as u32,
        height as u32,
        &grid,
    )?;
    Ok(())
}

/// Draws `points` to the SVG file `path`, ours and Bevy's as one line each, cheapest first.
pub fn plot(points: &[Point], path: &Path, caption: &str) -> Result<(), Box<dyn Error>> {
    let root = SVGBackend::new(path, (760, 480)).into_drawing_area();
    root.fill(&WHITE)?;
    let max_ms = points.iter().map(|p| p.ms).fold(0.0, f64::max) * 1.15;
    let max_error = points.iter().map(|p| p.rmse as f64).fold(0.0, f64::max) * 1.2;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 18))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..max_ms, 0.0..max_error)?;
    chart
        .configure_mesh()
        .x_desc("GPU time of the AO passes, ms")
        .y_desc("RMSE against ray-traced ground truth")
        .draw()?;
    for (ours, colour, label) in [
        (true, BLUE, "bevy_dynamic_ao, AoPreset Low → Ultra"),
        (false, RED, "Bevy's SSAO, Low → Ultra"),
    ] {
        let mut series: Vec<&Point> = points.iter().filter(|p| p.ours == ours).collect();
        series.sort_by(|a, b| a.ms.total_cmp(&b.ms));
        let coords: Vec<(f64, f64)> = series.iter().map(|p| (p.ms, p.rmse as f64)).collect();
        chart
            .draw_series(LineSeries::new(coords.clone(), colour.stroke_width(2)))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        chart.draw_series(coords.iter().map(|&c| Circle::new(c, 4, colour.filled())))?;
        chart.draw_series(series.iter().map(|p| {
            let level = p.name.rsplit(' ').next().unwrap_or_default().to_string();
            EmptyElement::at((p.ms, p.rmse as f64))
                + Text::new(level, (6, -16), ("sans-serif", 13).into_font())
        }))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .draw()?;
    root.present()?;
    Ok(())
}

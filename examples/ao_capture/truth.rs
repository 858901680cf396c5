//! `--out-truth`: what the capture should show, from the CPU ray tracer the crate's tests hold
//! every technique against (`reference::ground_truth`, eq. 1 of the papers): at each pixel
//! centre, the share of 256 cosine-weighted rays from the surface the camera sees that meet
//! nothing within the radius. It traces the scene as it stands when the capture is read (posed,
//! skinned and morphed on the CPU), through the capture's camera, and is written as the capture
//! is (16-bit linear visibility, 65535 where no geometry is).

use bevy::prelude::*;
use bevy_dynamic_ao::geometry::bvh::Bvh;
use bevy_dynamic_ao::reference::ground_truth::{
    GroundTruthSettings, geometry_mask, ground_truth_visibility,
};
use bevy_dynamic_ao::reference::metrics::{high_frequency_error, rmse};
use bevy_dynamic_ao::reference::nd_buffer::ViewMatrices;
use bevy_dynamic_ao::reference::png16::write_visibility_png;
use bevy_dynamic_ao::reference::posed::{descendants, posed_triangles_of};

use crate::{Capture, capture_view};

/// Hemisphere rays per pixel, as the crate's ground-truth tests trace.
pub const RAYS_PER_PIXEL: u32 = 256;

/// The ground truth of one capture and how far the capture lies from it.
pub struct Truth {
    /// Visibility per pixel, row-major.
    pub visibility: Vec<f32>,
    /// RMSE of the capture's visibility over the pixels that show geometry.
    pub rmse: f32,
    /// RMSE, over the same pixels, of the capture's fine detail against the truth's: each image
    /// minus its Gaussian blur at σ = 2 pixels (`reference::metrics::high_frequency_error`).
    /// Blur that smears detail the truth has raises it, as does noise the truth lacks.
    pub high_frequency: f32,
    /// How many pixels show geometry.
    pub pixels: usize,
}

/// Traces `bvh` through `view` at `width × height` and holds `captured` against it.
pub fn trace(
    bvh: &Bvh,
    view: &ViewMatrices,
    (width, height): (u32, u32),
    radius: f32,
    captured: &[f32],
) -> Truth {
    let settings = GroundTruthSettings {
        width,
        height,
        radius,
        rays_per_pixel: RAYS_PER_PIXEL,
    };
    let visibility = ground_truth_visibility(bvh, view, &settings);
    let mask = geometry_mask(bvh, view, width, height);
    Truth {
        rmse: rmse(captured, &visibility, Some(&mask)),
        high_frequency: high_frequency_error(captured, &visibility, width, height, Some(&mask)),
        pixels: mask.iter().filter(|m| **m).count(),
        visibility,
    }
}

/// `--out-truth`: once the capture is read, traces the posed scene through its camera on the CPU
/// and writes the result beside it (`truth.rs`).
pub fn write_truth(world: &mut World) {
    let capture = world.resource::<Capture>();
    let (Some(out), Some(captured), None, Some(root)) = (
        capture.options.out_truth.clone(),
        capture.visibility.clone(),
        capture.truth_line.as_ref(),
        capture.root,
    ) else {
        return;
    };
    let (width, height) = (capture.options.width, capture.options.height);
    let radius = capture.options.radius;
    let below = descendants(world, root);
    let scene = posed_triangles_of(world, |e| below.contains(&e));
    let Some(view) = capture_view(world) else {
        return;
    };
    let bvh = Bvh::new(scene.triangles);
    let truth = trace(&bvh, &view, (width, height), radius, &captured);
    let mut capture = world.resource_mut::<Capture>();
    if let Err(err) = write_visibility_png(&out, width, height, &truth.visibility) {
        capture.failure = Some(format!("cannot write {}: {err}", out.display()));
        return;
    }
    capture.truth_line = Some(format!(
        "ground truth: {} (CPU ray tracer, {} rays per pixel, R = {radius}); RMSE of the capture \
         {:.4} over the {} pixels that show geometry; high-frequency error {:.4}",
        out.display(),
        RAYS_PER_PIXEL,
        truth.rmse,
        truth.pixels,
        truth.high_frequency
    ));
}

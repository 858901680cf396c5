//! Camera setups beyond one full-target, single-sampled, perspective camera: MSAA, split-screen
//! viewports, HDR, orthographic projections and render layers. Each gets the AO a plain camera of
//! the same view gets, and Bevy's PBR lighting applies it at the right pixels.

mod msaa;
mod orthographic;
mod render_layers;
mod viewports_and_hdr;

fn rmse(a: &[f32], b: &[f32]) -> f32 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f32>() / a.len() as f32).sqrt()
}

/// RMSE over the pixels `mask` marks.
fn masked_rmse(a: &[f32], b: &[f32], mask: &[bool]) -> f32 {
    let (sum, n) = a
        .iter()
        .zip(b)
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0.0, 0.0), |(s, n), ((x, y), _)| {
            (s + (x - y).powi(2), n + 1.0)
        });
    (sum / n).sqrt()
}

//! Several cameras with different settings, and the debug view.

use bevy_dynamic_ao::prelude::*;

use crate::harness::{Gpu, plain_ao};
use crate::scenes;

#[test]
fn cameras_keep_their_own_settings() {
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::new(&scene, plain_ao().with_radius(0.25));
    let (wide, wide_readback) = gpu.add_camera(scene.camera, plain_ao().with_radius(1.0));
    let (off, off_readback) =
        gpu.add_camera(scene.camera, plain_ao().with_technique(AoTechnique::Off));
    let narrow = gpu.frame(4);
    let wide = gpu.frame_of(wide, &wide_readback, 0);
    let off = gpu.frame_of(off, &off_readback, 0);
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    let (n, w, o) = (
        mean(&narrow.visibility),
        mean(&wide.visibility),
        mean(&off.visibility),
    );
    println!("mean visibility: radius 0.25 m {n:.4}, radius 1 m {w:.4}, off {o:.4}");
    assert_eq!(o, 1.0, "the camera with AO off must be all open");
    assert!(
        w < n - 0.005,
        "a larger radius must occlude more: {w} vs {n}"
    );
    assert!(n < 1.0, "the narrow camera still has AO");
    // Same view, same ND-buffer: the cameras differ only in their settings.
    assert_eq!(narrow.nd.front.len(), wide.nd.front.len());
    let same = narrow
        .nd
        .front
        .iter()
        .zip(&wide.nd.front)
        .filter(|(a, b)| (a.depth - b.depth).abs() < 1e-6)
        .count();
    assert!(same as f32 > 0.99 * narrow.nd.front.len() as f32);
}

#[test]
fn debug_view_shows_the_ao_buffer() {
    let mut gpu = Gpu::new(
        &scenes::ball_near_wall(),
        DynamicAo {
            debug_view: true,
            ..plain_ao()
        },
    );
    let frame = gpu.frame(4);
    let image = gpu.color(0);
    let mut worst = 0.0f32;
    for (visibility, color) in frame.visibility.iter().zip(&image) {
        // The debug view writes visibility; the image is sRGB-encoded 8-bit, decoded to linear.
        worst = worst
            .max((color.x - visibility).abs())
            .max((color.y - visibility).abs());
    }
    assert!(
        worst < 0.02,
        "the debug view should show visibility, off by {worst}"
    );
    assert!(
        frame.visibility.iter().any(|v| *v < 0.7),
        "the debug image should have dark creases"
    );
}

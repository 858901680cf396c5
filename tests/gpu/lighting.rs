//! The hand-off to PBR: AO darkens ambient light only, never direct light.

use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;

use crate::harness::{Gpu, HEIGHT, WIDTH, plain_ao};
use crate::scenes;

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

#[test]
fn direct_light_is_untouched() {
    let mut scene = scenes::cube_on_plane();
    scene.ambient = 0.0;
    scene.sun = Some((
        Transform::from_xyz(1.0, 3.0, 2.0).looking_at(Vec3::ZERO, Vec3::Y),
        2_000.0,
    ));
    let mut gpu = Gpu::new(&scene, plain_ao().with_technique(AoTechnique::Off));
    let off = gpu.color(4);
    gpu.set_ao(|ao| ao.technique = AoTechnique::NearField);
    let frame = gpu.frame(2);
    let on = gpu.color(2);
    // The AO really is strong somewhere in this image, so an unchanged image means something.
    let darkest = frame.visibility.iter().copied().fold(1.0, f32::min);
    assert!(
        darkest < 0.6,
        "the crease should be occluded (min visibility {darkest})"
    );
    let mut lit = 0;
    for (a, b) in off.iter().zip(&on) {
        let (a, b) = (luminance(*a), luminance(*b));
        if a > 0.05 {
            lit += 1;
            // 8-bit sRGB output: allow one code step besides the 1% bound.
            assert!(
                (a - b).abs() <= 0.01 * a + 0.004,
                "a directly lit pixel changed: {a} → {b}"
            );
        }
    }
    assert!(lit > 2000, "too few directly lit pixels ({lit})");
}

#[test]
fn ambient_light_darkens_in_a_crease() {
    let mut scene = scenes::cube_on_plane();
    scene.ambient = 2_000.0;
    let mut gpu = Gpu::new(&scene, plain_ao().with_technique(AoTechnique::Off));
    let off = gpu.color(4);
    gpu.set_ao(|ao| ao.technique = AoTechnique::NearField);
    let frame = gpu.frame(2);
    let on = gpu.color(2);
    // The most occluded floor pixel is in the crease at the foot of the cube.
    let (crease, visibility) = frame
        .visibility
        .iter()
        .enumerate()
        .filter(|(i, _)| frame.position(*i).is_some_and(|p| p.y.abs() < 0.01))
        .min_by(|a, b| a.1.total_cmp(b.1))
        .expect("floor pixels");
    let (a, b) = (luminance(off[crease]), luminance(on[crease]));
    println!(
        "crease pixel ({}, {}): visibility {visibility:.3}, luminance {a:.4} → {b:.4}",
        crease % WIDTH as usize,
        crease / WIDTH as usize
    );
    assert!(
        *visibility < 0.7,
        "the crease should be occluded: {visibility}"
    );
    assert!(
        b < a * 0.85,
        "ambient light in the crease should darken: {a} → {b}"
    );
    // Far from everything, the open floor keeps its ambient light.
    let open = super::harness::index(WIDTH / 2, HEIGHT - 2);
    let (a, b) = (luminance(off[open]), luminance(on[open]));
    assert!(
        (a - b).abs() <= 0.02 * a + 0.004,
        "open floor changed: {a} → {b}"
    );
}

//! Split-screen viewports of one target and HDR cameras get the AO of their own view.

use bevy::camera::Hdr;
use bevy::camera::{RenderTarget, Viewport};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;

use super::rmse;
use crate::harness::{Gpu, HEIGHT, WIDTH, plain_ao};
use crate::scenes;

/// A camera drawing into `viewport` of a shared `target`, `order`-th, with a read-back of its
/// viewport.
fn spawn_viewport_camera(
    gpu: &mut Gpu,
    transform: Transform,
    target: &Handle<Image>,
    viewport: UVec2,
    order: isize,
) -> (Entity, AoReadback) {
    let world = gpu.app.world_mut();
    let readback = AoReadback::new(
        &mut world.resource_mut::<Assets<Image>>(),
        UVec2::new(WIDTH, HEIGHT),
    );
    let camera = world
        .spawn((
            Camera3d::default(),
            Camera {
                viewport: Some(Viewport {
                    physical_position: viewport,
                    physical_size: UVec2::new(WIDTH, HEIGHT),
                    ..default()
                }),
                order,
                // The first camera clears the whole target; the second keeps its pixels.
                clear_color: if order == 0 {
                    ClearColorConfig::Default
                } else {
                    ClearColorConfig::None
                },
                ..default()
            },
            transform,
            Msaa::Off,
            Tonemapping::None,
            RenderTarget::Image(target.clone().into()),
            plain_ao(),
            readback.clone(),
            AmbientLight {
                brightness: 500.0,
                ..default()
            },
        ))
        .id();
    (camera, readback)
}

#[test]
fn split_screen_viewports_get_the_ao_of_their_view() {
    // Two cameras side by side on one target, each a viewport of the size of the harness's own
    // cameras, which render the same two views to targets of their own as references.
    let scene = scenes::room_corner();
    let left_view =
        Transform::from_xyz(-0.6, 1.4, 2.6).looking_at(Vec3::new(-0.8, 0.3, -0.8), Vec3::Y);
    let mut gpu = Gpu::new(&scene, plain_ao());
    let (left_reference, left_reference_readback) = gpu.add_camera(left_view, plain_ao());
    gpu.app
        .world_mut()
        .entity_mut(left_reference)
        .insert(AmbientLight {
            brightness: 500.0,
            ..default()
        });
    let target =
        gpu.app
            .world_mut()
            .resource_mut::<Assets<Image>>()
            .add(Image::new_target_texture(
                2 * WIDTH,
                HEIGHT,
                bevy::render::render_resource::TextureFormat::Rgba8UnormSrgb,
                None,
            ));
    let (left, left_readback) = spawn_viewport_camera(&mut gpu, left_view, &target, UVec2::ZERO, 0);
    let (right, right_readback) =
        spawn_viewport_camera(&mut gpu, scene.camera, &target, UVec2::new(WIDTH, 0), 1);

    let right_reference = gpu.frame(4);
    let left_reference = gpu.frame_of(left_reference, &left_reference_readback, 0);
    let left = gpu.frame_of(left, &left_readback, 0);
    let right = gpu.frame_of(right, &right_readback, 0);
    let reference_lit = gpu.color(0);
    let split_lit = gpu.color_of(target, UVec2::new(2 * WIDTH, HEIGHT), 0);

    let left_error = rmse(&left.visibility, &left_reference.visibility);
    let right_error = rmse(&right.visibility, &right_reference.visibility);
    // The right half of the split image against the reference camera's image.
    let right_half: Vec<Vec3> = split_lit
        .chunks_exact(2 * WIDTH as usize)
        .flat_map(|row| row[WIDTH as usize..].to_vec())
        .collect();
    let lit_error = rmse(
        &right_half.iter().map(|c| c.y).collect::<Vec<_>>(),
        &reference_lit.iter().map(|c| c.y).collect::<Vec<_>>(),
    );
    println!(
        "split screen against full cameras: AO RMSE left {left_error:.5}, right \
         {right_error:.5}; lit right half RMSE {lit_error:.5}"
    );
    assert!(
        right.visibility.iter().any(|v| *v < 0.6) && left.visibility.iter().any(|v| *v < 0.6),
        "the split views have no dark creases"
    );
    // Measured 0 and 0 (the same pixels through the same passes).
    assert!(left_error < 1e-3, "left viewport AO: RMSE {left_error}");
    assert!(right_error < 1e-3, "right viewport AO: RMSE {right_error}");
    // Measured 0.0008 (8-bit sRGB rounding): PBR of the right camera reads its own AO.
    assert!(
        lit_error < 0.003,
        "the right viewport's lighting does not match its reference: RMSE {lit_error}"
    );
}

#[test]
fn hdr_and_ldr_cameras_get_the_same_ao() {
    let scene = scenes::ball_near_wall();
    let mut gpu = Gpu::new(&scene, plain_ao());
    let ldr = gpu.frame(4);
    let camera = gpu.camera;
    gpu.app.world_mut().entity_mut(camera).insert(Hdr);
    let hdr = gpu.frame(4);
    let error = rmse(&ldr.visibility, &hdr.visibility);
    println!("HDR against LDR: RMSE {error:.5}");
    assert!(hdr.visibility.iter().any(|v| *v < 0.6), "HDR lost the AO");
    assert!(error < 1e-3, "HDR AO differs from LDR AO: RMSE {error}");
}

//! What both tables share: the headless app, a camera of a configuration rendering into an image,
//! and reading images back.

#[path = "../../examples/common/mod.rs"]
mod common;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::time::TimeUpdateStrategy;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::nd_buffer::NdTexel;

use crate::Configuration;

/// Image size of both tables, pixels.
pub const SIZE: UVec2 = UVec2::new(160, 120);
/// Simulated time per frame, seconds: every run sees the same poses.
pub const FRAME_TIME: f32 = 1.0 / 30.0;

/// A headless app with the plugin, advancing time by [`FRAME_TIME`] per update.
pub fn new_app() -> App {
    let mut app = App::new();
    app.add_plugins((common::headless_plugins(), DynamicAoPlugin))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
            FRAME_TIME,
        )));
    common::finish_plugins(&mut app);
    app
}

/// The camera of a run and its images.
pub struct View {
    pub camera: Entity,
    pub readback: AoReadback,
    /// The lit image, `Rgba8UnormSrgb`.
    pub target: Handle<Image>,
}

/// Spawns a camera of `configuration` at `transform`, rendering into an image of [`SIZE`].
pub fn spawn_camera(
    world: &mut World,
    configuration: &Configuration,
    transform: Transform,
) -> View {
    let mut image = Image::new_target_texture(SIZE.x, SIZE.y, TextureFormat::Rgba8UnormSrgb, None);
    // Read back as well as rendered to.
    image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    let target = world.resource_mut::<Assets<Image>>().add(image);
    let readback = AoReadback::new(&mut world.resource_mut::<Assets<Image>>(), SIZE);
    let mut camera = world.spawn((
        Camera3d::default(),
        RenderTarget::Image(target.clone().into()),
        transform,
        Msaa::Off,
        // Most of the light is ambient, which AO darkens, so the lit image shows its changes.
        AmbientLight {
            brightness: 2000.0,
            ..default()
        },
        readback.clone(),
    ));
    configuration.insert(&mut camera);
    View {
        camera: camera.id(),
        readback,
        target,
    }
}

/// Reads `images` as they are after the next update: one update renders the frame and copies
/// it; the app keeps updating (the caller holds the scene still) until every copy has arrived.
pub fn read_next(app: &mut App, images: &[Handle<Image>]) -> Vec<Vec<u8>> {
    read_next_then(app, images, |_| {})
}

/// Like [`read_next`], calling `after_first` once the frame that is read has been rendered.
pub fn read_next_then(
    app: &mut App,
    images: &[Handle<Image>],
    after_first: impl FnOnce(&mut App),
) -> Vec<Vec<u8>> {
    let slots: Arc<Mutex<Vec<Option<Vec<u8>>>>> = Arc::new(Mutex::new(vec![None; images.len()]));
    let entities: Vec<Entity> = images
        .iter()
        .enumerate()
        .map(|(slot, image)| {
            let slots = slots.clone();
            app.world_mut()
                .spawn(Readback::texture(image.clone()))
                .observe(move |done: On<ReadbackComplete>| {
                    slots.lock().unwrap()[slot].get_or_insert_with(|| done.data.clone());
                })
                .id()
        })
        .collect();
    app.update();
    after_first(app);
    for _ in 0..60 {
        if slots.lock().unwrap().iter().all(Option::is_some) {
            break;
        }
        app.update();
        if slots.lock().unwrap().iter().all(Option::is_some) {
            break;
        }
    }
    for entity in entities {
        app.world_mut().despawn(entity);
    }
    let slots = slots.lock().unwrap().clone();
    slots
        .into_iter()
        .map(|s| s.expect("the read-back completes within 60 frames"))
        .collect()
}

/// Visibility as read back. Panics on a frame whose AO was not yet its technique's (every pixel
/// −1, `AoReadback`): a table must not count it as an error or a flicker.
pub fn visibility(data: &[u8]) -> Vec<f32> {
    let visibility = common::unpad_f32(data, SIZE.x as usize, SIZE.y as usize, 1);
    assert!(
        !not_written(&visibility),
        "a frame read before the AO was written (its passes had not compiled): wait with \
         `wait_until_written` first"
    );
    visibility
}

/// `AoReadback` marks a frame whose AO its technique has not written yet with −1 on every pixel.
fn not_written(visibility: &[f32]) -> bool {
    visibility.iter().all(|&v| v == -1.0)
}

/// Updates `app` until the AO of `view` is its technique's, so that the frames a table counts
/// from then on (to converge, to warm up) are frames of AO, however long the shaders took to load.
pub fn wait_until_written(app: &mut App, view: &View) {
    for _ in 0..600 {
        let data = read_next(app, std::slice::from_ref(&view.readback.visibility));
        let visibility = common::unpad_f32(&data[0], SIZE.x as usize, SIZE.y as usize, 1);
        if !not_written(&visibility) {
            return;
        }
    }
    panic!("the AO of the camera was not written within 600 frames");
}

/// Pixels where the front layer of an ND-buffer read-back saw geometry.
pub fn geometry_mask(front: &[u8]) -> Vec<bool> {
    common::unpad_f32(front, SIZE.x as usize, SIZE.y as usize, 4)
        .chunks_exact(4)
        .map(|c| NdTexel::from_rgba([c[0], c[1], c[2], c[3]]).depth > 0.0)
        .collect()
}

/// Luminance in [0, 1] of an `Rgba8UnormSrgb` read-back, on its encoded (display) values.
pub fn luminance(data: &[u8]) -> Vec<f32> {
    let row = (SIZE.x as usize * 4).next_multiple_of(256);
    (0..SIZE.y as usize)
        .flat_map(|y| {
            data[y * row..y * row + SIZE.x as usize * 4]
                .chunks_exact(4)
                .map(|c| {
                    (0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32) / 255.0
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The floor, box and ball both tables stand on, and a light.
pub fn spawn_floor_box_and_ball(world: &mut World) {
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let floor = meshes.add(Plane3d::default().mesh().size(14.0, 14.0));
    let cube = meshes.add(Cuboid::new(1.0, 1.0, 1.0));
    let ball = meshes.add(Sphere::new(0.3).mesh().uv(32, 16));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    for (mesh, transform) in [
        (floor, Transform::IDENTITY),
        (cube, Transform::from_xyz(0.0, 0.5, 0.0)),
        (ball, Transform::from_xyz(0.9, 0.3, 0.7)),
    ] {
        world.spawn((Mesh3d(mesh), MeshMaterial3d(material.clone()), transform));
    }
    world.spawn((
        DirectionalLight {
            illuminance: 1000.0,
            ..default()
        },
        Transform::from_xyz(2.0, 6.0, 3.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
}

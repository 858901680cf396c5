//! A small room with boxes, a ball and stairs, lit by a sun and ambient light, with dynamic AO.
//!
//! Windowed: `cargo run --example basic`.
//! Headless: `cargo run --example basic -- --headless --frames 10 --out basic.png`.

#[path = "../common/mod.rs"]
mod common;

use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;
use common::{ExampleArgs, HelpLine};

const USAGE: &str =
    "usage: basic [--headless] [--frames N] [--out FILE.png] [--width W] [--height H]
keys: Space AO on/off, T technique, B Bevy's SSAO, D debug view, 1-4 presets, L back-face layer,
      F blur, H half resolution, Esc quit";

fn main() {
    let args = ExampleArgs::parse(USAGE);
    if let Some(unknown) = args.rest.iter().find(|a| *a != "--debug-view") {
        eprintln!("error: unknown argument '{unknown}'\n{USAGE}");
        std::process::exit(2);
    }
    let mut app = common::example_app("bevy_dynamic_ao: basic", &args);
    app.insert_resource(StartWithDebugView(
        args.rest.iter().any(|a| a == "--debug-view"),
    ))
    .add_plugins(DynamicAoPlugin)
    .add_systems(Startup, setup)
    .add_systems(Update, (controls, show_settings, spin))
    .run();
}

#[derive(Component)]
struct Spin;

#[derive(Resource)]
struct StartWithDebugView(bool);

fn setup(world: &mut World) {
    let debug_view = world.resource::<StartWithDebugView>().0;
    common::spawn_ao_camera(
        world,
        Vec3::new(-3.2, 2.6, 4.6),
        Vec3::new(0.3, 0.6, 0.0),
        DynamicAo {
            debug_view,
            ..default()
        },
        900.0,
    );
    let _commands = world.commands();

    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let floor = meshes.add(Plane3d::default().mesh().size(12.0, 12.0));
    let wall = meshes.add(Cuboid::new(12.0, 4.0, 0.2));
    let cube = meshes.add(Cuboid::new(1.0, 1.0, 1.0));
    let ball = meshes.add(Sphere::new(0.5).mesh().uv(48, 24));
    let step = meshes.add(Cuboid::new(1.6, 0.25, 0.4));
    let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
    let white = materials.add(StandardMaterial {
        base_color: Color::srgb(0.85, 0.85, 0.82),
        perceptual_roughness: 0.9,
        ..default()
    });
    let orange = materials.add(StandardMaterial {
        base_color: Color::srgb(0.9, 0.45, 0.2),
        perceptual_roughness: 0.6,
        ..default()
    });
    let mut commands = world.commands();
    commands.spawn((Mesh3d(floor), MeshMaterial3d(white.clone())));
    commands.spawn((
        Mesh3d(wall),
        MeshMaterial3d(white.clone()),
        Transform::from_xyz(0.0, 2.0, -1.6),
    ));
    commands.spawn((
        Mesh3d(cube.clone()),
        MeshMaterial3d(orange.clone()),
        Transform::from_xyz(-1.2, 0.5, -0.9),
        Spin,
    ));
    commands.spawn((
        Mesh3d(cube),
        MeshMaterial3d(white.clone()),
        Transform::from_xyz(-0.4, 0.5, 0.6).with_scale(Vec3::new(0.6, 1.0, 0.6)),
    ));
    commands.spawn((
        Mesh3d(ball),
        MeshMaterial3d(orange),
        Transform::from_xyz(1.0, 0.5, -0.6),
    ));
    for i in 0..5 {
        commands.spawn((
            Mesh3d(step.clone()),
            MeshMaterial3d(white.clone()),
            Transform::from_xyz(2.4, 0.125 + 0.25 * i as f32, -1.3 + 0.4 * i as f32),
        ));
    }
    commands.spawn((
        DirectionalLight {
            illuminance: 3_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(3.0, 6.0, 2.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
}

fn spin(time: Res<Time>, mut spinning: Query<&mut Transform, With<Spin>>) {
    for mut transform in &mut spinning {
        transform.rotate_y(time.delta_secs() * 0.4);
    }
}

fn controls(keys: Res<ButtonInput<KeyCode>>, mut cameras: Query<&mut DynamicAo>) {
    for mut ao in &mut cameras {
        if keys.just_pressed(KeyCode::Space) {
            ao.technique = match ao.technique {
                AoTechnique::Off => AoTechnique::NearField,
                _ => AoTechnique::Off,
            };
        }
        if keys.just_pressed(KeyCode::KeyB) {
            ao.technique = match ao.technique {
                AoTechnique::BevySsao => AoTechnique::NearField,
                _ => AoTechnique::BevySsao,
            };
        }
        if keys.just_pressed(KeyCode::KeyT) {
            ao.technique = match ao.technique {
                AoTechnique::NearField => AoTechnique::Horizon,
                AoTechnique::Horizon => AoTechnique::RayMarch,
                _ => AoTechnique::NearField,
            };
        }
        if keys.just_pressed(KeyCode::KeyH) {
            ao.half_resolution = !ao.half_resolution;
        }
        if keys.just_pressed(KeyCode::KeyF) {
            ao.blur = if ao.blur.radius == 0 {
                AoBlur::default()
            } else {
                AoBlur::OFF
            };
        }
        if keys.just_pressed(KeyCode::KeyD) {
            ao.debug_view = !ao.debug_view;
        }
        if keys.just_pressed(KeyCode::KeyL) {
            ao.near_field.back_layer = !ao.near_field.back_layer;
        }
        common::preset_keys(&keys, &mut ao);
    }
}

fn show_settings(
    cameras: Query<(&DynamicAo, &Camera)>,
    mut text: Query<&mut Text, With<HelpLine>>,
) {
    let (Ok((ao, camera)), Ok(mut text)) = (cameras.single(), text.single_mut()) else {
        return;
    };
    let viewport = camera.physical_viewport_size().unwrap_or_default();
    let params = ao.near_field;
    text.0 = format!(
        "AO: {} | near field {} samples, back layer {} | radius {:.2} m | blur {} px | half res {} | debug view {}\n\
         Space AO on/off  T technique  B Bevy SSAO  D debug view  1-4 presets  L back layer  F blur  H half res  Esc quit",
        ao.technique.name(),
        params.max_samples,
        if params.back_layer { "on" } else { "off" },
        ao.radius,
        ao.blur.radius,
        match (ao.half_resolution, ao.half_resolution_at(viewport)) {
            (_, true) => "on",
            (true, false) => "on (full at this size)",
            (false, _) => "off",
        },
        if ao.debug_view { "on" } else { "off" },
    );
}

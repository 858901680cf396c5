//! Skinned characters walking near each other and a wall: their far-field occlusion comes from
//! spheres that are refit to the animated skin every frame (`SphereOccluder`), added to the
//! image-space near field. With `--voxels`, each walker instead carries a `VoxelAoVolume` that
//! follows it and is revoxelized every frame, skin, floor and passing neighbours included;
//! `--show-voxels` draws the occupied cells. The walker is the project's own generated asset
//! (`assets/characters/walker.glb`, written by `cargo run --example generate_assets`).
//!
//! Windowed: `cargo run --example deforming_characters`.
//! Headless: `cargo run --example deforming_characters -- --headless --frames 20 --out walkers.png`.
//! Voxels: `cargo run --example deforming_characters -- --voxels --show-voxels`.

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/walking.rs"]
mod walking;

use bevy::prelude::*;
use bevy::world_serialization::WorldAssetRoot;
use bevy_dynamic_ao::prelude::*;
use common::{ExampleArgs, HelpLine};
use walking::{WALKER, WalkAnimation, WalkPath, start_walking, walk};

const USAGE: &str = "usage: deforming_characters [--headless] [--frames N] [--out FILE.png] \
[--width W] [--height H] [--characters N] [--show-spheres] [--voxels] [--show-voxels] [--debug-view]
keys: N image-space AO on/off, F far field (spheres) on/off, V voxel volumes on/off, M blend (count once/add/max),
      S show spheres, O show occupied voxels, D debug view, Esc quit";

fn main() {
    let args = ExampleArgs::parse(USAGE);
    let mut options = Options {
        characters: 6,
        show_spheres: false,
        voxels: false,
        show_voxels: false,
        debug_view: false,
    };
    let mut rest = args.rest.iter();
    while let Some(flag) = rest.next() {
        match flag.as_str() {
            "--show-spheres" => options.show_spheres = true,
            "--voxels" => options.voxels = true,
            "--show-voxels" => {
                options.voxels = true;
                options.show_voxels = true;
            }
            "--debug-view" => options.debug_view = true,
            "--characters" => {
                options.characters =
                    common::numeric_flag(&mut rest, "--characters", 1, USAGE).min(200);
            }
            unknown => {
                eprintln!("error: unknown argument '{unknown}'\n{USAGE}");
                std::process::exit(2);
            }
        }
    }
    let mut app = common::example_app("bevy_dynamic_ao: deforming characters", &args);
    app.insert_resource(options)
        .add_plugins(DynamicAoPlugin)
        .add_systems(Startup, setup)
        .add_systems(
            Update,
            (
                walk,
                controls,
                show_settings,
                common::fail_without_required_asset,
            ),
        )
        .run();
}

#[derive(Resource, Clone, Copy)]
struct Options {
    characters: u32,
    show_spheres: bool,
    /// Each walker carries a voxel volume; spheres start switched off.
    voxels: bool,
    show_voxels: bool,
    debug_view: bool,
}

/// The region each walker's voxel volume covers around it: the body and the floor and walls
/// within reach, metres.
const WALKER_VOLUME: Vec3 = Vec3::new(0.75, 1.05, 0.75);

fn setup(world: &mut World) {
    let options = *world.resource::<Options>();
    world.resource_mut::<ShowOccluderSpheres>().0 = options.show_spheres;
    let scene = WalkAnimation::load(world);
    world.insert_resource(common::RequiredAsset {
        handle: scene.clone().untyped(),
        path: WALKER,
    });

    common::spawn_ao_camera(
        world,
        Vec3::new(0.0, 3.4, 6.4),
        Vec3::new(0.0, 0.6, -0.4),
        DynamicAo {
            debug_view: options.debug_view,
            spheres: !options.voxels,
            voxels: options.voxels,
            ..default()
        },
        1200.0,
    );

    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let floor = meshes.add(Plane3d::default().mesh().size(14.0, 14.0));
    let wall = meshes.add(Cuboid::new(14.0, 3.0, 0.2));
    let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
    let white = materials.add(StandardMaterial {
        base_color: Color::srgb(0.85, 0.85, 0.82),
        perceptual_roughness: 0.9,
        ..default()
    });
    let mut commands = world.commands();
    commands.spawn((Mesh3d(floor), MeshMaterial3d(white.clone())));
    commands.spawn((
        Mesh3d(wall),
        MeshMaterial3d(white),
        Transform::from_xyz(0.0, 1.5, -2.2),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 2_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(2.0, 6.0, 3.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    for i in 0..options.characters {
        // Rings of walkers; neighbours walk in opposite directions so they pass close by.
        let ring = i / 6;
        let slot = i % 6;
        let path = WalkPath {
            centre: Vec3::new(
                -2.4 + 1.6 * (slot % 3) as f32,
                0.0,
                -0.6 + 1.5 * (slot / 3) as f32 + 3.0 * ring as f32,
            ),
            radius: 0.7 + 0.1 * slot as f32,
            speed: if slot % 2 == 0 { 0.9 } else { -0.8 },
            phase: slot as f32 * 1.1,
        };
        let mut walker = commands.spawn((
            WorldAssetRoot(scene.clone()),
            SphereOccluder::default(),
            Transform::default(),
            path,
        ));
        walker.observe(start_walking);
        if options.voxels {
            // A child, so the volume walks and turns with its walker.
            walker.with_child((
                Transform::from_xyz(0.0, WALKER_VOLUME.y - 0.1, 0.0),
                VoxelAoVolume {
                    half_extents: WALKER_VOLUME,
                    // Cells of 1.6 × 2.2 × 1.6 cm: finer than the gap between arm and body,
                    // which coarser cells close (rays then start inside the arm).
                    resolution: 96,
                    ..default()
                },
            ));
        }
    }
    if options.show_voxels {
        world.flush();
        let volumes: Vec<Entity> = world
            .query_filtered::<Entity, With<VoxelAoVolume>>()
            .iter(world)
            .collect();
        for volume in volumes {
            world.entity_mut(volume).insert(ShowOccupiedVoxels);
        }
    }
}

fn controls(
    mut commands: Commands,
    keys: Res<ButtonInput<KeyCode>>,
    mut cameras: Query<&mut DynamicAo>,
    mut show_spheres: ResMut<ShowOccluderSpheres>,
    volumes: Query<(Entity, Has<ShowOccupiedVoxels>), With<VoxelAoVolume>>,
) {
    if keys.just_pressed(KeyCode::KeyS) {
        show_spheres.0 = !show_spheres.0;
    }
    if keys.just_pressed(KeyCode::KeyO) {
        for (volume, shown) in &volumes {
            if shown {
                commands.entity(volume).remove::<ShowOccupiedVoxels>();
            } else {
                commands.entity(volume).insert(ShowOccupiedVoxels);
            }
        }
    }
    for mut ao in &mut cameras {
        common::near_field_and_debug_keys(&keys, &mut ao);
        if keys.just_pressed(KeyCode::KeyF) {
            ao.spheres = !ao.spheres;
        }
        if keys.just_pressed(KeyCode::KeyV) {
            ao.voxels = !ao.voxels;
        }
        if keys.just_pressed(KeyCode::KeyM) {
            ao.far_field_blend = match ao.far_field_blend {
                FarFieldBlend::CountOnce => FarFieldBlend::Add,
                FarFieldBlend::Add => FarFieldBlend::Max,
                FarFieldBlend::Max => FarFieldBlend::CountOnce,
            };
        }
    }
}

fn show_settings(
    cameras: Query<&DynamicAo>,
    show_spheres: Res<ShowOccluderSpheres>,
    occluders: Query<&OccluderSpheres>,
    volumes: Query<Has<ShowOccupiedVoxels>, With<VoxelAoVolume>>,
    mut text: Query<&mut Text, With<HelpLine>>,
) {
    let (Ok(ao), Ok(mut text)) = (cameras.single(), text.single_mut()) else {
        return;
    };
    let on = |b: bool| if b { "on" } else { "off" };
    let spheres: usize = occluders.iter().map(|o| o.spheres.len()).sum();
    let shown = volumes.iter().any(|shown| shown);
    text.0 = format!(
        "near field {} | spheres {} ({spheres}, {:?}) | voxels {} ({} volumes) | show spheres {} \
         | show voxels {} | debug view {}\n\
         N image-space AO  F spheres  V voxels  M blend (count once/add/max)  S show spheres  O show voxels  \
         D debug view  Esc quit",
        on(ao.technique != AoTechnique::Off),
        on(ao.spheres),
        ao.far_field_blend,
        on(ao.voxels),
        volumes.iter().len(),
        on(show_spheres.0),
        on(shown),
        on(ao.debug_view),
    );
}

//! Toasters fly in, tumble and land on a kitchen counter; each casts ambient occlusion from a
//! precomputed AO field (`AoField`), baked from its mesh on load and cached on disk. The scene is
//! the project's own generated asset (`assets/scenes/toasters.glb`, written by
//! `cargo run --example generate_assets`). `--stress N` adds N more toasters circling above the
//! floor, all sharing one baked field.
//!
//! Windowed: `cargo run --example toasters`.
//! Headless: `cargo run --example toasters -- --headless --frames 90 --out toasters.png` (the
//! toasters have landed by frame 90, three seconds in).

#[path = "../common/mod.rs"]
mod common;

use bevy::gltf::GltfAssetLabel;
use bevy::prelude::*;
use bevy::world_serialization::{WorldAssetRoot, WorldInstanceReady};
use bevy_dynamic_ao::prelude::*;
use common::{ExampleArgs, HelpLine};

const USAGE: &str = "usage: toasters [--headless] [--frames N] [--out FILE.png] [--width W] \
[--height H] [--stress N] [--debug-view]
keys: N image-space AO on/off, F fields on/off, C cone / occlusion-only shading, D debug view, Esc quit";

const SCENE: &str = "scenes/toasters.glb";

#[derive(Resource, Clone, Copy)]
struct Options {
    stress: u32,
    debug_view: bool,
}

fn main() {
    let args = ExampleArgs::parse(USAGE);
    let mut options = Options {
        stress: 0,
        debug_view: false,
    };
    let mut rest = args.rest.iter();
    while let Some(flag) = rest.next() {
        match flag.as_str() {
            "--debug-view" => options.debug_view = true,
            "--stress" => {
                options.stress = common::numeric_flag(&mut rest, "--stress", 0, USAGE).min(4096);
            }
            unknown => {
                eprintln!("error: unknown argument '{unknown}'\n{USAGE}");
                std::process::exit(2);
            }
        }
    }
    let mut app = common::example_app("bevy_dynamic_ao: toasters", &args);
    app.insert_resource(options)
        .add_plugins(DynamicAoPlugin)
        .add_systems(Startup, setup)
        .add_systems(
            Update,
            (
                circle,
                controls,
                show_settings,
                common::fail_without_required_asset,
            ),
        )
        .run();
}

#[derive(Resource)]
struct Scene {
    graph: Handle<AnimationGraph>,
    node: AnimationNodeIndex,
}

/// A stress-mode toaster circling the counter: radius (metres), height, speed (radians per
/// second), phase.
#[derive(Component)]
struct Circling {
    radius: f32,
    height: f32,
    speed: f32,
    phase: f32,
}

fn setup(world: &mut World) {
    let options = *world.resource::<Options>();
    let assets = world.resource::<AssetServer>().clone();
    let scene = assets.load(GltfAssetLabel::Scene(0).from_asset(SCENE));
    let clip = assets.load(GltfAssetLabel::Animation(0).from_asset(SCENE));
    let (graph, node) = AnimationGraph::from_clip(clip);
    let graph = world.resource_mut::<Assets<AnimationGraph>>().add(graph);
    world.insert_resource(Scene { graph, node });
    world.insert_resource(common::RequiredAsset {
        handle: scene.clone().untyped(),
        path: SCENE,
    });

    common::spawn_ao_camera(
        world,
        Vec3::new(0.6, 2.2, 3.4),
        Vec3::new(0.0, 0.8, 0.0),
        DynamicAo {
            debug_view: options.debug_view,
            ..default()
        },
        1000.0,
    );
    let mut commands = world.commands();
    commands.spawn((
        DirectionalLight {
            illuminance: 2_500.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(-2.0, 5.0, 3.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.spawn(WorldAssetRoot(scene)).observe(scene_ready);

    if options.stress > 0 {
        let toaster: Handle<Mesh> = assets.load(
            GltfAssetLabel::Primitive {
                mesh: 2,
                primitive: 0,
            }
            .from_asset(SCENE),
        );
        let material = world
            .resource_mut::<Assets<StandardMaterial>>()
            .add(StandardMaterial {
                base_color: Color::srgb(0.75, 0.3, 0.25),
                perceptual_roughness: 0.4,
                ..default()
            });
        let mut commands = world.commands();
        for i in 0..options.stress {
            let ring = (i % 8) as f32;
            commands.spawn((
                Mesh3d(toaster.clone()),
                MeshMaterial3d(material.clone()),
                Transform::default(),
                AoField::default(),
                Circling {
                    radius: 1.7 + 0.15 * ring,
                    height: 0.15 + 0.12 * ((i / 8) % 12) as f32,
                    speed: 0.3 + 0.05 * ring,
                    phase: i as f32 * 2.399,
                },
            ));
        }
    }
}

/// Once the scene exists: the glTF's own camera stays off (ours shows the same view), the
/// animation loops, and every toaster mesh gets an AO field.
fn scene_ready(
    ready: On<WorldInstanceReady>,
    mut commands: Commands,
    scene: Res<Scene>,
    children: Query<&Children>,
    names: Query<&Name>,
    parents: Query<&ChildOf>,
    meshes: Query<(), With<Mesh3d>>,
    mut cameras: Query<&mut Camera>,
    mut players: Query<&mut AnimationPlayer>,
) {
    for entity in children.iter_descendants(ready.entity) {
        if let Ok(mut camera) = cameras.get_mut(entity) {
            camera.is_active = false;
        }
        if let Ok(mut player) = players.get_mut(entity) {
            player.play(scene.node).repeat();
            commands
                .entity(entity)
                .insert(AnimationGraphHandle(scene.graph.clone()));
        }
        let is_toaster = parents
            .get(entity)
            .and_then(|p| names.get(p.parent()))
            .is_ok_and(|n| n.as_str().starts_with("toaster"));
        if is_toaster && meshes.contains(entity) {
            commands.entity(entity).insert(AoField::default());
        }
    }
}

fn circle(time: Res<Time>, mut toasters: Query<(&Circling, &mut Transform)>) {
    let t = time.elapsed_secs();
    for (c, mut transform) in &mut toasters {
        let angle = c.phase + c.speed * t;
        transform.translation = Vec3::new(angle.cos() * c.radius, c.height, angle.sin() * c.radius);
        transform.rotation =
            Quat::from_rotation_y(-angle) * Quat::from_rotation_x(0.7 * t + c.phase);
    }
}

fn controls(keys: Res<ButtonInput<KeyCode>>, mut cameras: Query<&mut DynamicAo>) {
    for mut ao in &mut cameras {
        common::near_field_and_debug_keys(&keys, &mut ao);
        if keys.just_pressed(KeyCode::KeyF) {
            ao.fields = !ao.fields;
        }
        if keys.just_pressed(KeyCode::KeyC) {
            ao.field_shading = match ao.field_shading {
                FieldShading::Cone => FieldShading::OcclusionOnly,
                FieldShading::OcclusionOnly => FieldShading::Cone,
            };
        }
    }
}

fn show_settings(
    cameras: Query<&DynamicAo>,
    fields: Query<(), With<AoField>>,
    mut text: Query<&mut Text, With<HelpLine>>,
) {
    let (Ok(ao), Ok(mut text)) = (cameras.single(), text.single_mut()) else {
        return;
    };
    let on = |b: bool| if b { "on" } else { "off" };
    text.0 = format!(
        "near field {} | fields {} ({} occluders, {:?}) | debug view {}\n\
         N image-space AO  F fields  C cone / occlusion only  D debug view  Esc quit",
        on(ao.technique != AoTechnique::Off),
        on(ao.fields),
        fields.iter().count(),
        ao.field_shading,
        on(ao.debug_view),
    );
}

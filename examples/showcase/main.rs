//! The showcase: a hall with a colonnade, props, walkers and moving objects, lit mostly by
//! ambient light (the light AO darkens), shown three ways side by side from one viewpoint: ours
//! (`DynamicAo`, preset and far-field term by key) | Bevy's SSAO (High) | no AO. The bottom
//! line gives the GPU milliseconds of every AO pass, from Bevy's render diagnostics. The scene
//! is built in code; the walker is the project's own `assets/characters/walker.glb`.
//!
//! Windowed: `cargo run --example showcase`.
//! Headless: `cargo run --example showcase -- --headless --frames 60 --width 1500 --height 500
//! --out showcase.png` (`--layout ours` for ours alone, over the whole image).

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/far_terms.rs"]
mod far_terms;
mod hall;
mod hud;
mod views;
#[path = "../common/walking.rs"]
mod walking;

use bevy::prelude::*;
use bevy::render::diagnostic::RenderDiagnosticsPlugin;
use bevy_dynamic_ao::prelude::*;
use common::ExampleArgs;
use far_terms::FarTerm;
use views::{Layout, Shown};
use walking::{WALKER, WalkAnimation, walk};

const USAGE: &str = "usage: showcase [--headless] [--frames N] [--out FILE.png] [--width W] \
[--height H] [--layout thirds|ours|bevy|none] [--preset low|medium|high|ultra]
       [--far spheres|fields|voxels|none]
keys: C layout (thirds, ours, Bevy's, none), 1-4 presets, F far-field term (spheres, fields,
      voxels, none), D debug view, Esc quit";

/// The far-field term ours uses (`None`: the image-space term alone).
#[derive(Resource, Clone, Copy)]
pub struct Far(pub Option<FarTerm>);

/// The preset ours starts with.
#[derive(Resource)]
struct StartPreset(AoPreset);

fn main() {
    let args = ExampleArgs::parse(USAGE);
    let mut layout = Layout::Thirds;
    let mut preset = AoPreset::High;
    // The image-space term alone: on a view that holds the whole hall the far field adds little
    // and its box proxies cost far more (the F key shows both).
    let mut far = None;
    let mut rest = args.rest.iter();
    while let Some(flag) = rest.next() {
        let value = rest.next().map(String::as_str).unwrap_or("");
        let named_preset = AoPreset::ALL.into_iter().find(|p| p.name() == value);
        match (flag.as_str(), value) {
            ("--layout", "thirds") => layout = Layout::Thirds,
            ("--layout", "ours") => layout = Layout::Alone(Shown::Ours),
            ("--layout", "bevy") => layout = Layout::Alone(Shown::BevySsao),
            ("--layout", "none") => layout = Layout::Alone(Shown::NoAo),
            ("--preset", _) if named_preset.is_some() => preset = named_preset.unwrap(),
            ("--far", "none") => far = None,
            ("--far", name) if FarTerm::from_name(name).is_some() => {
                far = FarTerm::from_name(name);
            }
            _ => {
                eprintln!("error: bad argument '{flag} {value}'\n{USAGE}");
                std::process::exit(2);
            }
        }
    }
    let mut app = common::example_app("bevy_dynamic_ao: showcase", &args);
    app.insert_resource(layout)
        .insert_resource(Far(far))
        .insert_resource(StartPreset(preset))
        .insert_resource(ClearColor(Color::srgb(0.62, 0.68, 0.76)))
        .add_plugins((DynamicAoPlugin, RenderDiagnosticsPlugin))
        .add_systems(Startup, (setup, hud::spawn))
        .add_systems(
            Update,
            (
                walk,
                hall::shuttle,
                controls,
                apply_far_term,
                views::fit,
                hud::update,
                common::fail_without_required_asset,
            )
                .chain(),
        )
        .run();
}

fn setup(world: &mut World) {
    let walker = WalkAnimation::load(world);
    world.insert_resource(common::RequiredAsset {
        handle: walker.clone().untyped(),
        path: WALKER,
    });
    hall::spawn(world, walker);
    let preset = world.resource::<StartPreset>().0;
    views::spawn(world, DynamicAo::from_preset(preset));
}

fn controls(
    keys: Res<ButtonInput<KeyCode>>,
    mut layout: ResMut<Layout>,
    mut far: ResMut<Far>,
    mut ours: Query<&mut DynamicAo>,
) {
    if keys.just_pressed(KeyCode::KeyC) {
        *layout = layout.next();
    }
    if keys.just_pressed(KeyCode::KeyF) {
        far.0 = match far.0 {
            Some(FarTerm::Spheres) => Some(FarTerm::Fields),
            Some(FarTerm::Fields) => Some(FarTerm::Voxels),
            Some(FarTerm::Voxels) => None,
            None => Some(FarTerm::Spheres),
        };
    }
    for mut ao in &mut ours {
        common::preset_keys(&keys, &mut ao);
        if keys.just_pressed(KeyCode::KeyD) {
            ao.debug_view = !ao.debug_view;
        }
    }
}

/// Switches ours to the chosen far-field term, giving the scene its occluders the first time it
/// is chosen: an AO field for every moving rigid object (baked in the background), or one voxel
/// volume over the hall. The walkers and moving objects carry a `SphereOccluder` from the start.
fn apply_far_term(
    mut commands: Commands,
    far: Res<Far>,
    mut ours: Query<&mut DynamicAo>,
    rigid: Query<Entity, (With<hall::Shuttle>, Without<AoField>)>,
    volumes: Query<(), With<VoxelAoVolume>>,
) {
    for mut ao in &mut ours {
        let mut wanted = ao.clone();
        FarTerm::select(far.0, &mut wanted);
        if (wanted.spheres, wanted.fields, wanted.voxels) != (ao.spheres, ao.fields, ao.voxels) {
            *ao = wanted;
        }
    }
    match far.0 {
        Some(FarTerm::Fields) if !rigid.is_empty() => {
            let rigid: Vec<Entity> = rigid.iter().collect();
            FarTerm::Fields.attach(&mut commands, &rigid, hall::bounds(), 0.0);
        }
        Some(FarTerm::Voxels) if volumes.is_empty() => {
            FarTerm::Voxels.attach(&mut commands, &[], hall::bounds(), 0.0);
        }
        _ => {}
    }
}

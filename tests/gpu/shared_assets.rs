//! The back-face layer on third-party skinned models from `../shared/assets` (or the folder in
//! `DYNAMIC_AO_SHARED_ASSETS`): an animated character has the same silhouette in both layers.
//! Skipped, with a message, where the folder is absent.

use std::path::PathBuf;

use bevy::gltf::{Gltf, GltfAssetLabel};
use bevy::prelude::*;
use bevy::world_serialization::{WorldAsset, WorldAssetRoot};
use bevy_dynamic_ao::prelude::*;

use crate::harness::{Gpu, SceneSpec};

fn shared_assets() -> Option<PathBuf> {
    let folder = std::env::var_os("DYNAMIC_AO_SHARED_ASSETS")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/assets"));
    if folder.join("Fox/Fox.glb").is_file() {
        Some(std::fs::canonicalize(folder).ok()?)
    } else {
        println!(
            "skipped: no shared assets at {} (set DYNAMIC_AO_SHARED_ASSETS)",
            folder.display()
        );
        None
    }
}

#[test]
fn animated_fox_has_the_same_silhouette_in_both_layers() {
    let Some(folder) = shared_assets() else {
        return;
    };
    // The fox model is about 150 units long; frame it from a few lengths away.
    let camera =
        Transform::from_xyz(120.0, 80.0, 160.0).looking_at(Vec3::new(0.0, 30.0, 0.0), Vec3::Y);
    let mut gpu = Gpu::with_asset_folder(
        &SceneSpec::new(camera),
        DynamicAo::default(),
        folder.to_str(),
    );
    let world = gpu.app.world_mut();
    let assets = world.resource::<AssetServer>().clone();
    let gltf: Handle<Gltf> = assets.load("Fox/Fox.glb");
    let scene: Handle<WorldAsset> = assets.load(GltfAssetLabel::Scene(0).from_asset("Fox/Fox.glb"));
    world.spawn(WorldAssetRoot(scene));
    // Load, then start the run cycle half a second in.
    let mut started = false;
    for _ in 0..400 {
        gpu.update(1);
        let world = gpu.app.world_mut();
        let Some(clip) = world
            .resource::<Assets<Gltf>>()
            .get(&gltf)
            .and_then(|g| g.animations.get(2).cloned())
        else {
            continue;
        };
        let players: Vec<Entity> = world
            .query_filtered::<Entity, With<AnimationPlayer>>()
            .iter(world)
            .collect();
        if players.is_empty() {
            continue;
        }
        let (graph, node) = AnimationGraph::from_clip(clip);
        let graph = world.resource_mut::<Assets<AnimationGraph>>().add(graph);
        for player in players {
            world
                .entity_mut(player)
                .insert(AnimationGraphHandle(graph.clone()));
            world
                .get_mut::<AnimationPlayer>(player)
                .unwrap()
                .play(node)
                .seek_to(0.5)
                .pause();
        }
        started = true;
        break;
    }
    assert!(started, "Fox.glb did not load");
    let frame = gpu.frame(8);
    let front: Vec<bool> = frame.nd.front.iter().map(|t| t.depth > 0.0).collect();
    let back: Vec<bool> = frame.nd.back.iter().map(|t| t.depth > 0.0).collect();
    let count = front.iter().filter(|f| **f).count();
    let differ = front.iter().zip(&back).filter(|(f, b)| f != b).count();
    println!("Fox: {count} front pixels, {differ} differ in the back layer");
    assert!(count > 500, "the fox should be in view ({count} pixels)");
    assert!(
        differ * 50 < count,
        "the layers' silhouettes differ in {differ} of {count} pixels"
    );
}

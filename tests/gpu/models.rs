//! Third-party glTF models from `../shared/assets` (or the folder in `DYNAMIC_AO_SHARED_ASSETS`)
//! loaded into a test app, posed, and stood on the floor the way a user's scene would hold them.
#![allow(dead_code)]

use std::path::PathBuf;

use bevy::gltf::{Gltf, GltfAssetLabel};
use bevy::prelude::*;
use bevy::world_serialization::{WorldAsset, WorldAssetRoot};
use bevy_dynamic_ao::reference::posed::{descendants, posed_triangles_of};

use crate::harness::Gpu;

/// The folder of shared third-party models, or `None` (with a message) where it is absent.
pub fn shared_assets() -> Option<PathBuf> {
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

/// Loads scene 0 of `file` (relative to the app's asset folder), plays animation `animation`
/// (if the file has it) paused at `time` seconds, and returns the scene root once the scene
/// and its players exist.
pub fn load_model(gpu: &mut Gpu, file: &str, animation: Option<usize>, time: f32) -> Entity {
    let world = gpu.app.world_mut();
    let assets = world.resource::<AssetServer>().clone();
    let gltf: Handle<Gltf> = assets.load(file.to_string());
    let scene: Handle<WorldAsset> =
        assets.load(GltfAssetLabel::Scene(0).from_asset(file.to_string()));
    let root = world
        .spawn((WorldAssetRoot(scene), Transform::default()))
        .id();
    for _ in 0..600 {
        gpu.update(1);
        let world = gpu.app.world_mut();
        let Some(gltf) = world.resource::<Assets<Gltf>>().get(&gltf) else {
            continue;
        };
        let clip = animation.and_then(|a| gltf.animations.get(a).cloned());
        let meshes = world
            .query_filtered::<Entity, With<Mesh3d>>()
            .iter(world)
            .count();
        if meshes == 0 {
            continue;
        }
        let players: Vec<Entity> = world
            .query_filtered::<Entity, With<AnimationPlayer>>()
            .iter(world)
            .collect();
        if let Some(clip) = clip {
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
                    .seek_to(time)
                    .pause();
            }
        }
        gpu.update(2);
        return root;
    }
    panic!("{file} did not load");
}

/// World-space bounds of the posed meshes below `root`.
pub fn posed_bounds(world: &mut World, root: Entity) -> (Vec3, Vec3) {
    let below = descendants(world, root);
    let scene = posed_triangles_of(world, |e| below.contains(&e));
    scene.bounds()
}

/// Scales and moves the model below `root` so that, posed, it is `height` metres tall and
/// stands on y = 0 centred over `at` (x, z). Returns its new bounds.
pub fn stand_on_floor(gpu: &mut Gpu, root: Entity, height: f32, at: Vec2) -> (Vec3, Vec3) {
    let (lo, hi) = posed_bounds(gpu.app.world_mut(), root);
    assert!(
        lo.is_finite() && hi.is_finite(),
        "the model has no triangles"
    );
    let scale = height / (hi.y - lo.y).max(1e-6);
    let centre = (lo + hi) * 0.5;
    let old = *gpu.app.world().get::<Transform>(root).unwrap();
    // p' = s p + t: bring the foot of the bounds' centre to (at.x, 0, at.y).
    let translation = Vec3::new(at.x, 0.0, at.y) - scale * Vec3::new(centre.x, lo.y, centre.z);
    let placed = Transform {
        translation: translation + scale * old.translation,
        rotation: old.rotation,
        scale: old.scale * scale,
    };
    gpu.app.world_mut().entity_mut(root).insert(placed);
    gpu.update(2);
    posed_bounds(gpu.app.world_mut(), root)
}

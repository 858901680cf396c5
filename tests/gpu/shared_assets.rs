//! The back-face layer on third-party skinned models from `../shared/assets` (or the folder in
//! `DYNAMIC_AO_SHARED_ASSETS`): an animated character has the same silhouette in both layers.
//! Skipped, with a message, where the folder is absent.

use bevy::prelude::*;

use crate::harness::{Gpu, SceneSpec, plain_ao};
use crate::models::{load_model, shared_assets};

#[test]
fn animated_fox_has_the_same_silhouette_in_both_layers() {
    let Some(folder) = shared_assets() else {
        return;
    };
    // The fox model is about 150 units long; frame it from a few lengths away.
    let camera =
        Transform::from_xyz(120.0, 80.0, 160.0).looking_at(Vec3::new(0.0, 30.0, 0.0), Vec3::Y);
    let mut gpu = Gpu::with_asset_folder(&SceneSpec::new(camera), plain_ao(), folder.to_str());
    // The run cycle, half a second in.
    load_model(&mut gpu, "Fox/Fox.glb", Some(2), 0.5);
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

//! The `ao_capture` example as scripts call it: a real process, its exit code, its files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bevy::prelude::*;

use crate::examples::example_binary;
use crate::gltf_scene;
use crate::harness::gpu_turn;

mod accuracy;
mod malformed;
mod options;

fn binary() -> PathBuf {
    example_binary("ao_capture")
}

fn run(args: &[&str]) -> Output {
    let _turn = gpu_turn();
    Command::new(binary())
        .args(args)
        .output()
        .expect("ao_capture runs")
}

/// `run`, asserting that the capture succeeded (its error output in the message otherwise).
fn run_ok(args: &[&str]) -> Output {
    let out = run(args);
    assert!(
        out.status.success(),
        "ao_capture {} failed:\n{}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The arguments of a capture of `scene` at `width` × `height` pixels, R = 0.75 m, with
/// `technique`, into `out_ao`.
fn capture_args(
    scene: &Path,
    (width, height): (u32, u32),
    technique: &str,
    out_ao: &Path,
) -> Vec<String> {
    let (width, height) = (width.to_string(), height.to_string());
    [
        "--scene",
        scene.to_str().unwrap(),
        "--width",
        &width,
        "--height",
        &height,
        "--radius",
        "0.75",
        "--technique",
        technique,
        "--out-ao",
        out_ao.to_str().unwrap(),
    ]
    .map(str::to_string)
    .to_vec()
}

fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cube_on_plane.glb")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dynamic_ao_{name}_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn committed_scene_is_what_the_generator_writes() {
    let (meshes, nodes) = gltf_scene::cube_on_plane();
    let committed = std::fs::read(scene_path()).expect("assets/scenes/cube_on_plane.glb");
    assert!(
        committed == gltf_scene::write_glb(&meshes, &nodes),
        "assets/scenes/cube_on_plane.glb is stale: run `cargo run --example generate_assets`"
    );
}

#[test]
fn committed_walker_is_what_the_generator_writes() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/characters/walker.glb");
    let committed = std::fs::read(path).expect("assets/characters/walker.glb");
    assert!(
        committed == crate::character::walker_glb(),
        "assets/characters/walker.glb is stale: run `cargo run --example generate_assets`"
    );
}

#[test]
fn committed_toasters_are_what_the_generator_writes() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/toasters.glb");
    let committed = std::fs::read(path).expect("assets/scenes/toasters.glb");
    assert!(
        committed == crate::toasters::toasters_glb(),
        "assets/scenes/toasters.glb is stale: run `cargo run --example generate_assets`"
    );
}

#[test]
fn lists_its_techniques() {
    let out = run(&["--technique", "list"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in [
        "default",
        "none",
        "near-field",
        "bevy-ssao",
        "spheres",
        "near-field+spheres",
        "fields",
        "near-field+fields",
        "voxels",
        "near-field+voxels",
        "default+spheres",
        "default+fields",
        "default+voxels",
    ] {
        assert!(
            text.lines().any(|l| l == name),
            "{name} missing from:\n{text}"
        );
    }
}

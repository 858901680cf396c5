//! Writes the project's generated assets under `assets/`.
//!
//! `cargo run --example generate_assets` rewrites `assets/scenes/cube_on_plane.glb`; the tests
//! check that the committed file is what this generator writes.

#[path = "common/gltf_scene.rs"]
mod gltf_scene;

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    std::fs::create_dir_all(&root).expect("create assets/scenes");
    let (meshes, nodes) = gltf_scene::cube_on_plane();
    let path = root.join("cube_on_plane.glb");
    std::fs::write(&path, gltf_scene::write_glb(&meshes, &nodes)).expect("write the scene");
    println!("wrote {}", path.display());
}

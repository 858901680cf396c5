//! Writes the project's generated assets under `assets/`.
//!
//! `cargo run --example generate_assets` rewrites `assets/scenes/cube_on_plane.glb`,
//! `assets/scenes/toasters.glb` and `assets/characters/walker.glb`; the tests check that the
//! committed files are what this generator writes.

#[path = "common/character.rs"]
mod character;
#[path = "common/gltf_scene.rs"]
mod gltf_scene;
#[path = "common/toasters.rs"]
mod toasters;

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let (meshes, nodes) = gltf_scene::cube_on_plane();
    let files = [
        (
            "scenes/cube_on_plane.glb",
            gltf_scene::write_glb(&meshes, &nodes),
        ),
        ("characters/walker.glb", character::walker_glb()),
        ("scenes/toasters.glb", toasters::toasters_glb()),
    ];
    for (name, bytes) in files {
        let path = root.join(name);
        std::fs::create_dir_all(path.parent().expect("a folder")).expect("create the folder");
        std::fs::write(&path, bytes).expect("write the asset");
        println!("wrote {}", path.display());
    }
}

//! AO field files through Bevy's asset server, and the `ao_bake` example as scripts call it.

use std::path::Path;
use std::process::Command;

use bevy::asset::LoadState;
use bevy::math::Affine3A;
use bevy::prelude::*;
use bevy_dynamic_ao::fields::{AoFieldData, BakeSettings, bake};
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::scene::TriangleScene;

use crate::examples::example_binary;
use crate::harness::{GPU_TURN, Gpu};
use crate::scenes;

fn small_field() -> AoFieldData {
    let mut scene = TriangleScene::default();
    scene.add_mesh(&Cuboid::new(1.0, 1.0, 1.0).into(), Affine3A::IDENTITY);
    let settings = BakeSettings {
        resolution: 4,
        rays: 32,
        ..default()
    };
    bake(scene.triangles, &settings, &|_, _| {}).expect("a cube bakes")
}

#[test]
fn aofield_files_load_or_fail_with_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("dynamic_ao_fields_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let field = small_field();
    let good = field.to_bytes();
    let mut corrupt = good.clone();
    corrupt[100] ^= 0x10;
    let mut wrong_version = good.clone();
    wrong_version[8] = 9;
    let files: [(&str, Vec<u8>, Option<&str>); 5] = [
        ("good.aofield", good.clone(), None),
        ("corrupt.aofield", corrupt, Some("checksum")),
        (
            "truncated.aofield",
            good[..good.len() / 2].to_vec(),
            Some("truncated"),
        ),
        ("old.aofield", wrong_version, Some("version 9")),
        (
            "text.aofield",
            b"hello, not a field".to_vec(),
            Some("not an AO field"),
        ),
    ];
    for (name, bytes, _) in &files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let mut gpu = Gpu::with_asset_folder(
        &scenes::cube_on_plane(),
        DynamicAo::default(),
        Some(dir.to_str().unwrap()),
    );
    let handles: Vec<Handle<AoFieldData>> = files
        .iter()
        .map(|(name, _, _)| gpu.app.world().resource::<AssetServer>().load(*name))
        .collect();
    let settled = |gpu: &Gpu| {
        let server = gpu.app.world().resource::<AssetServer>();
        handles.iter().all(|h| {
            matches!(
                server.get_load_state(h),
                Some(LoadState::Loaded | LoadState::Failed(_))
            )
        })
    };
    for _ in 0..300 {
        if settled(&gpu) {
            break;
        }
        gpu.update(1);
    }
    let server = gpu.app.world().resource::<AssetServer>();
    for ((name, _, expected), handle) in files.iter().zip(&handles) {
        match (server.get_load_state(handle), expected) {
            (Some(LoadState::Loaded), None) => {
                let loaded = gpu
                    .app
                    .world()
                    .resource::<Assets<AoFieldData>>()
                    .get(handle);
                assert_eq!(loaded, Some(&field), "{name} loads what was written");
            }
            (Some(LoadState::Failed(error)), Some(words)) => {
                let message = error.to_string();
                println!("{name}: {message}");
                assert!(
                    message.contains(words),
                    "{name}: '{message}' should say '{words}'"
                );
            }
            (state, _) => panic!("{name}: unexpected load state {state:?}"),
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn ao_bake_writes_a_loadable_field_per_mesh() {
    let binary = example_binary("ao_bake");
    let out = std::env::temp_dir().join(format!("dynamic_ao_bake_{}", std::process::id()));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cube_on_plane.glb");
    let run = |args: &[&str]| {
        let _turn = GPU_TURN.lock().unwrap_or_else(|p| p.into_inner());
        Command::new(&binary)
            .args(args)
            .output()
            .expect("ao_bake runs")
    };
    let result = run(&[
        "--scene",
        scene.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--resolution",
        "8",
        "--rays",
        "64",
    ]);
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "ao_bake failed:\n{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let summaries: Vec<&str> = stdout.lines().filter(|l| l.contains("-> ")).collect();
    assert_eq!(summaries.len(), 3, "one summary line per mesh:\n{stdout}");
    let mut fields = 0;
    for entry in std::fs::read_dir(&out).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        let field = AoFieldData::from_bytes(&bytes).expect("a valid field");
        assert_eq!(field.resolution, UVec3::splat(8));
        assert!(
            field.cells.iter().any(|c| c[0] > 0.1),
            "the field holds occlusion"
        );
        fields += 1;
    }
    assert_eq!(fields, 3);

    let missing = run(&["--scene", "no_such.glb", "--out-dir", out.to_str().unwrap()]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("not found"));
    let bad = run(&[
        "--scene",
        scene.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--resolution",
        "1",
    ]);
    assert_eq!(bad.status.code(), Some(2));
    std::fs::remove_dir_all(&out).ok();
}

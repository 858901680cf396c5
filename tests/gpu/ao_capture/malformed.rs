//! Malformed arguments and files: a one-line error and an exit code, or a warning and the rest of
//! the scene rendered as if the broken part were absent.

use std::path::{Path, PathBuf};

use bevy::prelude::*;
use bevy_dynamic_ao::reference::{metrics::rmse, png16::read_visibility_png};

use super::{capture_args, run, scene_path, temp_dir};
use crate::gltf_scene::{self, NodeKind};

#[test]
fn bad_input_gives_a_one_line_error() {
    let dir = temp_dir("capture_errors");
    let out_ao = dir.join("ao.png");
    let scene = scene_path();
    let scene = scene.to_str().unwrap();
    let base = |extra: &[&str]| {
        let mut args = vec![
            "--width",
            "32",
            "--height",
            "24",
            "--radius",
            "0.5",
            "--technique",
            "near-field",
        ];
        args.extend_from_slice(&["--out-ao", out_ao.to_str().unwrap()]);
        args.extend_from_slice(extra);
        args.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let no_camera = dir.join("no_camera.glb");
    let (meshes, nodes) = gltf_scene::cube_on_plane();
    let nodes: Vec<_> = nodes
        .into_iter()
        .filter(|n| !matches!(n.kind, NodeKind::Camera { .. }))
        .collect();
    std::fs::write(&no_camera, gltf_scene::write_glb(&meshes, &nodes)).unwrap();
    let corrupt = dir.join("corrupt.glb");
    std::fs::write(&corrupt, b"glTF\x02\0\0\0garbage").unwrap();
    // Two faults the glTF reader inside Bevy's loader panics on instead of reporting them.
    let missing_accessor = dir.join("missing_accessor.glb");
    std::fs::write(
        &missing_accessor,
        edit_glb(&scene_bytes(), |json| {
            json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 999.into();
        }),
    )
    .unwrap();
    let short_stride = dir.join("short_stride.glb");
    std::fs::write(
        &short_stride,
        edit_glb(&scene_bytes(), |json| {
            json["bufferViews"][0]["byteStride"] = 4.into();
        }),
    )
    .unwrap();
    // Accessors read as another shape than they hold, and an animation channel that moves a
    // node the file does not have: the glTF reader panics on each (`preflight.rs`).
    let misread = |name: &str, edit: fn(&mut serde_json::Value)| {
        let path = dir.join(format!("{name}.glb"));
        std::fs::write(&path, edit_glb(&scene_bytes(), edit)).unwrap();
        path
    };
    let float_indices = misread("float_indices", |json| {
        let indices = json["meshes"][0]["primitives"][0]["indices"]
            .as_u64()
            .unwrap() as usize;
        json["accessors"][indices]["componentType"] = 5126.into();
    });
    let missing_target = misread("missing_target", |json| {
        json["animations"][0]["channels"][0]["target"]["node"] = 999.into();
    });
    let vector_times = misread("vector_times", |json| {
        let sampler = &mut json["animations"][0]["samplers"][0];
        sampler["input"] = sampler["output"].clone();
    });
    let scalar_morph_target = misread("scalar_morph_target", |json| {
        let indices = json["meshes"][0]["primitives"][0]["indices"].clone();
        json["meshes"][0]["primitives"][0]["targets"] =
            serde_json::json!([{ "POSITION": indices }]);
    });
    let weights_of_vectors = misread("weights_of_vectors", |json| {
        json["animations"][0]["channels"][0]["target"]["path"] = "weights".into();
    });
    // A camera with no view direction: Bevy's frustum update panics on it (with debug
    // assertions), or renders a view of nothing.
    let flat_camera = dir.join("flat_camera.glb");
    std::fs::write(
        &flat_camera,
        edit_glb(&scene_bytes(), |json| {
            for node in json["nodes"].as_array_mut().unwrap() {
                if node.get("camera").is_some() {
                    node["scale"] = serde_json::json!([0.0, 0.0, 0.0]);
                }
            }
        }),
    )
    .unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (base(&["--scene", "/nonexistent/scene.glb"]), "not found"),
        (
            [
                base(&["--scene", scene]),
                vec!["--width".into(), "abc".into()],
            ]
            .concat(),
            "--width",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--radius".into(), "-1".into()],
            ]
            .concat(),
            "--radius",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--height".into(), "100000".into()],
            ]
            .concat(),
            "--height",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--blur".into(), "99".into()],
            ]
            .concat(),
            "--blur takes a number from 0 to",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--thickness".into(), "2".into()],
            ]
            .concat(),
            "--thickness takes a number from 0 to 1",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--blur-sharpness".into(), "NaN".into()],
            ]
            .concat(),
            "--blur-sharpness takes a number",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--blur-normal-sharpness".into(), "-1".into()],
            ]
            .concat(),
            "--blur-normal-sharpness takes a number",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--near-field-radius".into(), "0".into()],
            ]
            .concat(),
            "--near-field-radius takes a positive number",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--voxel-accumulated-blur".into(), "17".into()],
            ]
            .concat(),
            "--voxel-accumulated-blur takes a number from 0 to",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--history-frames".into(), "0".into()],
            ]
            .concat(),
            "--history-frames takes a number from 1 to 64",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--technique".into(), "magic".into()],
            ]
            .concat(),
            "unknown technique",
        ),
        (
            [base(&["--scene", scene]), vec!["--msaa".into(), "3".into()]].concat(),
            "--msaa takes 1 or 4",
        ),
        (
            [
                base(&["--scene", scene]),
                ["--technique", "bevy-ssao", "--msaa", "4"]
                    .map(String::from)
                    .to_vec(),
            ]
            .concat(),
            "bevy-ssao needs --msaa 1",
        ),
        (base(&["--scene", no_camera.to_str().unwrap()]), "no camera"),
        (base(&["--scene", corrupt.to_str().unwrap()]), "cannot load"),
        (
            base(&["--scene", missing_accessor.to_str().unwrap()]),
            "names an object it does not have",
        ),
        (
            base(&["--scene", short_stride.to_str().unwrap()]),
            "reads elements of 12 bytes through buffer view 0, whose stride is 4 bytes",
        ),
        (
            base(&["--scene", flat_camera.to_str().unwrap()]),
            "the first camera's node has a zero scale",
        ),
        (
            base(&["--scene", float_indices.to_str().unwrap()]),
            "which holds SCALAR of FLOAT; indices are single unsigned integers",
        ),
        (
            base(&["--scene", missing_target.to_str().unwrap()]),
            "channel 0 of animation 0 moves node 999, and the file has 4 nodes",
        ),
        (
            base(&["--scene", vector_times.to_str().unwrap()]),
            "which holds VEC3 of FLOAT; key times are single floats",
        ),
        (
            base(&["--scene", scalar_morph_target.to_str().unwrap()]),
            "which holds SCALAR of UNSIGNED_INT; a morph target's POSITION is VEC3 of FLOAT",
        ),
        (
            base(&["--scene", weights_of_vectors.to_str().unwrap()]),
            "animates morph target weights from accessor",
        ),
    ];
    for (args, expected) in cases {
        let out = run(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !stderr.contains("panicked"),
            "{args:?}: nothing may panic:\n{stderr}"
        );
        let ours: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with("ao_capture:"))
            .collect();
        assert!(!out.status.success(), "{args:?} should fail");
        assert_eq!(
            ours.len(),
            1,
            "{args:?}: expected one error line, got:\n{stderr}"
        );
        assert!(
            ours[0].contains(expected),
            "{args:?}: '{}' should mention '{expected}'",
            ours[0]
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The committed generated scene's bytes.
fn scene_bytes() -> Vec<u8> {
    std::fs::read(scene_path()).expect("assets/scenes/cube_on_plane.glb")
}

/// `glb` with its JSON chunk changed by `edit` (the binary chunk kept).
fn edit_glb(glb: &[u8], edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_len = word(12);
    let mut json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    edit(&mut json);
    let mut json = serde_json::to_vec(&json).unwrap();
    json.resize(json.len().next_multiple_of(4), b' ');
    let bin = &glb[20 + json_len..];
    let mut out = Vec::new();
    out.extend_from_slice(&glb[0..8]);
    out.extend_from_slice(&((12 + 8 + json.len() + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&glb[16..20]);
    out.extend_from_slice(&json);
    out.extend_from_slice(bin);
    out
}

/// A 64 × 48 near-field capture of `scene` into `out_ao`, which must succeed; its stderr.
fn capture_near_field(scene: &Path, out_ao: &Path) -> String {
    capture_small(scene, out_ao, "near-field")
}

/// A 64 × 48 capture of `scene` with `technique` into `out_ao`, which must succeed; its stderr.
fn capture_small(scene: &Path, out_ao: &Path, technique: &str) -> String {
    let args = capture_args(scene, (64, 48), technique, out_ao);
    let out = run(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "{}: capture failed:\n{stderr}",
        scene.display()
    );
    stderr
}

/// The generated scene without its cube (mesh 1), written into `dir`: what a capture that leaves
/// the cube out must match.
fn generated_scene_without_its_cube(dir: &Path) -> PathBuf {
    let without = dir.join("without.glb");
    let (meshes, nodes) = gltf_scene::cube_on_plane();
    let nodes: Vec<_> = nodes
        .into_iter()
        .filter(|n| !matches!(n.kind, NodeKind::Mesh(1)))
        .collect();
    std::fs::write(&without, gltf_scene::write_glb(&meshes, &nodes)).unwrap();
    without
}

/// A primitive whose positions cannot be read (its accessor runs past its buffer) loads as a mesh
/// without positions, which Bevy's prepass pipeline fails wgpu's validation on: the capture leaves
/// that mesh out with a warning naming it and renders the rest, as the same scene without it.
#[test]
fn a_mesh_without_readable_positions_is_left_out_with_a_warning() {
    let dir = temp_dir("capture_unreadable_positions");
    let broken = dir.join("broken.glb");
    // Accessor 3 holds the cube's positions.
    std::fs::write(
        &broken,
        edit_glb(&scene_bytes(), |json| {
            json["accessors"][3]["count"] = 24_000.into();
        }),
    )
    .unwrap();
    let without = generated_scene_without_its_cube(&dir);
    let capture = |scene: &Path, name: &str| {
        let out_ao = dir.join(name);
        let stderr = capture_near_field(scene, &out_ao);
        (
            read_visibility_png(&out_ao).expect("the capture's PNG").2,
            stderr,
        )
    };
    let (broken_image, log) = capture(&broken, "broken.png");
    let warnings: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("is left out: it has no readable POSITION attribute"))
        .collect();
    assert_eq!(warnings.len(), 1, "one warning, naming the mesh:\n{log}");
    assert!(!log.contains("panicked"), "nothing may panic:\n{log}");
    let (expected, _) = capture(&without, "without.png");
    let darkest = expected.iter().copied().fold(1.0f32, f32::min);
    assert!(
        darkest < 0.9,
        "the pillar occludes the floor in the scene without the cube: darkest {darkest}"
    );
    let error = rmse(&broken_image, &expected, None);
    assert!(
        error < 1e-4,
        "the rest of the scene renders as without the broken mesh: RMSE {error}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A mesh of lines (or points) has no triangles to bake an AO field from: `--technique fields`
/// says so once for it and captures the rest, instead of waiting for a field that never comes
/// (it waited out its 15-minute bake limit and failed).
#[test]
fn a_mesh_without_triangles_does_not_hold_up_a_fields_capture() {
    let dir = temp_dir("capture_fields_without_triangles");
    let lines = dir.join("lines.glb");
    // Mesh 1 is the cube.
    std::fs::write(
        &lines,
        edit_glb(&scene_bytes(), |json| {
            json["meshes"][1]["primitives"][0]["mode"] = 1.into();
        }),
    )
    .unwrap();
    let without = generated_scene_without_its_cube(&dir);
    let log = capture_small(&lines, &dir.join("lines.png"), "fields");
    assert!(!log.contains("panicked"), "nothing may panic:\n{log}");
    let warnings: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("casts no field: the object has no usable triangle"))
        .collect();
    assert_eq!(warnings.len(), 1, "one warning, for the cube:\n{log}");
    capture_small(&without, &dir.join("without.png"), "fields");
    let read = |name: &str| read_visibility_png(&dir.join(name)).expect("a PNG").2;
    let (with_lines, expected) = (read("lines.png"), read("without.png"));
    let darkest = expected.iter().copied().fold(1.0f32, f32::min);
    assert!(
        darkest < 0.9,
        "the pillar's field occludes the floor: darkest {darkest}"
    );
    // The cube's edges, drawn as lines, are the only pixels that may differ (measured: 43 of
    // 3072).
    let differing = with_lines
        .iter()
        .zip(&expected)
        .filter(|(a, b)| (*a - *b).abs() > 0.01)
        .count();
    println!("pixels that differ from the scene without the cube: {differing}");
    assert!(
        differing * 40 < expected.len(),
        "{differing} of {} pixels differ from the scene without the cube",
        expected.len()
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A skinned node whose mesh has no joint indices fails Bevy's skinned draw (wgpu's validation
/// ends the app): the capture draws it unskinned, in its rest pose, with a warning naming it.
#[test]
fn a_skinned_mesh_without_joints_is_drawn_unskinned_with_a_warning() {
    let dir = temp_dir("capture_unskinnable");
    let walker =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/characters/walker.glb"))
            .expect("assets/characters/walker.glb");
    let broken = dir.join("walker_without_joints.glb");
    std::fs::write(
        &broken,
        edit_glb(&walker, |json| {
            json["meshes"][0]["primitives"][0]["attributes"]
                .as_object_mut()
                .unwrap()
                .remove("JOINTS_0");
            json["cameras"] = serde_json::json!([
                { "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }
            ]);
            let nodes = json["nodes"].as_array_mut().unwrap();
            nodes.push(serde_json::json!({ "camera": 0, "translation": [0.0, 1.0, 4.0] }));
            let camera = nodes.len() - 1;
            json["scenes"][0]["nodes"]
                .as_array_mut()
                .unwrap()
                .push(camera.into());
        }),
    )
    .unwrap();
    let out_ao = dir.join("ao.png");
    let log = capture_near_field(&broken, &out_ao);
    assert!(!log.contains("panicked"), "nothing may panic:\n{log}");
    let warnings = log
        .lines()
        .filter(|l| {
            l.contains("is drawn unskinned, in its rest pose: its mesh has no readable JOINTS_0")
        })
        .count();
    assert_eq!(warnings, 1, "one warning, naming the mesh:\n{log}");
    let (_, _, visibility) = read_visibility_png(&out_ao).expect("the capture's PNG");
    let shown = visibility.iter().filter(|v| **v < 0.999).count();
    assert!(shown > 0, "the walker's rest pose shows occlusion");
    std::fs::remove_dir_all(&dir).ok();
}

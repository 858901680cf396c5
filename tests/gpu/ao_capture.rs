//! The `ao_capture` example as scripts call it: a real process, its exit code, its files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bevy::asset::RenderAssetUsages;
use bevy::camera::{CameraProjection, PerspectiveProjection};
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use bevy_dynamic_ao::reference::{
    bvh::Bvh,
    ground_truth::{GroundTruthSettings, ground_truth_visibility},
    metrics::rmse,
    nd_buffer::ViewMatrices,
    png16::read_visibility_png,
    scene::TriangleScene,
};

use crate::examples::example_binary;
use crate::gltf_scene::{self, NodeKind};
use crate::harness::GPU_TURN;

fn binary() -> PathBuf {
    example_binary("ao_capture")
}

fn run(args: &[&str]) -> Output {
    let _turn = GPU_TURN
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    Command::new(binary())
        .args(args)
        .output()
        .expect("ao_capture runs")
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
        "none",
        "near-field",
        "bevy-ssao",
        "spheres",
        "near-field+spheres",
        "fields",
        "near-field+fields",
        "voxels",
        "near-field+voxels",
    ] {
        assert!(
            text.lines().any(|l| l == name),
            "{name} missing from:\n{text}"
        );
    }
}

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
            "--blur",
        ),
        (
            [
                base(&["--scene", scene]),
                vec!["--technique".into(), "magic".into()],
            ]
            .concat(),
            "unknown technique",
        ),
        (base(&["--scene", no_camera.to_str().unwrap()]), "no camera"),
        (base(&["--scene", corrupt.to_str().unwrap()]), "cannot load"),
    ];
    for (args, expected) in cases {
        let out = run(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let stderr = String::from_utf8_lossy(&out.stderr);
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

/// The generated scene posed at `time`, as triangles, and its camera.
fn generated_scene(time: f32, width: u32, height: u32) -> (Bvh, ViewMatrices) {
    let (meshes, nodes) = gltf_scene::cube_on_plane();
    let mut scene = TriangleScene::default();
    let mut view = None;
    for node in &nodes {
        let mut transform = node.transform;
        if let [(t0, a), (t1, b)] = node.animation[..] {
            transform.translation = a.lerp(b, ((time - t0) / (t1 - t0)).clamp(0.0, 1.0));
        }
        match node.kind {
            NodeKind::Mesh(index) => {
                let data = &meshes[index];
                let mesh = Mesh::new(
                    PrimitiveTopology::TriangleList,
                    RenderAssetUsages::default(),
                )
                .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, data.positions.clone())
                .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, data.normals.clone())
                .with_inserted_indices(Indices::U32(data.indices.clone()));
                scene.add_mesh(&mesh, transform.compute_affine());
            }
            NodeKind::Camera { yfov } => {
                let projection = PerspectiveProjection {
                    fov: yfov,
                    aspect_ratio: width as f32 / height as f32,
                    near: 0.05,
                    ..default()
                };
                view = Some(ViewMatrices::new(
                    transform.to_matrix(),
                    projection.get_clip_from_view(),
                ));
            }
        }
    }
    (
        Bvh::new(scene.triangles),
        view.expect("the scene has a camera"),
    )
}

#[test]
fn captures_the_generated_scene_close_to_ground_truth() {
    let dir = temp_dir("capture");
    let (w, h, radius, time) = (160u32, 120u32, 0.75f32, 1.0f32);
    let capture = |technique: &str| {
        let out_ao = dir.join(format!("{technique}.png"));
        let out_color = dir.join(format!("{technique}_color.png"));
        let out = run(&[
            "--scene",
            scene_path().to_str().unwrap(),
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--radius",
            &radius.to_string(),
            "--technique",
            technique,
            "--time",
            &time.to_string(),
            "--out-ao",
            out_ao.to_str().unwrap(),
            "--out-color",
            out_color.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "ao_capture failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out_color.is_file(), "--out-color wrote nothing");
        let (iw, ih, ao) = read_visibility_png(&out_ao).expect("a 16-bit grayscale PNG");
        assert_eq!((iw, ih), (w, h));
        ao
    };
    let none = capture("none");
    assert!(
        none.iter().all(|v| *v == 1.0),
        "technique none must be all open"
    );

    let ours = capture("near-field");
    let (bvh, view) = generated_scene(time, w, h);
    let truth = ground_truth_visibility(
        &bvh,
        &view,
        &GroundTruthSettings {
            width: w,
            height: h,
            radius,
            rays_per_pixel: 256,
        },
    );
    // Where ground truth sees no geometry, the capture must say open.
    let sky: Vec<bool> = (0..truth.len())
        .map(|i| {
            let (origin, dir) = bevy_dynamic_ao::reference::ground_truth::camera_ray(
                &view,
                (i as u32) % w,
                (i as u32) / w,
                w,
                h,
            );
            bvh.closest_hit(origin, dir, 0.0, f32::INFINITY).is_none()
        })
        .collect();
    let sky_count = sky.iter().filter(|s| **s).count();
    assert!(
        sky_count > 100,
        "the camera should see some sky ({sky_count})"
    );
    let sky_open = ours
        .iter()
        .zip(&sky)
        .filter(|(v, s)| **s && **v == 1.0)
        .count();
    assert!(
        sky_open as f32 > 0.98 * sky_count as f32,
        "sky pixels must be 65535 ({sky_open}/{sky_count})"
    );
    let error = rmse(&ours, &truth, None);
    println!(
        "ao_capture near-field on the generated scene at t = {time} s: RMSE {error:.4} vs ground truth"
    );
    assert!(error < 0.15, "RMSE {error} against ground truth");
    // The pose matters: the cube slid to x = 0 by t = 1 s, so the floor crease follows it.
    let (bvh0, _) = generated_scene(0.0, w, h);
    let truth0 = ground_truth_visibility(
        &bvh0,
        &view,
        &GroundTruthSettings {
            width: w,
            height: h,
            radius,
            rays_per_pixel: 64,
        },
    );
    assert!(
        rmse(&ours, &truth, None) < rmse(&ours, &truth0, None),
        "the capture ignored --time"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `spheres` puts a `SphereOccluder` on every mesh of the scene: the far field alone darkens the
/// floor around the cube and the pillar like ground truth does, and added to the near field it
/// brings the capture closer to ground truth over a radius wider than the near field's.
#[test]
fn captures_the_far_field_of_the_generated_scene() {
    let dir = temp_dir("capture_spheres");
    let (w, h, radius, time) = (160u32, 120u32, 0.75f32, 1.0f32);
    let capture_falloff = |technique: &str, blend: &str, falloff: &str| {
        let out_ao = dir.join(format!("{technique}_{blend}_{falloff}.png"));
        let out = run(&[
            "--scene",
            scene_path().to_str().unwrap(),
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--radius",
            &radius.to_string(),
            "--technique",
            technique,
            "--far-blend",
            blend,
            "--voxel-falloff",
            falloff,
            "--time",
            &time.to_string(),
            "--out-ao",
            out_ao.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "ao_capture {technique} failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains(&format!("technique {technique} ")),
            "{stdout}"
        );
        read_visibility_png(&out_ao)
            .expect("a 16-bit grayscale PNG")
            .2
    };
    let capture_with = |technique: &str, blend: &str| capture_falloff(technique, blend, "wendland");
    let capture = |technique: &str| capture_with(technique, "add");
    let spheres = capture("spheres");
    let near = capture("near-field");
    let both = capture("near-field+spheres");
    let fields = capture("fields");
    let near_fields = capture("near-field+fields");
    let near_fields_max = capture_with("near-field+fields", "max");
    let (bvh, view) = generated_scene(time, w, h);
    let truth = |radius: f32| {
        ground_truth_visibility(
            &bvh,
            &view,
            &GroundTruthSettings {
                width: w,
                height: h,
                radius,
                rays_per_pixel: 256,
            },
        )
    };
    let (truth_near, truth_wide) = (truth(radius), truth(2.0));
    let report = |name: &str, v: &[f32]| {
        let (a, b) = (rmse(v, &truth_near, None), rmse(v, &truth_wide, None));
        println!(
            "ao_capture {name}: RMSE {a:.4} vs ground truth R = {radius} m, {b:.4} vs R = 2 m"
        );
        (a, b)
    };
    let (_, spheres_wide) = report("spheres", &spheres);
    let (_, near_wide) = report("near-field", &near);
    let (_, both_wide) = report("near-field+spheres", &both);
    let (_, fields_wide) = report("fields", &fields);
    let (_, near_fields_wide) = report("near-field+fields", &near_fields);
    let (_, near_fields_max_wide) = report("near-field+fields, max blend", &near_fields_max);
    // Fields see every box whole, the floor included: over the wide radius they alone come
    // closer to ground truth than the near field. Added to it they count the near boxes twice;
    // the max blend does not.
    assert!(
        fields_wide < near_wide,
        "fields {fields_wide} vs near field {near_wide}"
    );
    assert!(near_fields_max_wide < near_wide);
    assert!(near_fields_max_wide < near_fields_wide);
    // Beyond the near field's radius the floor still receives occlusion from the cube and the
    // pillar (ground truth over 2 m); the near field shows none there, the far field does.
    let beyond: Vec<usize> = (0..truth_wide.len())
        .filter(|&i| {
            let (origin, dir) = bevy_dynamic_ao::reference::ground_truth::camera_ray(
                &view,
                (i as u32) % w,
                (i as u32) / w,
                w,
                h,
            );
            let on_floor = bvh
                .closest_hit(origin, dir, 0.0, f32::INFINITY)
                .is_some_and(|hit| (origin + dir * hit.t).y.abs() < 1e-3);
            on_floor && near[i] > 0.995 && truth_wide[i] < 0.95
        })
        .collect();
    assert!(beyond.len() > 200, "{} floor pixels beyond R", beyond.len());
    let mean = |v: &[f32]| beyond.iter().map(|&i| 1.0 - v[i]).sum::<f32>() / beyond.len() as f32;
    println!(
        "floor beyond the near field's reach ({} pixels), mean occlusion: ground truth {:.3}, \
         spheres {:.3}, fields {:.3}, near field {:.3}",
        beyond.len(),
        mean(&truth_wide),
        mean(&spheres),
        mean(&fields),
        mean(&near)
    );
    // Inscribed spheres fill only part of a box, and each is cut off at its reach d_far, so
    // the far field finds a part of this occlusion, not all of it.
    assert!(
        mean(&spheres) > 0.1 * mean(&truth_wide) && mean(&spheres) > 5.0 * mean(&near),
        "the far field misses occlusion beyond the near field's radius"
    );
    assert!(spheres_wide < rmse(&vec![1.0; spheres.len()], &truth_wide, None));
    assert!(
        both_wide < near_wide,
        "adding the far field should bring the capture closer to wide ground truth"
    );

    // `voxels` puts one volume around the scene with d_max = R: it sees every box whole and
    // the floor, within the same radius as the near field. Wendland's falloff (the default, as
    // published) weights far hits down, so it finds less than ground truth, which counts every
    // hit within R; without falloff it estimates ground truth's own quantity.
    let (near_near, _) = report("near-field", &near);
    let (wendland, _) = report("voxels", &capture("voxels"));
    let unweighted = capture_falloff("voxels", "add", "none");
    let (unweighted_near, _) = report("voxels, no falloff", &unweighted);
    assert!(
        unweighted.iter().any(|v| *v < 0.8),
        "the voxels should darken the scene"
    );
    assert!(
        unweighted_near < wendland && unweighted_near < near_near,
        "no-falloff voxels {unweighted_near} vs ground truth"
    );
    println!("near field alone: {near_near:.4}");
    std::fs::remove_dir_all(&dir).ok();
}

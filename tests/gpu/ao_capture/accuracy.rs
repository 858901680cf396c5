//! Captures of the generated scene held against the CPU ray tracer, near and far field.

use bevy::asset::RenderAssetUsages;
use bevy::camera::{CameraProjection, PerspectiveProjection};
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use bevy_dynamic_ao::geometry::{bvh::Bvh, triangles::TriangleScene};
use bevy_dynamic_ao::reference::{
    ground_truth::{GroundTruthSettings, geometry_mask},
    metrics::{high_frequency_error, rmse},
    nd_buffer::ViewMatrices,
    png16::read_visibility_png,
};

use super::{run_ok, scene_path, temp_dir};
use crate::gltf_scene::{self, NodeKind};
use crate::harness::ground_truth;

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

/// The near field captured from the generated scene against the CPU ray tracer; `--out-truth`
/// writes that same ground truth (the tracer on the same posed scene and view) and prints the
/// capture's RMSE against it over the pixels that show geometry.
#[test]
fn captures_the_generated_scene_close_to_ground_truth() {
    let dir = temp_dir("capture");
    let (w, h, radius, time) = (160u32, 120u32, 0.75f32, 1.0f32);
    let out_truth = dir.join("truth.png");
    let capture = |technique: &str, extra: &[&str]| {
        let out_ao = dir.join(format!("{technique}.png"));
        let out_color = dir.join(format!("{technique}_color.png"));
        let (scene, numbers) = (scene_path(), [w, h].map(|n| n.to_string()));
        let (radius, time) = (radius.to_string(), time.to_string());
        let mut args = vec![
            "--scene",
            scene.to_str().unwrap(),
            "--width",
            &numbers[0],
            "--height",
            &numbers[1],
            "--radius",
            &radius,
            "--technique",
            technique,
            "--time",
            &time,
            "--out-ao",
            out_ao.to_str().unwrap(),
            "--out-color",
            out_color.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = run_ok(&args);
        assert!(out_color.is_file(), "--out-color wrote nothing");
        let (iw, ih, ao) = read_visibility_png(&out_ao).expect("a 16-bit grayscale PNG");
        assert_eq!((iw, ih), (w, h));
        (ao, String::from_utf8_lossy(&out.stdout).into_owned())
    };
    let (none, _) = capture("none", &[]);
    assert!(
        none.iter().all(|v| *v == 1.0),
        "technique none must be all open"
    );

    let (ours, stdout) = capture("near-field", &["--out-truth", out_truth.to_str().unwrap()]);
    let (bvh, view) = generated_scene(time, w, h);
    let truth = ground_truth(
        &bvh,
        &view,
        &GroundTruthSettings {
            width: w,
            height: h,
            radius,
            rays_per_pixel: 256,
        },
    );
    let written = read_visibility_png(&out_truth)
        .expect("--out-truth's PNG")
        .2;
    let difference = rmse(&written, &truth, None);
    println!("--out-truth against the tests' ground truth: RMSE {difference:.5}");
    // Measured: 0.00000 (16-bit quantization aside).
    assert!(difference < 0.001, "--out-truth: RMSE {difference}");
    let geometry = geometry_mask(&bvh, &view, w, h);
    let printed: f32 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("ground truth: "))
        .and_then(|l| l.split("RMSE of the capture ").nth(1))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|number| number.parse().ok())
        .unwrap_or_else(|| panic!("no ground-truth RMSE in:\n{stdout}"));
    let over_geometry = rmse(&ours, &truth, Some(&geometry));
    assert!(
        (printed - over_geometry).abs() < 0.001,
        "printed RMSE {printed} against {over_geometry} over the geometry pixels"
    );
    let printed_detail: f32 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("ground truth: "))
        .and_then(|l| l.split("high-frequency error ").nth(1))
        .and_then(|number| number.trim().parse().ok())
        .unwrap_or_else(|| panic!("no high-frequency error in:\n{stdout}"));
    let detail = high_frequency_error(&ours, &truth, w, h, Some(&geometry));
    assert!(
        detail > 0.0 && (printed_detail - detail).abs() < 0.001,
        "printed high-frequency error {printed_detail} against {detail} over the geometry pixels"
    );
    // Where ground truth sees no geometry, the capture must say open.
    let sky: Vec<bool> = geometry.iter().map(|g| !g).collect();
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
    let truth0 = ground_truth(
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

/// The far-field techniques as scripts call them: every mesh of the scene an occluder (proxies,
/// fields baked on load, one voxel volume over what the view needs), joined to the near field
/// and to the default (`default+TERM`) with the default blend. Against ground truth at the
/// capture's radius: better than either alone at 0.75 m, and far better at 2 m, where the near
/// field's samples stand for large patches and the ray march's reach ends at the screen's edge. The paper's options (`--far-blend add`, `--voxel-falloff wendland`) stay
/// available and do worse.
#[test]
fn captures_the_far_field_of_the_generated_scene() {
    let dir = temp_dir("capture_far");
    let (w, h, time) = (160u32, 120u32, 1.0f32);
    let scene = scene_path();
    let capture = |technique: &str, radius: f32, extra: &[&str]| {
        let out_ao = dir.join(format!("{technique}_{radius}_{}.png", extra.join("_")));
        let radius_text = radius.to_string();
        let mut args = vec![
            "--scene",
            scene.to_str().unwrap(),
            "--width",
            "160",
            "--height",
            "120",
            "--radius",
            &radius_text,
            "--technique",
            technique,
            "--time",
            "1",
            "--out-ao",
            out_ao.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = run_ok(&args);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains(&format!("technique {technique} ")),
            "{stdout}"
        );
        read_visibility_png(&out_ao)
            .expect("a 16-bit grayscale PNG")
            .2
    };
    let (bvh, view) = generated_scene(time, w, h);
    for radius in [0.75f32, 2.0] {
        let truth = ground_truth(
            &bvh,
            &view,
            &GroundTruthSettings {
                width: w,
                height: h,
                radius,
                rays_per_pixel: 256,
            },
        );
        let error = |v: &[f32]| rmse(v, &truth, None);
        let near = error(&capture("near-field", radius, &[]));
        println!("ao_capture, R = {radius} m: near-field RMSE {near:.4}");
        for term in ["spheres", "fields", "voxels"] {
            let joined = error(&capture(&format!("near-field+{term}"), radius, &[]));
            println!("  near-field+{term} {joined:.4}");
            // Measured: 0.66–0.72 × the near field's RMSE at 0.75 m (0.60–0.64 × while the
            // accumulated near field was still blurred), 0.28–0.32 × at 2 m (0.24–0.28 ×); the
            // voxels' 0.32 at 2 m since the upsampling weighs the distance from the pixel's
            // plane (0.319 before).
            let bound = if radius < 1.0 { 0.73 } else { 0.33 };
            assert!(
                joined <= bound * near,
                "{term} at {radius} m: {joined} vs {near}"
            );
            // The blend is the same arithmetic at any radius: one radius shows it.
            if radius < 1.0 {
                let added = error(&capture(
                    &format!("near-field+{term}"),
                    radius,
                    &["--far-blend", "add"],
                ));
                println!("  with --far-blend add {added:.4}");
                assert!(added > joined, "adding counts in-view occluders twice");
            }
        }
        // What `DynamicAo::default()` runs (the accumulated ray march) with each term joined.
        let default = error(&capture("default", radius, &[]));
        println!("ao_capture, R = {radius} m: default RMSE {default:.4}");
        // Measured: 0.0094 at 0.75 m, 0.0168 at 2 m at full resolution, which the default runs
        // at this size (`DynamicAo::small_viewport_pixels`). At half resolution: 0.0097 at
        // 0.75 m, 0.0175 at 2 m since the last step lies at R (0.0105 /
        // 0.0190 before; 0.0136 / 0.0488 before steps just behind the back-face layer counted
        // as blocked, `RayMarchParams::thickness`). The scene's floor
        // is a slab: with each pixel's farthest back face in the ray march's layer, the air
        // between a box and the slab's underside behind it read as solid, and this read 0.0467 /
        // 0.0560 (BENCHMARKS.md, "DamagedHelmet close up", tried and not kept).
        let bound = if radius < 1.0 { 0.0103 } else { 0.0185 };
        assert!(
            default < bound,
            "the default at {radius} m: RMSE {default:.4} against ground truth"
        );
        for term in ["spheres", "fields", "voxels"] {
            let joined = error(&capture(&format!("default+{term}"), radius, &[]));
            println!("  default+{term} {joined:.4}");
            // Measured at full resolution, which the default runs at this size
            // (`DynamicAo::small_viewport_pixels`): 0.76–0.94 × the default's RMSE at 0.75 m,
            // 0.57–0.79 × at 2 m (the default alone 0.0094 and 0.0168). At half resolution:
            // 0.81–0.92 × the default's RMSE at 0.75 m, 0.58–0.75 × at 2 m since the
            // default's last step lies at R, which lowered the default alone and not the joined
            // figures (0.84–0.95 and 0.62–0.71 before; 0.89–0.94 and 0.35–0.37 against the default
            // before the thickness, which itself gained most at 2 m; joined, the error fell at
            // both radii). At 0.75 m the default alone is within 0.0097 of the truth here, and the
            // terms join it at 0.0079–0.0089: no term may raise it.
            let bound = if radius < 1.0 { 1.0 } else { 0.8 };
            assert!(
                joined <= bound * default,
                "default+{term} at {radius} m: {joined} vs {default}"
            );
        }
        if radius > 1.0 {
            let wendland = error(&capture("voxels", radius, &["--voxel-falloff", "wendland"]));
            let none = error(&capture("voxels", radius, &[]));
            println!("  voxels with Wendland's falloff {wendland:.4}, without {none:.4}");
            assert!(
                none < wendland,
                "the default falloff estimates ground truth's quantity"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

//! The capture's options as a script uses them: `--technique default`, `--timings`, `--compare`.

use std::path::Path;

use bevy::prelude::*;
use bevy_dynamic_ao::reference::png16::read_visibility_png;

use super::{capture_args, run, run_ok, scene_path, temp_dir};

/// Captures cube on plane at 96 × 72 with `technique` and `extra` options into `dir`: the AO
/// image, and stdout and stderr together, as a script that merges them reads them.
fn capture(dir: &Path, technique: &str, extra: &[&str]) -> (Vec<f32>, String) {
    let out_ao = dir.join(format!("{technique}.png"));
    let mut args = capture_args(&scene_path(), (96, 72), technique, &out_ao);
    args.extend(extra.iter().map(|a| a.to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = run_ok(&args);
    // Both streams, as a script that merges them reads them.
    let text = format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (read_visibility_png(&out_ao).expect("a PNG").2, text)
}

/// The `ao_gpu_ms`, `frame_gpu_ms` and `frames` of the one `timings:` line in `text`, which
/// must also name each pass's span (on stderr).
fn timings(text: &str) -> (f64, f64, u32) {
    let lines: Vec<&str> = text.lines().filter(|l| l.contains("timings:")).collect();
    assert_eq!(lines.len(), 1, "exactly one timings line in:\n{text}");
    assert!(lines[0].starts_with("timings: "), "{}", lines[0]);
    assert!(
        text.contains("gpu span "),
        "each pass's mean goes to stderr:\n{text}"
    );
    let field = |key: &str| -> String {
        lines[0]
            .split_whitespace()
            .find_map(|w| w.strip_prefix(&format!("{key}=")))
            .unwrap_or_else(|| panic!("{key} missing from {}", lines[0]))
            .to_string()
    };
    (
        field("ao_gpu_ms").parse().unwrap(),
        field("frame_gpu_ms").parse().unwrap(),
        field("frames").parse().unwrap(),
    )
}

/// A capture of one frame shows the technique asked for, as captures of more frames do: the
/// frames `--frames` counts begin once the scene is ready and the passes run, not while Bevy's
/// SSAO stands in for them (or nothing is drawn yet), and `--timings` waits for that frame's
/// spans.
#[test]
fn a_one_frame_capture_shows_its_technique() {
    let dir = temp_dir("one_frame");
    for technique in ["near-field", "default"] {
        // Without accumulation the pattern stands still: every frame is the same image.
        let (one, text) = capture(
            &dir,
            technique,
            &["--no-temporal", "--frames", "1", "--timings"],
        );
        let (four, _) = capture(&dir, technique, &["--no-temporal", "--frames", "4"]);
        let differ = one.iter().zip(&four).filter(|(a, b)| a != b).count();
        let mean = one.iter().sum::<f32>() / one.len() as f32;
        println!(
            "{technique}: --frames 1 differs from --frames 4 at {differ} pixels, mean visibility {mean:.4}"
        );
        // Before the count waited for the passes, one frame read back an image never written
        // (mean visibility 0) or Bevy's SSAO standing in.
        assert_eq!(
            differ, 0,
            "{technique}: --frames 1 captured another image than --frames 4"
        );
        let (ao, frame, frames) = timings(&text);
        assert!(
            frames >= 1 && ao > 0.0 && frame >= ao,
            "{technique}: ao {ao} ms, frame {frame} ms over {frames} frames"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn default_technique_and_timings() {
    let dir = temp_dir("timings");
    let capture = |technique: &str, extra: &[&str]| capture(&dir, technique, extra);
    let rmse = |a: &[f32], b: &[f32]| {
        (a.iter().zip(b).map(|(a, b)| (a - b).powi(2)).sum::<f32>() / a.len() as f32).sqrt()
    };
    // `default` is what `DynamicAo::default()` runs: the ray march of preset High, accumulated,
    // at full resolution at this size (`DynamicAo::small_viewport_pixels`), and at half
    // resolution where `--half-res` asks for it at every size.
    let (default, text) = capture("default", &["--no-temporal"]);
    let (half, _) = capture("default", &["--half-res", "--no-temporal"]);
    for (ours, reference) in [
        (&default, capture("ray-march", &["--no-temporal"]).0),
        (
            &half,
            capture("ray-march", &["--half-res", "--no-temporal"]).0,
        ),
    ] {
        let differ = ours.iter().zip(&reference).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "--technique default is the default ray march");
    }
    assert_ne!(
        half, default,
        "--half-res halves the resolution of a small capture"
    );
    let (accumulated, _) = capture("default", &[]);
    let moved = accumulated
        .iter()
        .zip(&default)
        .filter(|(a, b)| (*a - *b).abs() > 0.01)
        .count();
    assert!(
        moved > default.len() / 20,
        "the default accumulates: only {moved} pixels differ by 1% from a single frame"
    );
    // The frames a capture accumulates count from the frame its scene is ready, and the
    // pattern's sequence from the history's start, so a capture does not depend on how long the
    // scene took to load.
    let (again, _) = capture("default", &[]);
    let repeat = rmse(&accumulated, &again);
    println!("accumulated capture against a second one: RMSE {repeat:.4}");
    // Measured 0.0000.
    assert!(repeat <= 0.001, "two captures differ by RMSE {repeat}");
    // The same captures with 4 samples per pixel (an MSAA camera, which Bevy's SSAO refuses,
    // has no AO until our passes run: `--frames` counts from then).
    for extra in [&["--no-temporal"][..], &[][..]] {
        let (plain, _) = capture("default", extra);
        let (msaa, _) = capture("default", &[extra, &["--msaa", "4"]].concat());
        let msaa_rmse = rmse(&plain, &msaa);
        println!("--msaa 4 against --msaa 1 {extra:?}: RMSE {msaa_rmse:.4}");
        // Measured 0.0000 in both.
        assert!(
            msaa_rmse <= 0.001,
            "--msaa 4 differs from --msaa 1 by RMSE {msaa_rmse}"
        );
    }
    assert!(!text.contains("timings:"), "no timings line unless asked");
    // With --preset low, `default` is the Low preset: the ray march, accumulated, with Low's
    // budget (which differs from the default's), at full resolution at this size and so with the
    // blur of `SMALL_VIEWPORT_BLUR_RADIUS`.
    let (low, _) = capture("default", &["--preset", "low"]);
    let (ray_march_low, _) = capture("ray-march", &["--preset", "low", "--accumulated-blur", "1"]);
    let differ = low
        .iter()
        .zip(&ray_march_low)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differ, 0, "--technique default follows --preset");
    let from_high = low.iter().zip(&accumulated).filter(|(a, b)| a != b).count();
    assert!(
        from_high > low.len() / 20,
        "--preset low changed only {from_high} pixels of the default's capture"
    );

    let timings =
        |technique: &str| timings(&capture(technique, &["--frames", "12", "--timings"]).1);
    for technique in ["near-field", "bevy-ssao"] {
        let (ao, frame, frames) = timings(technique);
        assert!(
            frames > 0 && frames <= 20,
            "{technique}: {frames} frames measured"
        );
        assert!(
            ao > 0.0 && frame >= ao,
            "{technique}: ao {ao} ms, frame {frame} ms"
        );
    }
}

/// `--history-frames N` sets `AoTemporal::max_frames`: the same capture as the default at 16,
/// the same as 16 until a history holds 16 samples, and past that a longer history averages more
/// samples, so its capture lies nearer the CPU ray tracer's.
#[test]
fn history_frames_sets_the_history_length() {
    let dir = temp_dir("history_frames");
    let truth = dir.join("truth.png");
    let truth_arg = truth.to_str().expect("a UTF-8 path");
    let error = |frames: &str| {
        let (image, text) = capture(
            &dir,
            "default",
            &["--history-frames", frames, "--out-truth", truth_arg],
        );
        let rmse: f32 = text
            .split("RMSE of the capture ")
            .nth(1)
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|figure| figure.parse().ok())
            .unwrap_or_else(|| panic!("no RMSE in:\n{text}"));
        (image, rmse)
    };
    let (sixteen, _) = error("16");
    let (default, _) = capture(&dir, "default", &[]);
    assert!(sixteen == default, "--history-frames 16 is the default");
    let early = |frames: &str| {
        capture(
            &dir,
            "default",
            &["--history-frames", frames, "--frames", "20"],
        )
        .0
    };
    assert!(
        early("16") == early("32"),
        "before a history holds 16 samples (32 frames under the checkerboard), 16 and 32 agree"
    );
    let (_, short) = error("2");
    let (_, long) = error("32");
    println!("RMSE against the ray tracer: history of 2 samples {short:.4}, of 32 {long:.4}");
    // Measured 0.0100 and 0.0209.
    assert!(long < 0.6 * short, "32 samples read {long}, 2 read {short}");
}

#[test]
fn compare_writes_ours_bevys_and_none_side_by_side() {
    let dir = temp_dir("compare");
    let (out_ao, out_color, compare) = (
        dir.join("ao.png"),
        dir.join("color.png"),
        dir.join("compare.png"),
    );
    run_ok(&[
        "--scene",
        scene_path().to_str().unwrap(),
        "--width",
        "160",
        "--height",
        "120",
        "--radius",
        "0.75",
        "--technique",
        "default",
        "--out-ao",
        out_ao.to_str().unwrap(),
        "--out-color",
        out_color.to_str().unwrap(),
        "--compare",
        compare.to_str().unwrap(),
    ]);
    // Three 160 × 120 images with 4 white pixels between them.
    let luma = crate::examples::image_luma(&compare);
    let width = 3 * 160 + 8;
    assert_eq!(luma.len(), width * 120, "three images side by side");
    let pixel = |third: usize, i: usize| luma[(i / 160) * width + third * 164 + i % 160] as i32;
    let darker =
        |a: usize, b: usize| (0..160 * 120).filter(move |&i| pixel(a, i) + 6 < pixel(b, i));
    let (ours, bevy, lighter) = (
        darker(0, 2).count(),
        darker(1, 2).count(),
        darker(2, 0).count() + darker(2, 1).count(),
    );
    println!(
        "--compare: pixels darker than no AO: ours {ours}, Bevy's SSAO {bevy}; lighter {lighter}"
    );
    // Measured: ours 518, Bevy's 648 of 19,200, lighter 0: the lit image shows the AO (ambient
    // light is most of the light) and the three views agree.
    assert!(ours > 450 && bevy > 550, "both AO views should darken");
    assert_eq!(lighter, 0, "AO never lightens");
    // `--out-color` is ours alone, as in the comparison.
    let color = crate::examples::image_luma(&out_color);
    assert!((0..160 * 120).all(|i| color[i] as i32 == pixel(0, i)));
    let bad = run(&["--compare", "x.png", "--msaa", "4", "--scene", "a.glb"]);
    assert_eq!(bad.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

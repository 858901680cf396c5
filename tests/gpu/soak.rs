//! The soak benchmark's run (`benches/soak`), 1,000 frames as CI runs it: occluders of every kind
//! spawning and despawning, the target resized, presets, techniques and MSAA toggled, `DynamicAo`
//! taken off and put back. Memory must stay bounded. It runs in a process of its own, in one
//! allocator arena and without the Vulkan validation layer, so neither the tests before it, the
//! machine's load nor a debugging layer installed on it move its RSS.

#[path = "../../benches/soak/run.rs"]
mod run;

use crate::harness::gpu_alone;

/// Every term on, the sphere term included (its splat pass once made lavapipe keep a new shader
/// variant at every draw, 6.6 MB each; `spheres/splat.wgsl` says why no longer).
#[test]
fn a_thousand_frames_of_changes_stay_bounded() {
    let _turn = gpu_alone();
    if !run::is_measured() {
        // Its own process, in one allocator arena and without the validation layer
        // (`run::ONE_ARENA` and `run::NO_VALIDATION_LAYER` say why), this test alone.
        let name = "soak::a_thousand_frames_of_changes_stay_bounded";
        let output = run::again_measured(["--exact", name, "--nocapture"])
            .output()
            .expect("the test runs itself again");
        let stdout = String::from_utf8_lossy(&output.stdout);
        print!("{stdout}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        let tail: Vec<&str> = stderr.lines().rev().take(30).collect();
        assert!(
            output.status.success(),
            "the soak failed: {}",
            tail.into_iter().rev().collect::<Vec<_>>().join("\n")
        );
        // A filter that matched nothing would also succeed.
        assert!(
            stdout.contains(&format!("test {name} ... ok")),
            "the measured run did not run {name}"
        );
        return;
    }
    // The schedule repeats every 400 frames: growth is measured over the last 500.
    let report = run::soak(1000, 20, true, run::CYCLE / 4);
    println!("{}", report.table());
    let verdict = report.verdict();
    println!("{verdict}");
    assert!(verdict.bounded(), "{verdict}");
    let end = report.end();
    assert!(end.gpu > 0, "nothing on the GPU at the end");
    // From the seventh occluder on, one despawns as one spawns, each with a mesh of its own:
    // over the second half mesh assets and entities hold steady, so every despawned occluder's
    // mesh was freed and its entities went with it.
    let half = &report.samples[report.samples.len() / 2..];
    assert!(
        half.iter().all(|s| s.meshes == end.meshes),
        "meshes left behind"
    );
    let entities = half.iter().map(|s| s.entities);
    let spread = entities.clone().max().unwrap() - entities.min().unwrap();
    assert!(spread <= 2, "entities left behind");
}

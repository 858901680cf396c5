//! Soak: 10,000 frames at 64×48 while occluders spawn and despawn, the view resizes, settings
//! and MSAA toggle and `DynamicAo` comes and goes (see `run.rs` for the schedule). Prints process
//! RSS and the plugin's GPU bytes at checkpoints as a Markdown table, then the RSS growth from the
//! warm checkpoint (frame 2,000, a fifth of the way) to the end and the largest GPU bytes seen,
//! and exits with code 1 when either passes its bound (code 2 for a run too short to reach the
//! warm checkpoint). It runs itself again with glibc's allocator limited to one arena and without
//! the Vulkan validation layer (`run::ONE_ARENA` and `run::NO_VALIDATION_LAYER` say why).
//!
//! `cargo bench --profile dev --bench soak` (`-- --frames N` for another length,
//! `-- --without-spheres` to keep the sphere term off). CI runs 1,000 frames as the GPU test
//! `soak::a_thousand_frames_of_changes_stay_bounded`.

#[path = "../../examples/common/mod.rs"]
mod common;
mod run;

fn main() {
    if !run::is_measured() {
        let status = run::again_measured(std::env::args_os().skip(1))
            .status()
            .expect("the soak runs itself again in the environment it measures in");
        std::process::exit(status.code().unwrap_or(1));
    }
    let mut frames = 10_000;
    let mut spheres = true;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--frames" => {
                frames = args
                    .next()
                    .and_then(|n| n.parse().ok())
                    .expect("--frames takes a number");
            }
            "--without-spheres" => spheres = false,
            // `cargo bench` passes `--bench`.
            _ => {}
        }
    }
    // A run that ends before the warm checkpoint would print a growth of nothing, whatever its
    // memory did.
    let warm = run::warm_frame(run::CYCLE);
    if frames <= warm {
        eprintln!(
            "soak: --frames {frames} ends before the warm checkpoint at frame {warm}, from which growth \
             is measured; give more frames"
        );
        std::process::exit(2);
    }
    let start = std::time::Instant::now();
    let report = run::soak(frames, 20, spheres, run::CYCLE);
    println!("{}", report.table());
    let verdict = report.verdict();
    println!(
        "soak: frames={frames} spheres={spheres} seconds={:.0} {verdict}",
        start.elapsed().as_secs_f64()
    );
    if !verdict.bounded() {
        eprintln!("soak: memory grew past its bound");
        std::process::exit(1);
    }
}

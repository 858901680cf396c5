//! `--timings`: the mean GPU time of the AO passes and of every pass, from Bevy's render
//! diagnostics (timestamp queries), over the frames the capture renders once its scene, fields
//! and volume are ready.

use bevy::diagnostic::DiagnosticsStore;

/// Whether the GPU time span `name` belongs to the AO: Bevy's own `ssao` span for Bevy's SSAO;
/// for ours every `dynamic_ao_*` span except the read-back copy this tool adds.
pub fn is_ao_pass(name: &str, bevy_ssao: bool) -> bool {
    if bevy_ssao {
        name == "ssao"
    } else {
        name.starts_with("dynamic_ao") && name != "dynamic_ao_readback"
    }
}

/// The name of a GPU time span's diagnostic, if `path` is one.
fn gpu_span(path: &str) -> Option<&str> {
    path.strip_prefix("render/")?.strip_suffix("/elapsed_gpu")
}

/// Forgets every GPU time measured so far: frames spent loading, baking or compiling do not
/// count.
pub fn forget(store: &mut DiagnosticsStore) {
    for diagnostic in store.iter_mut() {
        if gpu_span(diagnostic.path().as_str()).is_some() {
            diagnostic.clear_history();
        }
    }
}

/// Whether every AO span has come back for `frames` frames (or for as many as its history
/// holds): timestamps come back a few frames after their frame, so a short capture waits for
/// them before it prints. `false` while no AO span has come back at all.
pub fn measured(store: &DiagnosticsStore, bevy_ssao: bool, frames: u32) -> bool {
    let mut spans = store
        .iter()
        .filter(|d| gpu_span(d.path().as_str()).is_some_and(|name| is_ao_pass(name, bevy_ssao)))
        .peekable();
    spans.peek().is_some()
        && spans.all(|d| d.history_len() >= (frames as usize).min(d.get_max_history_length()))
}

/// The one line `--timings` prints on stdout: `ao_gpu_ms`, the mean per frame of the AO passes
/// summed; `frame_gpu_ms`, of every pass with a GPU time span; `frames`, how many frames the AO
/// means are over (0, with `nan` times, where the adapter has no timestamp queries). Each pass's
/// mean, and a warning for each AO span that missed its work, go to stderr.
pub fn summary(store: &DiagnosticsStore, bevy_ssao: bool) -> String {
    let spans: Vec<_> = store
        .iter()
        .filter_map(|d| Some((gpu_span(d.path().as_str())?, d.average()?, d)))
        .collect();
    let all: f64 = spans.iter().map(|(_, mean, _)| mean).sum();
    let (mut ao, mut frames) = (0.0, None::<usize>);
    for (name, mean, diagnostic) in spans {
        // Every pass on its own line on stderr, none starting `timings:`: stdout and stderr read
        // together still hold one summary line.
        eprintln!("ao_capture: gpu span {name}: {mean:.3} ms");
        if is_ao_pass(name, bevy_ssao) {
            ao += mean;
            let measured = diagnostic.history_len();
            let values = diagnostic.values().copied();
            if let Some(warning) = empty_span_warning(name, values, measured, all) {
                eprintln!("{warning}");
            }
            frames = Some(frames.map_or(measured, |f| f.min(measured)));
        }
    }
    match frames {
        Some(frames) if frames > 0 => {
            format!("timings: ao_gpu_ms={ao:.3} frame_gpu_ms={all:.3} frames={frames}")
        }
        _ => "timings: ao_gpu_ms=nan frame_gpu_ms=nan frames=0".to_string(),
    }
}

/// A span under both of these bracketed none of its pass's work: an adapter may take a span's
/// timestamps with the work outside them (lavapipe did so for our compute passes until each
/// span's start made it run its queue first: BENCHMARKS.md, "Spans that hold their work"). A
/// time alone would name every pass on a hardware GPU, where each takes well under a millisecond
/// yet none under 1% of the frame (an NVIDIA H200's smallest AO pass read 3.8% at 640×480); a
/// share alone would name lavapipe's back faces of a few triangles, which take about 0.5 ms of
/// a 70 ms frame.
const EMPTY_SPAN_MS: f64 = 0.2;
const EMPTY_SPAN_SHARE: f64 = 0.01;

/// A warning for stderr where the span `name` read under [`EMPTY_SPAN_MS`] and under
/// [`EMPTY_SPAN_SHARE`] of `frame_ms` (the mean GPU time of every pass) in a quarter or more of
/// its `measured` frames (`values`, ms): its mean, and `ao_gpu_ms` with it, leave that work out,
/// so the figure understates the pass.
fn empty_span_warning(
    name: &str,
    values: impl Iterator<Item = f64>,
    measured: usize,
    frame_ms: f64,
) -> Option<String> {
    let under = EMPTY_SPAN_MS.min(EMPTY_SPAN_SHARE * frame_ms);
    let empty = values.filter(|ms| *ms < under).count();
    (measured > 0 && empty * 4 >= measured).then(|| {
        format!(
            "ao_capture: warning: gpu span {name} read under {under:.3} ms (0.2 ms or 1% of the \
             frame's {frame_ms:.3}, the less) in {empty} of {measured} frames; the adapter's timestamps left that \
             work out, so ao_gpu_ms understates it"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ao_passes_are_told_apart() {
        assert!(is_ao_pass("ssao", true));
        assert!(!is_ao_pass("dynamic_ao_compose", true));
        assert!(is_ao_pass("dynamic_ao_near_field", false));
        assert!(!is_ao_pass("dynamic_ao_readback", false));
        assert!(!is_ao_pass("ssao", false));
        assert_eq!(gpu_span("render/ssao/elapsed_gpu"), Some("ssao"));
        assert_eq!(gpu_span("render/ssao/elapsed_cpu"), None);
    }

    #[test]
    fn spans_that_missed_their_work_are_named() {
        // lavapipe, a 60 ms frame: 2 of 8 frames empty is a quarter, so the span is named, with
        // both counts.
        let values = [9.8, 0.0, 10.1, 0.1, 19.7, 9.6, 20.3, 12.6];
        let warning =
            empty_span_warning("dynamic_ao_temporal", values.into_iter(), 8, 60.0).unwrap();
        assert!(warning.starts_with("ao_capture: warning: gpu span dynamic_ao_temporal"));
        assert!(warning.contains("in 2 of 8 frames"), "{warning}");
        // 1 of 8 is not enough, and nothing measured warns of nothing.
        let values = [9.8, 0.0, 10.1, 10.3, 19.7, 9.6, 20.3, 12.6];
        assert_eq!(
            empty_span_warning("dynamic_ao_temporal", values.into_iter(), 8, 60.0),
            None
        );
        assert_eq!(
            empty_span_warning("ssao", std::iter::empty(), 0, 60.0),
            None
        );
        // A hardware GPU: a 0.015 ms pass of a 0.395 ms frame did its work.
        let values = [0.015, 0.014, 0.016, 0.015];
        assert_eq!(
            empty_span_warning("dynamic_ao_temporal", values.into_iter(), 4, 0.395),
            None
        );
    }
}

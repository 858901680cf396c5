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

/// The one line `--timings` prints on stdout (each pass's mean goes to stderr): `ao_gpu_ms`, the mean per frame of the AO passes summed;
/// `frame_gpu_ms`, of every pass with a GPU time span; `frames`, how many frames the AO means
/// are over (0, with `nan` times, where the adapter has no timestamp queries).
pub fn summary(store: &DiagnosticsStore, bevy_ssao: bool) -> String {
    let (mut ao, mut all, mut frames) = (0.0, 0.0, None::<usize>);
    for diagnostic in store.iter() {
        let (Some(name), Some(mean)) = (gpu_span(diagnostic.path().as_str()), diagnostic.average())
        else {
            continue;
        };
        all += mean;
        // Every pass on its own line on stderr; stdout keeps the one summary line.
        eprintln!("timings: pass {name} {mean:.3} ms");
        if is_ao_pass(name, bevy_ssao) {
            ao += mean;
            let measured = diagnostic.history_len();
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
}

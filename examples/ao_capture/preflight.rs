//! A look at the file's glTF structure before Bevy's loader reads it. Two kinds of malformed file
//! make the glTF reader inside Bevy's loader panic rather than return an error: an attribute that
//! names an accessor the file does not have (the validator indexes it before it reports it), and
//! a buffer view whose stride is shorter than the elements its accessors read. Bevy catches the
//! loader's panic, but its message and backtrace end up on stderr; the capture names the fault in
//! one line instead and does not hand the file on.

use std::panic;
use std::path::Path;

/// What is wrong with the glTF file at `path`, where it is one of the kinds above. Anything else
/// (a missing file, a file that is no glTF) is left to Bevy's loader, which reports it.
pub fn check(path: &Path) -> Result<(), String> {
    let Ok(bytes) = std::fs::read(path) else {
        return Ok(());
    };
    // The validator's panic is the answer here, not a fault of the capture: keep it off stderr.
    let hook = panic::take_hook();
    panic::set_hook(Box::new(|_| {}));
    let parsed = panic::catch_unwind(|| gltf::Gltf::from_slice(&bytes));
    panic::set_hook(hook);
    let gltf = match parsed {
        Err(_) => {
            return Err(format!(
                "cannot load {}: its glTF structure names an object it does not have (the glTF \
                 validator failed on it)",
                path.display()
            ));
        }
        Ok(Err(_)) => return Ok(()),
        Ok(Ok(gltf)) => gltf,
    };
    for accessor in gltf.accessors() {
        let Some(view) = accessor.view() else {
            continue;
        };
        if let Some(stride) = view.stride()
            && stride < accessor.size()
        {
            return Err(format!(
                "cannot load {}: accessor {} reads elements of {} bytes through buffer view {}, \
                 whose stride is {} bytes",
                path.display(),
                accessor.index(),
                accessor.size(),
                view.index(),
                stride
            ));
        }
    }
    Ok(())
}

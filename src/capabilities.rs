//! What the plugin needs of the GPU, checked once when the app finishes building.
//!
//! On an adapter that lacks any of it the plugin logs one error naming what is missing and
//! registers no render pass: cameras render without ambient occlusion rather than failing on
//! pipeline creation.

use bevy::app::{App, SubApp};
use bevy::ecs::resource::Resource;
use bevy::log::{error, warn};
use bevy::render::{
    RenderApp,
    render_resource::DownlevelFlags,
    renderer::{RenderAdapter, RenderDevice},
    settings::WgpuLimits,
};

/// Storage textures one shader stage binds at most: the AO read-back writes three; Bevy's SSAO
/// plugin, whose output texture our compose pass writes, needs five to load at all.
pub(crate) const REQUIRED_STORAGE_TEXTURES: u32 = 5;
/// Storage buffers one shader stage binds at most (voxelization: triangles, volumes, grid).
pub(crate) const REQUIRED_STORAGE_BUFFERS: u32 = 3;

/// The result of the check, kept in the render world.
#[derive(Resource)]
struct Checked {
    supported: bool,
}

/// What `limits` and `downlevel` lack of the plugin's needs, one line each; empty when nothing.
pub(crate) fn missing_capabilities(limits: &WgpuLimits, downlevel: DownlevelFlags) -> Vec<String> {
    let mut missing = Vec::new();
    if limits.max_storage_textures_per_shader_stage < REQUIRED_STORAGE_TEXTURES {
        missing.push(format!(
            "Limits::max_storage_textures_per_shader_stage is {}, needs {REQUIRED_STORAGE_TEXTURES}",
            limits.max_storage_textures_per_shader_stage
        ));
    }
    if limits.max_storage_buffers_per_shader_stage < REQUIRED_STORAGE_BUFFERS {
        missing.push(format!(
            "Limits::max_storage_buffers_per_shader_stage is {}, needs {REQUIRED_STORAGE_BUFFERS}",
            limits.max_storage_buffers_per_shader_stage
        ));
    }
    for (flag, name) in [
        (DownlevelFlags::COMPUTE_SHADERS, "COMPUTE_SHADERS"),
        // The splat and AO field passes read their occluders in the vertex shader.
        (DownlevelFlags::VERTEX_STORAGE, "VERTEX_STORAGE"),
    ] {
        if !downlevel.contains(flag) {
            missing.push(format!("DownlevelFlags::{name}"));
        }
    }
    missing
}

/// Checks the adapter of `render_app` once, logging what it lacks.
fn check(render_app: &mut SubApp) -> bool {
    if let Some(checked) = render_app.world().get_resource::<Checked>() {
        return checked.supported;
    }
    let world = render_app.world();
    let (Some(device), Some(adapter)) = (
        world.get_resource::<RenderDevice>(),
        world.get_resource::<RenderAdapter>(),
    ) else {
        return false;
    };
    let missing =
        missing_capabilities(&device.limits(), adapter.get_downlevel_capabilities().flags);
    if !missing.is_empty() {
        error!(
            "DynamicAoPlugin not loaded, cameras render without ambient occlusion: the GPU lacks {}",
            missing.join("; ")
        );
    }
    render_app.insert_resource(Checked {
        supported: missing.is_empty(),
    });
    missing.is_empty()
}

/// How many of `len` items of `item_bytes` each one storage buffer binding of at most
/// `max_binding` bytes holds: `len`, or fewer when they would pass the device's
/// `max_storage_buffer_binding_size` (binding a larger buffer fails validation and ends the app).
pub(crate) fn fit_storage_binding(len: usize, item_bytes: usize, max_binding: u64) -> usize {
    let most = max_binding / item_bytes.max(1) as u64;
    len.min(usize::try_from(most).unwrap_or(usize::MAX))
}

/// How many of `len` items of type `T` one storage binding of at most `max_binding` bytes holds;
/// when fewer than `len`, warns once per `warned`, naming `what`, the limit and the sizes.
pub(crate) fn cap_to_storage_binding<T>(
    what: &str,
    len: usize,
    max_binding: u64,
    warned: &mut bool,
) -> usize {
    let kept = fit_storage_binding(len, size_of::<T>(), max_binding);
    if kept < len && !std::mem::replace(warned, true) {
        warn!(
            "{}",
            storage_binding_warning(what, len, kept, size_of::<T>(), max_binding)
        );
    }
    kept
}

/// The warning for `len` items of `item_bytes` of which only `kept` fit one storage binding:
/// names the limit and the sizes, and what is left out.
fn storage_binding_warning(
    what: &str,
    len: usize,
    kept: usize,
    item_bytes: usize,
    max_binding: u64,
) -> String {
    format!(
        "{what}: {len} of {item_bytes} bytes each take {} bytes, more than this device's \
         max_storage_buffer_binding_size ({max_binding} bytes); the last {} are left out while \
         it lasts",
        len as u64 * item_bytes as u64,
        len - kept
    )
}

/// The render app, where the adapter can run the plugin: what each part's `finish()` registers
/// its render systems on.
pub(crate) fn render_app(app: &mut App) -> Option<&mut SubApp> {
    let render_app = app.get_sub_app_mut(RenderApp)?;
    check(render_app).then_some(render_app)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_missing_capability_is_named() {
        // WebGPU's default of 4 storage textures is one short of what Bevy's SSAO needs.
        let desktop = WgpuLimits {
            max_storage_textures_per_shader_stage: 8,
            ..WgpuLimits::default()
        };
        assert!(missing_capabilities(&desktop, DownlevelFlags::all()).is_empty());
        let webgl = WgpuLimits::downlevel_webgl2_defaults();
        let missing = missing_capabilities(&webgl, DownlevelFlags::empty());
        assert_eq!(missing.len(), 4, "{missing:?}");
        assert!(missing[0].contains("max_storage_textures_per_shader_stage is 0, needs 5"));
        assert!(missing[1].contains("max_storage_buffers_per_shader_stage is 0, needs 3"));
        assert_eq!(missing[2], "DownlevelFlags::COMPUTE_SHADERS");
        assert_eq!(missing[3], "DownlevelFlags::VERTEX_STORAGE");
    }

    #[test]
    fn storage_bindings_keep_what_fits() {
        assert_eq!(fit_storage_binding(10, 80, 800), 10);
        assert_eq!(fit_storage_binding(11, 80, 800), 10);
        assert_eq!(fit_storage_binding(11, 80, 79), 0);
        assert_eq!(fit_storage_binding(3, 0, 0), 0);
        let message = storage_binding_warning("SphereOccluder proxies", 11, 10, 80, 800);
        assert_eq!(
            message,
            "SphereOccluder proxies: 11 of 80 bytes each take 880 bytes, more than this \
             device's max_storage_buffer_binding_size (800 bytes); the last 1 are left out while \
             it lasts"
        );
    }
}

//! How much GPU memory the plugin's own resources hold, readable from the main world.
//!
//! Every technique that owns GPU memory beyond Bevy's texture cache reports its bytes each frame,
//! after it uploaded or resized them: sphere proxies, AO fields, voxel volumes and the temporal
//! histories. The render world writes, the main world reads: both hold the same counters.

use std::sync::{Arc, Mutex, PoisonError};

use bevy::app::App;
use bevy::ecs::resource::Resource;
use bevy::render::RenderApp;

/// GPU memory the plugin's own buffers and history textures hold, bytes, as the render world
/// left them after its latest frame, by owner: `"spheres"` (proxy buffer), `"fields"` (field
/// cells and occluders), `"voxels"` (grids, triangles, volumes), `"temporal"` (every view's
/// two history textures) and `"back faces"` (the coarse copies of meshes of many triangles and
/// their instances). What Bevy's texture cache lends the passes (ND-buffer layers,
/// occlusion buffers) is Bevy's and not counted.
///
/// A main-world resource [`DynamicAoPlugin`](crate::DynamicAoPlugin) inserts. Watch it in a
/// running game to see that memory follows what is on screen; the soak benchmark asserts that it
/// stays bounded over thousands of frames.
#[derive(Resource, Clone, Default)]
pub struct DynamicAoGpuMemory(Arc<Mutex<Vec<(&'static str, u64)>>>);

impl DynamicAoGpuMemory {
    /// All owners together, bytes.
    pub fn bytes(&self) -> u64 {
        self.by_owner().iter().map(|(_, bytes)| bytes).sum()
    }

    /// Bytes per owner, in the order they first reported.
    pub fn by_owner(&self) -> Vec<(&'static str, u64)> {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// Sets what `owner` holds now.
    pub(crate) fn report(&self, owner: &'static str, bytes: u64) {
        let mut owners = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        match owners.iter_mut().find(|(name, _)| *name == owner) {
            Some((_, held)) => *held = bytes,
            None => owners.push((owner, bytes)),
        }
    }
}

/// Inserts the counters into the main world and, sharing them, into the render world.
pub(crate) fn insert(app: &mut App) {
    let memory = DynamicAoGpuMemory::default();
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        render_app.insert_resource(memory.clone());
    }
    app.insert_resource(memory);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owners_report_what_they_hold_now() {
        let memory = DynamicAoGpuMemory::default();
        let render_world = memory.clone();
        render_world.report("spheres", 960);
        render_world.report("voxels", 4096);
        render_world.report("spheres", 96);
        assert_eq!(memory.by_owner(), vec![("spheres", 96), ("voxels", 4096)]);
        assert_eq!(memory.bytes(), 4192);
    }
}

//! Horizon-based ambient occlusion, Bavoil & Sainz 2008 ("Horizon-Based Ambient Occlusion").
//!
//! The front layer of the ND-buffer is read as a heightfield seen from the camera. For each of
//! a few image-space directions around a pixel (randomly rotated per pixel), the pass steps
//! outwards up to the radius R projected on screen (fewer steps where it covers fewer pixels),
//! tracks the highest elevation angle h seen so far, measured from the view plane, and adds
//! W0 · W(r/R) · (sin h_new − sin h_old) whenever the horizon rises, starting from the elevation
//! t of the tangent plane (raised by the angle bias). W(x) = 1 − x². The mean over directions,
//! times the contrast, is the occlusion. `reference::horizon` is the CPU twin.
//!
//! The whitepaper's low and high modes are named there but not spelled out; what they do here is
//! documented on [`HorizonMode`](crate::settings::HorizonMode).
//!
//! This folder holds the technique's settings (`settings.rs`) and shader (`horizon.wgsl`). Its pass
//! is shared with the other image-space techniques and lives in `src/image_space/`:
//! `image_space/pipeline.rs` compiles this shader over the common layout,
//! `image_space/node.rs` dispatches it; the common bindings are `shaders/image_space_bindings.wgsl`.

pub mod settings;
use bevy::app::{App, Plugin};
use bevy::asset::{Handle, embedded_asset, load_embedded_asset};
use bevy::ecs::world::World;
use bevy::shader::Shader;

/// Embeds the horizon-based shader; the shared image-space pass (`crate::image_space`) runs it.
pub struct HorizonPlugin;

impl Plugin for HorizonPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "horizon.wgsl");
    }
}

pub(crate) fn shader(world: &World) -> Handle<Shader> {
    load_embedded_asset!(world, "horizon.wgsl")
}

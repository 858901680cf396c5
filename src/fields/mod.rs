//! Precomputed ambient occlusion fields for rigid occluders (Malmer et al. 2005).
//!
//! A field is a small 3D grid around an object, in the object's own space, holding at every
//! grid point the fraction of the sphere of directions the object blocks (eq. 2) and the average
//! occluded direction. [`baker`] computes it by ray casting (grid extent by eq. 4, border
//! rescale §3.4.1, interior fill §3.4.2); [`format`] stores it as a versioned, checksummed
//! `.aofield` file; [`AoFieldLoader`] loads such files as [`AoFieldData`] assets, and bad files
//! fail to load with a message instead of panicking. The `ao_bake` example bakes every mesh of
//! a glTF file.
//!
//! Applying fields at render time (the box pass) is not part of the crate yet.

pub mod baker;
pub mod format;
mod loader;

use bevy::app::{App, Plugin};
use bevy::asset::AssetApp;

pub use baker::{BakeError, BakeSettings, bake, grid_box};
pub use format::{AoFieldData, AoFieldError};
pub use loader::AoFieldLoader;

/// Registers the [`AoFieldData`] asset and its `.aofield` loader.
pub struct AoFieldPlugin;

impl Plugin for AoFieldPlugin {
    fn build(&self, app: &mut App) {
        app.init_asset::<AoFieldData>()
            .register_asset_loader(AoFieldLoader);
    }
}

//! The occluder component users add, and where baked fields are cached.

use std::path::PathBuf;

use bevy::asset::Handle;
use bevy::ecs::prelude::*;
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

use super::baker::BakeSettings;
pub use super::cache::default_folder as default_cache_folder;
use super::format::AoFieldData;

/// Makes a rigid object cast ambient occlusion from a precomputed field (Malmer et al. 2005):
/// a grid around the object, in its own space, that moves with its `GlobalTransform`. Its cost
/// depends on the pixels its grid box covers, not on the object's triangles.
///
/// Put it on the entity with the object's `Mesh3d`. Either give it a field baked beforehand
/// (`ao_bake`, loaded from a `.aofield` file), or let the plugin bake one from the entity's mesh
/// when it appears: on the async compute pool, cached on disk in [`AoFieldCache`], so the frame
/// never waits and the next run loads it.
///
/// A field the plugin bakes is baked at the entity's world scale, so that it reaches the camera's
/// radius in metres whatever units the mesh was modelled in (a glTF model in centimetres scaled
/// by 0.01, a unit plane scaled to a floor); it is baked again, in the background, when that
/// scale changes by more than about 1 %. A field loaded from a file lies in the mesh's space and
/// reaches as far in mesh units as it was baked for: bake it at the scale it is shown at.
///
/// The object casts only on the cameras that draw it: those that share a layer of the entity's
/// `RenderLayers`.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone, Debug)]
pub enum AoField {
    /// A baked field, e.g. `asset_server.load("crate.aofield")`, in the mesh's space (its reach
    /// in mesh units).
    Asset(Handle<AoFieldData>),
    /// Bake from the entity's own mesh, at its world scale, with these settings.
    Bake(BakeSettings),
}

impl Default for AoField {
    /// Bake from the entity's mesh with [`BakeSettings::default`] (32³, ε = 0.1, 256 rays).
    fn default() -> Self {
        Self::Bake(BakeSettings::default())
    }
}

/// Where fields baked on load are kept between runs: one `<hash>.aofield` file per mesh content
/// and bake settings. Default: `bevy_dynamic_ao/fields` in the user's cache directory
/// ([`default_cache_folder`]: `$XDG_CACHE_HOME` or `~/.cache` on Linux, `~/Library/Caches` on
/// macOS, `%LOCALAPPDATA%` on Windows), never a folder other users share; set `folder` to `None`
/// to bake every run without touching the disk.
///
/// The folder is kept under [`max_bytes`](Self::max_bytes): after each bake the fields used
/// longest ago are deleted until the rest fit.
///
/// Files are written atomically and never through a symlink, the folder is made readable by the
/// user alone, and a cached file is used only if it is a regular file of the size the bake would
/// write, its checksum holds and its grid is the one this mesh and these settings bake; anything
/// else is baked again and replaced, with a warning.
#[derive(Resource, Clone, Debug)]
pub struct AoFieldCache {
    /// The cache folder, created when first written.
    pub folder: Option<PathBuf>,
    /// The most bytes the folder's fields may take, in bytes. After a field is written, the
    /// fields read or written longest ago are deleted until the rest fit; the field just
    /// written is kept even if it alone is larger. `u64::MAX` keeps every field. Default:
    /// [`AoFieldCache::DEFAULT_MAX_BYTES`].
    pub max_bytes: u64,
}

impl AoFieldCache {
    /// 512 MiB: about 140 fields of the default 32³ (3.7 MB each).
    pub const DEFAULT_MAX_BYTES: u64 = 512 << 20;

    /// No cache: every field is baked every run, and nothing is written to disk.
    pub fn disabled() -> Self {
        Self {
            folder: None,
            ..Self::default()
        }
    }
}

impl Default for AoFieldCache {
    fn default() -> Self {
        Self {
            folder: default_cache_folder(),
            max_bytes: Self::DEFAULT_MAX_BYTES,
        }
    }
}

//! The occluder component users add, and where baked fields are cached.

use std::path::PathBuf;

use bevy::asset::Handle;
use bevy::ecs::prelude::*;
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

use super::baker::BakeSettings;
use super::format::AoFieldData;

/// Makes a rigid object cast ambient occlusion from a precomputed field (Malmer et al. 2005):
/// a grid around the object, in its own space, that moves with its `GlobalTransform`. Its cost
/// depends on the pixels its grid box covers, not on the object's triangles.
///
/// Put it on the entity with the object's `Mesh3d`. Either give it a field baked beforehand
/// (`ao_bake`, loaded from a `.aofield` file), or let the plugin bake one from the entity's mesh
/// when it appears: on the async compute pool, cached on disk in [`AoFieldCache`], so the frame
/// never waits and the next run loads it.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone, Debug)]
pub enum AoField {
    /// A baked field, e.g. `asset_server.load("crate.aofield")`, in the mesh's space.
    Asset(Handle<AoFieldData>),
    /// Bake from the entity's own mesh with these settings.
    Bake(#[reflect(ignore)] BakeSettings),
}

impl Default for AoField {
    /// Bake from the entity's mesh with [`BakeSettings::default`] (32³, ε = 0.1, 256 rays).
    fn default() -> Self {
        Self::Bake(BakeSettings::default())
    }
}

/// Where fields baked on load are kept between runs: one `<hash>.aofield` file per mesh content
/// and bake settings. Default: `bevy_dynamic_ao/fields` in the system's temporary folder; set
/// `folder` to `None` to bake every run without touching the disk.
#[derive(Resource, Clone, Debug)]
pub struct AoFieldCache {
    /// The cache folder, created when first written.
    pub folder: Option<PathBuf>,
}

impl Default for AoFieldCache {
    fn default() -> Self {
        Self {
            folder: Some(std::env::temp_dir().join("bevy_dynamic_ao").join("fields")),
        }
    }
}

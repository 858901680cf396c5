//! Main-world systems: turning each [`AoField`] into a loaded field asset, baking (on the async
//! compute pool, through the disk cache) where asked.

use std::path::PathBuf;

use bevy::asset::{AssetId, Assets, Handle};
use bevy::ecs::prelude::*;
use bevy::log::{info, warn};
use bevy::math::Affine3A;
use bevy::mesh::{Mesh, Mesh3d};
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::{GlobalTransform, Name};
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};

use super::baker::{BakeSettings, bake};
use super::component::{AoField, AoFieldCache};
use super::format::AoFieldData;
use crate::reference::scene::{Triangle, TriangleScene};

/// The field an [`AoField`] occluder casts from, added by the plugin once that field exists
/// (loaded, or baked on load). Until then the occluder casts nothing.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct ActiveAoField(pub Handle<AoFieldData>);

type BakeKey = (AssetId<Mesh>, [u32; 4]);
type BakeResult = Result<AoFieldData, String>;

/// Fields baked (or being baked) from meshes this run.
#[derive(Resource, Default)]
pub(crate) struct BakedFields {
    ready: HashMap<BakeKey, Result<Handle<AoFieldData>, String>>,
    pending: HashMap<BakeKey, Task<BakeResult>>,
}

fn key(mesh: AssetId<Mesh>, settings: &BakeSettings) -> BakeKey {
    (
        mesh,
        [
            settings.resolution,
            settings.epsilon.to_bits(),
            settings.rays,
            u32::from(settings.rescale_border) | u32::from(settings.fill_interior) << 1,
        ],
    )
}

/// FNV-1a over the triangles and settings: the name of the cached file.
fn content_hash(triangles: &[Triangle], settings: &BakeSettings) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |bytes: &[u8]| {
        for b in bytes {
            hash = (hash ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for t in triangles {
        for v in t.vertices {
            for c in v.to_array() {
                eat(&c.to_le_bytes());
            }
        }
    }
    for v in key(AssetId::default(), settings).1 {
        eat(&v.to_le_bytes());
    }
    hash
}

fn bake_or_load(
    triangles: Vec<Triangle>,
    settings: BakeSettings,
    cache: Option<PathBuf>,
) -> BakeResult {
    let path = cache.map(|folder| {
        folder.join(format!(
            "{:016x}.aofield",
            content_hash(&triangles, &settings)
        ))
    });
    if let Some(path) = &path
        && let Ok(bytes) = std::fs::read(path)
    {
        match AoFieldData::from_bytes(&bytes) {
            Ok(field) => return Ok(field),
            // A bad cache file is baked again and replaced.
            Err(error) => warn!("AoField: ignoring cached {}: {error}", path.display()),
        }
    }
    let field = bake(triangles, &settings, &|_, _| {}).map_err(|e| e.to_string())?;
    if let Some(path) = &path {
        let written = path
            .parent()
            .map_or(Ok(()), std::fs::create_dir_all)
            .and_then(|_| std::fs::write(path, field.to_bytes()));
        if let Err(error) = written {
            warn!(
                "AoField: cannot cache the baked field in {}: {error}",
                path.display()
            );
        } else {
            info!("AoField: baked and cached {}", path.display());
        }
    }
    Ok(field)
}

pub(crate) fn resolve_fields(
    mut commands: Commands,
    occluders: Query<(
        Entity,
        &AoField,
        Option<&Mesh3d>,
        Option<&ActiveAoField>,
        Option<&Name>,
        Option<&GlobalTransform>,
    )>,
    meshes: Res<Assets<Mesh>>,
    mut fields: ResMut<Assets<AoFieldData>>,
    cache: Res<AoFieldCache>,
    mut baked: ResMut<BakedFields>,
    mut warned: Local<HashSet<Entity>>,
    mut degenerate: Local<HashSet<Entity>>,
) {
    // Finished bakes become assets.
    let mut finished = Vec::new();
    for (key, task) in baked.pending.iter_mut() {
        if let Some(result) = check_ready(task) {
            finished.push((*key, result));
        }
    }
    for (key, result) in finished {
        baked.pending.remove(&key);
        baked
            .ready
            .insert(key, result.map(|field| fields.add(field)));
    }

    for (entity, field, mesh, resolved, name, transform) in &occluders {
        // The render pass skips an occluder it cannot place; say so once.
        let placeable = transform.is_none_or(|t| {
            let affine = t.affine();
            affine.is_finite() && affine.matrix3.determinant().abs() > 1e-12
        });
        if !placeable {
            if degenerate.insert(entity) {
                warn!(
                    "AoField on {entity}: its transform is zero-size or not finite; it casts no \
                     field while that lasts"
                );
            }
        } else {
            degenerate.remove(&entity);
        }
        let handle = match field {
            AoField::Asset(handle) => Some(Ok(handle.clone())),
            AoField::Bake(settings) => {
                let Some(mesh) = mesh else {
                    if warned.insert(entity) {
                        warn!(
                            "AoField::Bake on {entity} needs a Mesh3d on the same entity; it casts no field"
                        );
                    }
                    continue;
                };
                let key = key(mesh.id(), settings);
                if let Some(result) = baked.ready.get(&key) {
                    Some(result.clone())
                } else {
                    if !baked.pending.contains_key(&key)
                        && let Some(data) = meshes.get(mesh.id())
                    {
                        let mut scene = TriangleScene::default();
                        scene.add_mesh(data, Affine3A::IDENTITY);
                        let (settings, folder) = (*settings, cache.folder.clone());
                        let task = AsyncComputeTaskPool::get()
                            .spawn(async move { bake_or_load(scene.triangles, settings, folder) });
                        baked.pending.insert(key, task);
                    }
                    None
                }
            }
        };
        match handle {
            Some(Ok(handle)) if resolved.is_none_or(|r| r.0 != handle) => {
                commands.entity(entity).insert(ActiveAoField(handle));
            }
            Some(Err(error)) if warned.insert(entity) => {
                let label =
                    name.map_or_else(|| format!("{entity}"), |n| format!("'{n}' ({entity})"));
                warn!("AoField on {label} casts no field: {error}");
            }
            _ => {}
        }
    }
}

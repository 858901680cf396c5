//! Main-world systems: turning each [`AoField`] into a loaded field asset, baking (on the async
//! compute pool, through the disk cache) where asked.

use std::path::Path;

use bevy::asset::{AssetEvent, AssetId, Assets, Handle};
use bevy::ecs::prelude::*;
use bevy::log::{info, warn};
use bevy::math::{Affine3A, Vec3};
use bevy::mesh::morph::{MeshMorphWeights, MorphWeights};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::mesh::{Mesh, Mesh3d};
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::{GlobalTransform, Name};
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};

use super::baker::{BakeGrid, BakeSettings, FieldReach, bake};
use super::cache::{self, CacheMiss};
use super::component::{AoField, AoFieldCache};
use super::format::{self, AoFieldData};
use crate::geometry::deform::{Deformer, Pose};
use crate::geometry::deform::{mesh_morph_weights, skin_joints};
use crate::geometry::rest_mesh::RestMesh;
use crate::geometry::triangles::{Triangle, TriangleScene};
use crate::settings::{DEFAULT_NEAR_FIELD_RADIUS, DEFAULT_RADIUS, DynamicAo};

/// The field an [`AoField`] occluder casts from, added by the plugin once that field exists
/// (loaded, or baked on load). Until then the occluder casts nothing.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct ActiveAoField {
    /// The field.
    pub field: Handle<AoFieldData>,
    /// The scale the field was baked at: its grid lies in the mesh's space scaled by this (per
    /// axis, no unit), so that its reach is measured in world units. The entity's own scale is
    /// taken out where it is placed. `Vec3::ONE` for a field loaded from a file, which lies in
    /// the mesh's space and reaches as far in mesh units as it was baked for.
    pub baked_scale: Vec3,
}

/// On an [`AoField::Bake`] occluder while its field for the current cameras' radii is being baked
/// (in the background); the field it had before, if any, stays active meanwhile. Tools that
/// capture one frame wait until no occluder carries it.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PendingAoField;

/// Each warning an occluder can get, said once per occluder and kind (one set per kind, so that
/// one warning never hides another).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) enum FieldWarning {
    NoMesh,
    MeshNotReadable,
    Failed,
    Degenerate,
    Posed,
}

/// Taking `AoField` away takes its field away: the occluder stops casting on the next frame.
pub(crate) fn remove_active_field(remove: On<Remove, AoField>, mut commands: Commands) {
    if let Ok(mut occluder) = commands.get_entity(remove.entity) {
        occluder.try_remove::<(ActiveAoField, PendingAoField)>();
    }
}

/// A bake: the mesh, for a posed (skinned or morphed) mesh the entity whose pose it is, the
/// settings and the scale (in [`scale_steps`]).
type BakeKey = (AssetId<Mesh>, Option<Entity>, [u32; 7], [i32; 3]);
type BakeResult = Result<AoFieldData, String>;

/// Fields baked (or being baked) from meshes this run.
#[derive(Resource, Default)]
pub(crate) struct BakedFields {
    ready: HashMap<BakeKey, Result<Handle<AoFieldData>, String>>,
    pending: HashMap<BakeKey, Task<BakeResult>>,
}

fn settings_key(settings: &BakeSettings) -> [u32; 7] {
    let (kind, a, b) = match settings.reach {
        FieldReach::CameraRadius => (0, 0.0, 0.0),
        FieldReach::Distance { reach, near } => (1, reach, near),
        FieldReach::Unlimited { epsilon } => (2, epsilon, 0.0),
    };
    [
        settings.resolution,
        kind,
        a.to_bits(),
        b.to_bits(),
        settings.rays,
        u32::from(settings.rescale_border)
            | u32::from(settings.fill_interior) << 1
            | u32::from(settings.axis_correction) << 2,
        super::format::VERSION,
    ]
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
    for v in settings_key(settings) {
        eat(&v.to_le_bytes());
    }
    // Files of another format version are other files: they miss instead of being rejected. So
    // are those of another release of this crate, whose baker may count differently.
    eat(&format::VERSION.to_le_bytes());
    eat(env!("CARGO_PKG_VERSION").as_bytes());
    hash
}

fn bake_or_load(
    triangles: Vec<Triangle>,
    settings: BakeSettings,
    cache: AoFieldCache,
) -> BakeResult {
    let path = cache.folder.as_ref().map(|folder| {
        folder.join(format!(
            "{:016x}.{}",
            content_hash(&triangles, &settings),
            cache::FIELD_EXTENSION
        ))
    });
    let grid = BakeGrid::plan(&triangles, &settings);
    if let (Some(path), Some(grid)) = (&path, &grid) {
        match cache::read(path, grid) {
            Ok(field) => return Ok(field),
            Err(CacheMiss::Absent) => {}
            // A file that is not to be trusted is baked again and replaced.
            Err(CacheMiss::Rejected(why)) => {
                warn!("AoField: ignoring cached {}: {why}", path.display());
            }
        }
    }
    let field = bake(triangles, &settings, &|_, _| {}).map_err(|e| e.to_string())?;
    if let Some(path) = &path {
        match cache::write(path, &field) {
            Ok(()) => {
                info!("AoField: baked and cached {}", path.display());
                prune(path, cache.max_bytes);
            }
            Err(error) => warn!(
                "AoField: cannot cache the baked field in {}: {error}",
                path.display()
            ),
        }
    }
    Ok(field)
}

/// Keeps the cache folder of `written` under `max_bytes` (see [`AoFieldCache::max_bytes`]).
fn prune(written: &Path, max_bytes: u64) {
    let Some(folder) = written.parent() else {
        return;
    };
    match cache::prune(folder, max_bytes, written) {
        Ok(pruned) if pruned.files > 0 => info!(
            "AoField: deleted the {} cached fields used longest ago ({:.1} MB) to keep {} under \
             {:.1} MB",
            pruned.files,
            pruned.bytes as f64 / 1e6,
            folder.display(),
            max_bytes as f64 / 1e6
        ),
        Ok(_) => {}
        Err(error) => warn!(
            "AoField: cannot keep the field cache {} under its size: {error}",
            folder.display()
        ),
    }
}

/// Steps of a scale per doubling: a field is baked again when its entity's scale changes by
/// more than about 1 %.
const SCALE_STEPS_PER_OCTAVE: f32 = 64.0;

/// An entity's world scale (per axis, positive) in steps of [`SCALE_STEPS_PER_OCTAVE`], and the
/// scale those steps stand for. Rays count hits within R world units, so a mesh is baked at its
/// world scale: baked in mesh space, a model scaled by 0.01 (a glTF file in centimetres) would
/// reach 0.01 R.
fn scale_steps(transform: Option<&GlobalTransform>) -> ([i32; 3], Vec3) {
    let scale = transform.map_or(Vec3::ONE, |t| t.to_scale_rotation_translation().0.abs());
    let steps = scale.to_array().map(|s| {
        if s.is_finite() && s > 0.0 {
            (s.log2() * SCALE_STEPS_PER_OCTAVE)
                .round()
                .clamp(-4096.0, 4096.0) as i32
        } else {
            0
        }
    });
    let snapped = Vec3::from_array(steps.map(|k| (k as f32 / SCALE_STEPS_PER_OCTAVE).exp2()));
    (steps, snapped)
}

/// Frames a skinned or morphed occluder is seen before it is baked, so that an animation set on
/// the frame it appears has posed it.
const POSE_FRAMES: u32 = 3;

/// The radius R and near-field reach the fields should count within: the largest among the
/// cameras with [`DynamicAo`], the crate's defaults without one.
fn camera_reach(cameras: &Query<&DynamicAo>) -> (f32, f32) {
    let mut reach: Option<(f32, f32)> = None;
    for ao in cameras {
        let radius = ao.effective_radius();
        let near = radius.min(ao.effective_near_field_radius());
        reach = Some(reach.map_or((radius, near), |(r, n)| (r.max(radius), n.max(near))));
    }
    reach.unwrap_or((
        DEFAULT_RADIUS,
        DEFAULT_RADIUS.min(DEFAULT_NEAR_FIELD_RADIUS),
    ))
}

type Occluders<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static AoField,
        Option<&'static Mesh3d>,
        Option<&'static ActiveAoField>,
        Has<PendingAoField>,
        Option<&'static Name>,
        Option<&'static GlobalTransform>,
        Option<&'static SkinnedMesh>,
        Option<&'static MeshMorphWeights>,
    ),
>;

/// The triangles to bake for one occluder, in its mesh's space scaled by `scale`: the mesh as
/// stored, or for a skinned or morphed mesh its current pose brought back into the entity's
/// space.
fn bake_triangles(
    mesh: &Mesh,
    posed: Option<(&GlobalTransform, &[Affine3A], &[f32])>,
    scale: Vec3,
) -> Vec<Triangle> {
    let scaled = Affine3A::from_scale(scale);
    let mut scene = TriangleScene::default();
    let Some((transform, joints, weights)) = posed else {
        scene.add_mesh(mesh, scaled);
        return scene.triangles;
    };
    let Ok(rest) = RestMesh::from_mesh(mesh) else {
        scene.add_mesh(mesh, scaled);
        return scene.triangles;
    };
    let pose = Pose {
        world_from_mesh: transform.affine(),
        joints,
        morph_weights: weights,
    };
    let deformer = Deformer::new(&rest, &pose);
    let mesh_from_world = scaled * transform.affine().inverse();
    let points: Vec<Vec3> = (0..rest.positions.len())
        .map(|v| mesh_from_world.transform_point3(deformer.point(v).into()))
        .collect();
    rest.triangles
        .iter()
        .map(|t| Triangle {
            vertices: t.map(|i| points[i as usize]),
            normals: None,
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn resolve_fields(
    mut commands: Commands,
    occluders: Occluders,
    cameras: Query<&DynamicAo>,
    transforms: Query<&GlobalTransform>,
    morph_weights: Query<&MorphWeights>,
    meshes: Res<Assets<Mesh>>,
    inverse_bindposes: Res<Assets<SkinnedMeshInverseBindposes>>,
    mut fields: ResMut<Assets<AoFieldData>>,
    cache: Res<AoFieldCache>,
    mut baked: ResMut<BakedFields>,
    mut mesh_events: MessageReader<AssetEvent<Mesh>>,
    mut warned: Local<HashSet<(Entity, FieldWarning)>>,
    mut joints: Local<Vec<Affine3A>>,
    mut seen_for: Local<HashMap<Entity, u32>>,
) {
    // A mesh edited at runtime is baked again (its old field stays until the new one is ready).
    for event in mesh_events.read() {
        if let AssetEvent::Modified { id } = event {
            baked.ready.retain(|key, _| key.0 != *id);
            baked.pending.retain(|key, _| key.0 != *id);
        }
    }
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
    let (radius, near) = camera_reach(&cameras);
    seen_for.retain(|e, _| occluders.contains(*e));
    warned.retain(|(e, _)| occluders.contains(*e));
    // The bakes some occluder asks for this frame; the others are freed at the end.
    let mut used = HashSet::new();

    for (entity, field, mesh, resolved, pending, name, transform, skinned, morphs) in &occluders {
        let label = || name.map_or_else(|| format!("{entity}"), |n| format!("'{n}' ({entity})"));
        // The render pass skips an occluder it cannot place; say so once.
        let placeable = transform.is_none_or(|t| {
            let affine = t.affine();
            affine.is_finite() && affine.matrix3.determinant().abs() > 1e-12
        });
        if !placeable {
            if warned.insert((entity, FieldWarning::Degenerate)) {
                warn!(
                    "AoField on {}: its transform is zero-size or not finite; it casts no field \
                     while that lasts",
                    label()
                );
            }
        } else {
            warned.remove(&(entity, FieldWarning::Degenerate));
        }
        let handle = match field {
            AoField::Asset(handle) => Some(Ok((handle.clone(), Vec3::ONE))),
            AoField::Bake(settings) => {
                let Some(mesh) = mesh else {
                    if warned.insert((entity, FieldWarning::NoMesh)) {
                        warn!(
                            "AoField::Bake on {} needs a Mesh3d on the same entity; it casts no \
                             field",
                            label()
                        );
                    }
                    continue;
                };
                if meshes
                    .get(mesh.id())
                    .is_some_and(|m| m.try_attribute_option(Mesh::ATTRIBUTE_POSITION).is_err())
                {
                    if warned.insert((entity, FieldWarning::MeshNotReadable)) {
                        warn!(
                            "AoField::Bake on {}: its mesh's vertex data was moved to the render \
                             world (RenderAssetUsages without MAIN_WORLD), so it cannot be baked; \
                             it casts no field (keep MAIN_WORLD, or load a baked .aofield with \
                             AoField::Asset)",
                            label()
                        );
                    }
                    if resolved.is_some() || pending {
                        commands
                            .entity(entity)
                            .remove::<(ActiveAoField, PendingAoField)>();
                    }
                    continue;
                }
                if !placeable {
                    // No scale to bake at: a field baked at scale 1 would be thrown away once
                    // the transform is usable again, at its own scale. The field it had stays
                    // (the render pass skips it while it cannot be placed).
                    if pending {
                        commands.entity(entity).remove::<PendingAoField>();
                    }
                    continue;
                }
                let (steps, scale) = scale_steps(transform);
                let settings = settings.for_camera(radius, near);
                let weights = mesh_morph_weights(morphs, &morph_weights);
                let posed = skinned.is_some() || weights.iter().any(|w| *w != 0.0);
                let key = (
                    mesh.id(),
                    posed.then_some(entity),
                    settings_key(&settings),
                    steps,
                );
                // A posed mesh waits a few frames for its animation to be applied.
                let frames = seen_for.entry(entity).or_insert(0);
                *frames += 1;
                let settled = !posed || *frames > POSE_FRAMES;
                used.insert(key);
                if let Some(result) = baked.ready.get(&key) {
                    Some(result.clone().map(|handle| (handle, scale)))
                } else {
                    if settled
                        && !baked.pending.contains_key(&key)
                        && let Some(data) = meshes.get(mesh.id())
                    {
                        let pose = match (posed, transform) {
                            (true, Some(transform)) => {
                                if warned.insert((entity, FieldWarning::Posed)) {
                                    warn!(
                                        "AoField on {}: a skinned or morphed mesh is baked in \
                                         the pose it has now and then moves rigidly with its \
                                         entity; for animated meshes use SphereOccluder or a \
                                         VoxelAoVolume",
                                        label()
                                    );
                                }
                                if let Some(skinned) = skinned {
                                    skin_joints(
                                        skinned,
                                        &inverse_bindposes,
                                        &transforms,
                                        &mut joints,
                                    );
                                } else {
                                    joints.clear();
                                }
                                Some((transform, joints.as_slice(), weights))
                            }
                            _ => None,
                        };
                        let triangles = bake_triangles(data, pose, scale);
                        let cache = cache.clone();
                        let task = AsyncComputeTaskPool::get().spawn(async move {
                            let mut field = bake_or_load(triangles, settings, cache);
                            if posed && let Ok(field) = &mut field {
                                // Its own surface moves away from where it was baked (a running
                                // fox's legs): measured darker than the near field alone.
                                field.own_surface.fill([0.0; 4]);
                            }
                            field
                        });
                        baked.pending.insert(key, task);
                    }
                    None
                }
            }
        };
        match handle {
            Some(Ok((field, baked_scale))) => {
                if resolved.is_none_or(|r| r.field != field || r.baked_scale != baked_scale) {
                    commands
                        .entity(entity)
                        .insert(ActiveAoField { field, baked_scale });
                }
                if pending {
                    commands.entity(entity).remove::<PendingAoField>();
                }
            }
            Some(Err(error)) => {
                if pending {
                    commands.entity(entity).remove::<PendingAoField>();
                }
                if warned.insert((entity, FieldWarning::Failed)) {
                    warn!("AoField on {} casts no field: {error}", label());
                }
            }
            None => {
                if !pending {
                    commands.entity(entity).insert(PendingAoField);
                }
            }
        }
    }
    // A field no occluder asks for any more is freed once no `ActiveAoField` holds it; a bake
    // nobody waits for is dropped (which cancels it).
    baked.ready.retain(|key, _| used.contains(key));
    baked.pending.retain(|key, _| used.contains(key));
}

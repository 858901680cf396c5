//! Meshes Bevy cannot draw: a glTF primitive whose `POSITION` accessor could not be read (it runs
//! past its buffer, or holds other than three floats per vertex) loads as a mesh without
//! positions, and Bevy's prepass pipeline fails wgpu's validation on it; a skinned node whose
//! mesh has no usable `JOINTS_0` or `WEIGHTS_0` fails it in the skinned draw. Either ends the app
//! with no image. The capture leaves such meshes out, or draws such a node unskinned in its rest
//! pose, with a warning naming it, and renders the rest.
//!
//! Cameras Bevy cannot place: a camera node whose transform, or an ancestor's, has a zero scale
//! or a value that is not finite has no view direction, and Bevy's frustum update panics on it
//! (in builds with debug assertions; in others it renders a view of nothing). The capture gives
//! such cameras a neutral place before Bevy reads it and, where it is the one to render through,
//! says why in one line.

use bevy::math::Affine3A;
use bevy::mesh::VertexAttributeValues;
use bevy::mesh::skinning::SkinnedMesh;
use bevy::prelude::*;

/// Why `mesh` cannot be drawn, or `None` where it can.
pub fn why_undrawable(mesh: &Mesh) -> Option<&'static str> {
    match mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION) {
        // Data kept only in the render world: Bevy built it, so it can draw it.
        Err(_) => None,
        Ok(None) => Some("it has no readable POSITION attribute"),
        Ok(Some(VertexAttributeValues::Float32x3(_))) => None,
        Ok(Some(_)) => Some("its POSITION attribute is not three floats per vertex"),
    }
}

/// Why `mesh` cannot be skinned, or `None` where it can (the formats Bevy's glTF loader gives
/// readable joints and weights).
pub fn why_unskinnable(mesh: &Mesh) -> Option<&'static str> {
    let joints = mesh.try_attribute_option(Mesh::ATTRIBUTE_JOINT_INDEX);
    let weights = mesh.try_attribute_option(Mesh::ATTRIBUTE_JOINT_WEIGHT);
    match (joints, weights) {
        (Err(_), _) | (_, Err(_)) => None,
        (
            Ok(Some(VertexAttributeValues::Uint16x4(_))),
            Ok(Some(VertexAttributeValues::Float32x4(_))),
        ) => None,
        (Ok(None), _) => Some("its mesh has no readable JOINTS_0 attribute"),
        (_, Ok(None)) => Some("its mesh has no readable WEIGHTS_0 attribute"),
        _ => {
            Some("its mesh's JOINTS_0 or WEIGHTS_0 attribute has a format Bevy does not skin with")
        }
    }
}

/// Takes `Mesh3d` off every mesh under `root` that Bevy cannot draw, and `SkinnedMesh` off every
/// one it cannot skin, naming each in a warning.
pub fn leave_out_undrawable(
    commands: &mut Commands,
    root: Entity,
    children: &Query<&Children>,
    meshes: &Query<(&Mesh3d, Option<&Name>, Has<SkinnedMesh>)>,
    assets: &Assets<Mesh>,
) {
    for entity in children.iter_descendants(root) {
        let Ok((mesh, name, skinned)) = meshes.get(entity) else {
            continue;
        };
        let Some(mesh) = assets.get(&mesh.0) else {
            continue;
        };
        let name = name.map_or_else(|| format!("{entity}"), |n| format!("'{n}'"));
        if let Some(why) = why_undrawable(mesh) {
            warn!("mesh {name} is left out: {why} (the file's accessor could not be read)");
            commands.entity(entity).remove::<Mesh3d>();
        } else if let Some(why) = why_unskinnable(mesh).filter(|_| skinned) {
            warn!("mesh {name} is drawn unskinned, in its rest pose: {why}");
            commands.entity(entity).remove::<SkinnedMesh>();
        }
    }
}

/// Whether the node `entity` lies in the world with no view direction: its transform composed
/// with its ancestors' has a zero-size or non-finite linear part.
pub fn unplaceable(entity: Entity, transforms: &Query<(&Transform, Option<&ChildOf>)>) -> bool {
    let mut world_from_node = Affine3A::IDENTITY;
    let mut node = Some(entity);
    while let Some(current) = node {
        let Ok((transform, parent)) = transforms.get(current) else {
            break;
        };
        world_from_node = transform.compute_affine() * world_from_node;
        node = parent.map(ChildOf::parent);
    }
    !(world_from_node.is_finite() && world_from_node.matrix3.determinant().abs() > 1e-12)
}

/// Gives every camera whose world transform has no view direction (a zero scale, or a value that
/// is not finite) the identity instead, before Bevy's frustum update reads it. Runs in
/// `PostUpdate`, between transform propagation and the frustum update: the scene's cameras are
/// spawned a frame before the capture looks at the scene, and Bevy places them in between.
pub fn neutralize_unplaceable_cameras(
    mut cameras: Query<&mut GlobalTransform, (With<Camera>, Changed<GlobalTransform>)>,
) {
    for mut transform in &mut cameras {
        let affine = transform.affine();
        if !(affine.is_finite() && affine.matrix3.determinant().abs() > 1e-12) {
            *transform = GlobalTransform::IDENTITY;
        }
    }
}

//! Meshes Bevy cannot draw: a glTF primitive whose `POSITION` accessor could not be read (it runs
//! past its buffer, or holds other than three floats per vertex) loads as a mesh without
//! positions, and Bevy's prepass pipeline fails wgpu's validation on it, which ends the app with
//! no image. The capture leaves such meshes out with a warning instead, and renders the rest.

use bevy::mesh::VertexAttributeValues;
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

/// Takes `Mesh3d` off every mesh under `root` that Bevy cannot draw, naming each in a warning.
pub fn leave_out_undrawable(
    commands: &mut Commands,
    root: Entity,
    children: &Query<&Children>,
    meshes: &Query<(&Mesh3d, Option<&Name>)>,
    assets: &Assets<Mesh>,
) {
    for entity in children.iter_descendants(root) {
        let Ok((mesh, name)) = meshes.get(entity) else {
            continue;
        };
        let Some(why) = assets.get(&mesh.0).and_then(why_undrawable) else {
            continue;
        };
        let name = name.map_or_else(|| format!("{entity}"), |n| format!("'{n}'"));
        warn!("ao_capture: mesh {name} is left out: {why} (the file's accessor could not be read)");
        commands.entity(entity).remove::<Mesh3d>();
    }
}

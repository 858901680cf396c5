//! The sphere debug view: every occluder sphere drawn as a wire sphere.

use bevy::color::Color;
use bevy::ecs::prelude::*;
use bevy::gizmos::gizmos::Gizmos;
use bevy::math::Isometry3d;
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

use super::component::OccluderSpheres;

/// Draws every [`OccluderSpheres`] sphere with gizmos when `true` (needs Bevy's gizmo rendering,
/// `bevy_gizmos_render`, in the app). Default `false`.
#[derive(Resource, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Resource, Default)]
pub struct ShowOccluderSpheres(pub bool);

pub(crate) fn draw_spheres(
    show: Res<ShowOccluderSpheres>,
    occluders: Query<&OccluderSpheres>,
    mut gizmos: Gizmos,
) {
    if !show.0 {
        return;
    }
    let color = Color::srgb(1.0, 0.55, 0.1);
    for occluder in &occluders {
        for sphere in &occluder.spheres {
            gizmos
                .sphere(
                    Isometry3d::from_translation(sphere.center),
                    sphere.radius,
                    color,
                )
                .resolution(12);
        }
    }
}

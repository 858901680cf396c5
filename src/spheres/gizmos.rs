//! The proxy debug view: every far-field proxy drawn as a wire box or sphere.

use bevy::color::Color;
use bevy::ecs::prelude::*;
use bevy::gizmos::gizmos::Gizmos;
use bevy::math::{Affine3A, Isometry3d};
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

use super::component::{OccluderSpheres, ProxyShape};

/// Draws every [`OccluderSpheres`] proxy (wire box or sphere) with gizmos when `true` (needs Bevy's gizmo rendering,
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
        for proxy in &occluder.spheres {
            match proxy.shape {
                ProxyShape::Boxes => gizmos.cube(
                    Affine3A::from_mat3_translation(proxy.axes * 2.0, proxy.center),
                    color,
                ),
                ProxyShape::Spheres => {
                    gizmos
                        .sphere(
                            Isometry3d::from_translation(proxy.center),
                            proxy.radius,
                            color,
                        )
                        .resolution(12);
                }
            }
        }
    }
}

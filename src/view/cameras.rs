//! Main-world checks of the cameras that carry [`DynamicAo`]: those the plugin cannot serve
//! render without it, with one warning.

use bevy::camera::Camera;
use bevy::ecs::prelude::*;
use bevy::log::warn;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::platform::collections::HashSet;
use bevy::render::view::Msaa;

use crate::settings::DynamicAo;

/// Why a camera with [`DynamicAo`] renders without it.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(super) enum Unsupported {
    Msaa,
    EmptyViewport,
}

/// Marks a camera the plugin switched off because its viewport had no pixels: Bevy's renderer
/// rejects zero-size views (a validation error that stops the app), so the camera waits,
/// inactive, until its viewport has pixels again.
#[derive(Component)]
pub(crate) struct SuspendedForEmptyViewport;

/// A camera as warnings name it: its `Name` and entity, or the entity.
fn label(entity: Entity, name: Option<&Name>) -> String {
    name.map_or_else(|| format!("{entity}"), |n| format!("'{n}' ({entity})"))
}

/// Taking `DynamicAo` away from a camera takes away the `ScreenSpaceAmbientOcclusion` it
/// required: the camera renders without ambient occlusion, as before it had the component (for
/// Bevy's SSAO, keep `DynamicAo` with `AoTechnique::BevySsao`). The render world drops the view's
/// state at the next extraction.
pub(super) fn remove_required_ssao(remove: On<Remove, DynamicAo>, mut commands: Commands) {
    if let Ok(mut camera) = commands.get_entity(remove.entity) {
        camera.try_remove::<ScreenSpaceAmbientOcclusion>();
    }
}

/// Cameras the plugin cannot serve lose Bevy's SSAO component (whose pass would fail on them)
/// and get one warning; they get it back once the problem is gone.
pub(super) fn check_cameras(
    mut commands: Commands,
    mut cameras: Query<(
        Entity,
        Ref<DynamicAo>,
        &mut Camera,
        &Msaa,
        Has<ScreenSpaceAmbientOcclusion>,
        Has<SuspendedForEmptyViewport>,
        Option<&Name>,
    )>,
    mut warned: Local<HashSet<(Entity, Unsupported)>>,
    mut warned_settings: Local<HashSet<(Entity, String)>>,
) {
    warned.retain(|(entity, _)| cameras.contains(*entity));
    warned_settings.retain(|(entity, _)| cameras.contains(*entity));
    for (entity, ao, .., name) in &cameras {
        // Settings are checked when they change, not every frame.
        if !ao.is_changed() {
            continue;
        }
        for problem in ao.problems() {
            if !warned_settings.contains(&(entity, problem.clone())) {
                warn!("DynamicAo on camera {}: {problem}", label(entity, name));
                warned_settings.insert((entity, problem));
            }
        }
    }
    for (entity, ao, mut camera, msaa, has_ssao, suspended, name) in &mut cameras {
        let empty_viewport = camera
            .viewport
            .as_ref()
            .is_some_and(|v| v.physical_size.x == 0 || v.physical_size.y == 0);
        if empty_viewport && camera.is_active {
            camera.is_active = false;
            commands.entity(entity).insert(SuspendedForEmptyViewport);
        } else if !empty_viewport && suspended {
            camera.is_active = true;
            commands
                .entity(entity)
                .remove::<SuspendedForEmptyViewport>();
        }
        // Bevy's SSAO extraction logs an error for every MSAA camera carrying its component, so
        // none of them does: compose gives the render-world view the component instead.
        let msaa_on = *msaa != Msaa::Off;
        let problem = if msaa_on && !ao.works_with_msaa() {
            Some(Unsupported::Msaa)
        } else if empty_viewport {
            Some(Unsupported::EmptyViewport)
        } else {
            None
        };
        match problem {
            Some(problem) => {
                if warned.insert((entity, problem)) {
                    let label = label(entity, name);
                    match problem {
                        Unsupported::Msaa => warn!(
                            "AoTechnique::BevySsao on camera {label} needs Msaa::Off (it is \
                             {msaa:?}); rendering this camera without ambient occlusion (every \
                             other technique works with MSAA)"
                        ),
                        Unsupported::EmptyViewport => warn!(
                            "camera {label} has a zero-size viewport, which Bevy's renderer \
                             rejects; DynamicAo deactivates the camera until the viewport has \
                             pixels"
                        ),
                    }
                }
                if has_ssao {
                    commands
                        .entity(entity)
                        .remove::<ScreenSpaceAmbientOcclusion>();
                }
            }
            None if msaa_on => {
                warned.retain(|(e, _)| *e != entity);
                if has_ssao {
                    commands
                        .entity(entity)
                        .remove::<ScreenSpaceAmbientOcclusion>();
                }
            }
            None => {
                warned.retain(|(e, _)| *e != entity);
                if !has_ssao {
                    commands
                        .entity(entity)
                        .insert(ScreenSpaceAmbientOcclusion::default());
                }
            }
        }
    }
}

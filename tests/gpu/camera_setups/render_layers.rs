//! `RenderLayers`: far-field occluders cast only on the views that share a layer with them.

use bevy::camera::visibility::RenderLayers;
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;

use crate::far_scenes::{self, FarRun};
use crate::far_terms::FarTerm;
use crate::harness::largest_difference;
use crate::models::shared_assets;

/// Far-field occluders cast only on views that share a render layer with them, as Bevy draws
/// them. An occluder just outside the view on layer 1 (the floor on layers 0 and 1) casts on a
/// layer-0 camera what no occluder casts, and on a layer-1 camera what it casts when everything
/// is on layer 0. Each term alone, every mesh an occluder (spheres, AO fields, one voxel volume,
/// given layer 1 with the camera as it voxelizes the meshes on every one of its layers), at
/// R = 0.75 m and 2 m: a box beside the view, and the third-party CesiumMan beside it (where the
/// shared assets exist).
#[test]
fn render_layers_decide_which_views_each_term_casts_on() {
    let scene = far_scenes::procedural().swap_remove(4);
    assert_eq!(scene.name, "box beside view");
    let mut run = FarRun::new(&scene, None);
    let cube = {
        let world = run.gpu.app.world_mut();
        let mut query = world.query::<&Transform>();
        let beside = |e: &&Entity| query.get(world, **e).unwrap().translation.x > 1.0;
        *run.meshes.iter().find(beside).expect("the box")
    };
    check_layers(&mut run, scene.name, cube, &[cube]);
    // One app at a time holds the GPU.
    drop(run);

    let Some(folder) = shared_assets() else {
        return;
    };
    let scene = far_scenes::third_party().pop().expect("a scene");
    assert_eq!(scene.name, "CesiumMan beside view");
    let mut run = FarRun::new(&scene, folder.to_str());
    let world = run.gpu.app.world_mut();
    let root = world
        .query_filtered::<Entity, With<bevy::world_serialization::WorldAssetRoot>>()
        .single(world)
        .expect("the model's root");
    let model: Vec<Entity> = world
        .query_filtered::<Entity, (With<Mesh3d>, With<ChildOf>)>()
        .iter(world)
        .collect();
    check_layers(&mut run, scene.name, root, &model);
}

/// The checks of [`render_layers_decide_which_views_each_term_casts_on`] on `run`, whose
/// occluder `meshes` move with `root` and every other mesh is floor.
fn check_layers(run: &mut FarRun, name: &str, root: Entity, meshes: &[Entity]) {
    let camera = run.gpu.camera;
    let floors: Vec<Entity> = run
        .meshes
        .iter()
        .copied()
        .filter(|e| !meshes.contains(e))
        .collect();
    let placed = *run.gpu.app.world().get::<Transform>(root).unwrap();
    let place = |run: &mut FarRun, transform: Transform| {
        run.gpu.app.world_mut().entity_mut(root).insert(transform);
    };
    for radius in [0.75, 2.0] {
        for term in FarTerm::ALL {
            let render = |run: &mut FarRun| {
                run.render(false, Some(term), FarFieldBlend::CountOnce, radius)
                    .visibility
            };
            let with = render(run);
            place(
                run,
                placed.with_translation(placed.translation + Vec3::X * 100.0),
            );
            let without = render(run);
            place(run, placed);

            let world = run.gpu.app.world_mut();
            for &mesh in meshes {
                world.entity_mut(mesh).insert(RenderLayers::layer(1));
            }
            for &floor in &floors {
                world
                    .entity_mut(floor)
                    .insert(RenderLayers::from_layers(&[0, 1]));
            }
            let other_layer = render(run);

            // Placed by the first render with voxels at this radius.
            let volume = run.volume();
            let world = run.gpu.app.world_mut();
            for entity in [Some(camera), volume].into_iter().flatten() {
                world.entity_mut(entity).insert(RenderLayers::layer(1));
            }
            let same_layer = render(run);

            let world = run.gpu.app.world_mut();
            let all = [Some(camera), volume]
                .into_iter()
                .flatten()
                .chain(meshes.iter().copied())
                .chain(floors.iter().copied());
            for entity in all {
                world.entity_mut(entity).remove::<RenderLayers>();
            }
            let term = term.name();
            let casts = largest_difference(&with, &without);
            let hidden = largest_difference(&other_layer, &without);
            let seen = largest_difference(&same_layer, &with);
            println!(
                "{name}, R = {radius} m, {term}: the occluder casts up to {casts}; other layer \
                 {hidden}, same layer {seen}"
            );
            // Measured at least 0.047 (CesiumMan's proxies at R = 0.75 m).
            assert!(
                casts > 0.03,
                "{name}, {term}: the occluder casts only {casts}"
            );
            assert!(
                hidden < 1e-4,
                "{name}, R = {radius} m, {term}: on another layer it casts {hidden}"
            );
            assert!(
                seen < 1e-4,
                "{name}, R = {radius} m, {term}: on a shared layer off by {seen}"
            );
        }
    }
}

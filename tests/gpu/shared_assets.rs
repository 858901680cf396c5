//! The back-face layer on third-party models from `../shared/assets` (or the folder in
//! `DYNAMIC_AO_SHARED_ASSETS`): an animated character has the same silhouette in both layers,
//! and the depth-only layer the default draws holds the nearest back faces a CPU ray cast finds.
//! Skipped, with a message, where the folder is absent.

use bevy::prelude::*;
use bevy_dynamic_ao::geometry::bvh::Bvh;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::nd_buffer::ViewMatrices;

use crate::far_scenes::{self, FarRun};
use crate::far_terms::FarTerm;
use crate::harness::{Gpu, HEIGHT, SceneSpec, WIDTH, plain_ao};
use crate::models::{load_model, shared_assets};

#[test]
fn animated_fox_has_the_same_silhouette_in_both_layers() {
    let Some(folder) = shared_assets() else {
        return;
    };
    // The fox model is about 150 units long; frame it from a few lengths away.
    let camera =
        Transform::from_xyz(120.0, 80.0, 160.0).looking_at(Vec3::new(0.0, 30.0, 0.0), Vec3::Y);
    let mut gpu = Gpu::with_asset_folder(&SceneSpec::new(camera), plain_ao(), folder.to_str());
    // The run cycle, half a second in.
    load_model(&mut gpu, "Fox/Fox.glb", Some(2), 0.5);
    let frame = gpu.frame(8);
    let front: Vec<bool> = frame.nd.front.iter().map(|t| t.depth > 0.0).collect();
    let back: Vec<bool> = frame.nd.back.iter().map(|t| t.depth > 0.0).collect();
    let count = front.iter().filter(|f| **f).count();
    let differ = front.iter().zip(&back).filter(|(f, b)| f != b).count();
    println!("Fox: {count} front pixels, {differ} differ in the back layer");
    assert!(count > 500, "the fox should be in view ({count} pixels)");
    assert!(
        differ * 50 < count,
        "the layers' silhouettes differ in {differ} of {count} pixels"
    );
}

/// Reverse-Z depth of the nearest back face (a triangle facing away from the ray) along the ray
/// through the centre of pixel (x, y), or 0 where the ray meets none: what the back layer holds.
fn traced_back_depth(bvh: &Bvh, view: &ViewMatrices, x: u32, y: u32) -> f32 {
    let eye = view.view_from_world.inverse().w_axis.truncate();
    let near = view.world_position(x as i32, y as i32, WIDTH, HEIGHT, 1.0);
    let dir = (near - eye).normalize();
    let mut t_min = 0.0;
    for _ in 0..256 {
        let Some(hit) = bvh.closest_hit(eye, dir, t_min, 1e4) else {
            return 0.0;
        };
        if bvh.triangles()[hit.triangle].face_normal().dot(dir) > 0.0 {
            let clip = view.clip_from_view * view.view_from_world * (eye + dir * hit.t).extend(1.0);
            return clip.z / clip.w;
        }
        t_min = hit.t * (1.0 + 1e-5) + 1e-5;
    }
    0.0
}

/// The default draws the back-face layer as depth only (no fragment stage); the near field draws
/// it with normals. On third-party models set up as a user would (a skinned character, a room of
/// thin walls, a character just outside the view, every mesh a sphere occluder and an AO field),
/// the depth-only layer equals the near field's and holds the nearest back faces a CPU ray cast
/// through the posed triangles finds.
#[test]
fn the_depth_only_back_layer_holds_the_traced_back_faces() {
    let Some(shared) = shared_assets() else {
        return;
    };
    for scene in far_scenes::third_party() {
        if ![
            "CesiumMan on floor",
            "CornellBox on floor",
            "CesiumMan beside view",
        ]
        .contains(&scene.name)
        {
            continue;
        }
        let mut run = FarRun::new(&scene, shared.to_str());
        let bvh = run.bvh();
        run.image_space = DynamicAo::default();
        let depth_only = run.render(true, Some(FarTerm::Spheres), FarFieldBlend::CountOnce, 0.75);
        run.image_space = plain_ao();
        let with_normals = run.render(true, Some(FarTerm::Spheres), FarFieldBlend::CountOnce, 0.75);

        let (mut drawn, mut same, mut traced, mut agree) = (0, 0, 0, 0);
        for (i, (a, b)) in depth_only
            .nd
            .back
            .iter()
            .zip(&with_normals.nd.back)
            .enumerate()
        {
            assert_eq!(
                a.normal,
                Vec3::ZERO,
                "{}: a normal in the depth-only layer",
                scene.name
            );
            if a.depth > 0.0 {
                drawn += 1;
                same += usize::from((a.depth - b.depth).abs() <= 1e-6);
            }
            let (x, y) = (i as u32 % WIDTH, i as u32 / WIDTH);
            let truth = traced_back_depth(&bvh, &depth_only.view, x, y);
            if truth > 0.0 || a.depth > 0.0 {
                traced += 1;
                let view_z = |d: f32| {
                    depth_only
                        .view
                        .view_position(x as i32, y as i32, WIDTH, HEIGHT, d)
                        .z
                };
                agree += usize::from(
                    truth > 0.0
                        && a.depth > 0.0
                        && (view_z(a.depth) - view_z(truth)).abs() <= 0.01 * -view_z(truth),
                );
            }
        }
        let share = agree as f32 / traced.max(1) as f32;
        println!(
            "{}: {drawn} back-layer pixels, {same} equal to the near field's; {agree} of {traced} \
             pixels with a traced or drawn back face agree within 1% of depth ({share:.3})",
            scene.name
        );
        assert_eq!(
            same, drawn,
            "{}: the depth-only layer differs from the near field's",
            scene.name
        );
        if scene.strip.is_some() {
            // The character stands outside the view: the layer holds nothing, as the ray cast.
            assert_eq!(
                (drawn, traced),
                (0, 0),
                "{}: back faces in view",
                scene.name
            );
            continue;
        }
        assert!(
            drawn > 100,
            "{}: the back layer should hold the model ({drawn})",
            scene.name
        );
        // Measured: 1.000 on CesiumMan, 0.955 on CornellBox. There 161 pixels inside one box
        // hold a back face behind the floor in both layers drawn (depth only and with normals)
        // where the ray cast, through the box's side and the floor, finds none: not explained
        // yet, and not this layer's doing, as the near field's layer holds the same.
        assert!(
            share >= 0.94,
            "{}: {agree} of {traced} pixels agree with the ray cast",
            scene.name
        );
    }
}

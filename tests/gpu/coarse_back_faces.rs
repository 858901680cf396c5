//! The back-face layer of meshes of many triangles, drawn from their coarse copies
//! (`DynamicAo::coarse_back_faces`): against the layer drawn from the meshes as they are, and
//! the AO of each against the CPU ray tracer.

use bevy::prelude::*;
use bevy_dynamic_ao::nd_buffer::COARSE_BACK_FACES_ABOVE;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::metrics::rmse;

use crate::harness::{Frame, Gpu, HEIGHT, SceneSpec, WIDTH, converged_frames};

/// A torus of `minor × major × 2` triangles, 0.9 m across.
fn torus(minor: u32, major: u32) -> Mesh {
    Torus::new(0.2, 0.45)
        .mesh()
        .minor_resolution(minor as usize)
        .major_resolution(major as usize)
        .build()
}

/// Two tori of 65,536 triangles on a floor, seen from above their rims; with `mirrored`, the
/// right one has scale −1 in x, which turns its winding on screen around (Bevy 0.19 culls by that
/// winding, so its prepass then holds the mirrored torus's far side, and the back layer its near
/// side).
fn fine_tori_on_floor(mirrored: bool) -> SceneSpec {
    let sign = if mirrored { -1.0 } else { 1.0 };
    SceneSpec::new(Transform::from_xyz(0.0, 1.4, 2.0).looking_at(Vec3::new(0.0, 0.2, 0.0), Vec3::Y))
        .with(
            Plane3d::default().mesh().size(10.0, 10.0).build(),
            Transform::IDENTITY,
        )
        .with(torus(128, 256), Transform::from_xyz(-0.55, 0.15, 0.0))
        .with(
            torus(128, 256),
            Transform::from_xyz(0.55, 0.15, 0.0).with_scale(Vec3::new(sign, 1.0, 1.0)),
        )
}

/// How the back layers of `coarse` and `full` compare, pixel by pixel: the pixels where both
/// hold a back face, those where only one does, those of the first kind within `near` metres of
/// each other (view space), and those that differ at all.
struct LayerDifference {
    both: usize,
    only_one: usize,
    near: usize,
    moved: usize,
}

impl LayerDifference {
    /// Asserts that the layers hold back faces in at least `least` pixels, in 99% of them within
    /// `near` of each other, and in one layer only in at most 1% of them.
    fn assert_close(&self, least: usize) {
        assert!(self.both > least, "back faces in {} pixels", self.both);
        assert!(
            self.near * 100 >= self.both * 99,
            "{} of {} within 2 cm",
            self.near,
            self.both
        );
        assert!(
            self.only_one * 100 <= self.both,
            "{} in one layer only",
            self.only_one
        );
    }
}

fn layer_difference(coarse: &Frame, full: &Frame, near: f32) -> LayerDifference {
    let mut d = LayerDifference {
        both: 0,
        only_one: 0,
        near: 0,
        moved: 0,
    };
    for y in 0..HEIGHT as i32 {
        for x in 0..WIDTH as i32 {
            let (Some(c), Some(f)) = (coarse.nd.texel(true, x, y), full.nd.texel(true, x, y))
            else {
                continue;
            };
            match (c.depth > 0.0, f.depth > 0.0) {
                (true, true) => {
                    d.both += 1;
                    let at = |depth| full.view.view_position(x, y, WIDTH, HEIGHT, depth);
                    let distance = at(c.depth).distance(at(f.depth));
                    d.near += usize::from(distance < near);
                    d.moved += usize::from(c.depth != f.depth);
                }
                (true, false) | (false, true) => d.only_one += 1,
                (false, false) => {}
            }
        }
    }
    d
}

/// The handles of the scene's meshes of more than [`COARSE_BACK_FACES_ABOVE`] triangles.
fn large_meshes(gpu: &mut Gpu) -> Vec<Handle<Mesh>> {
    let world = gpu.app.world_mut();
    let handles: Vec<Handle<Mesh>> = world
        .query::<&Mesh3d>()
        .iter(world)
        .map(|m| m.0.clone())
        .collect();
    let meshes = world.resource::<Assets<Mesh>>();
    handles
        .into_iter()
        .filter(|h| {
            meshes
                .get(h)
                .and_then(|m| m.indices())
                .is_some_and(|i| i.len() / 3 > COARSE_BACK_FACES_ABOVE)
        })
        .collect()
}

/// The default draws the two tori's back faces from coarse copies: the layer differs from the
/// full meshes' (so the copies are what was drawn), but lies within 2 cm of it almost everywhere,
/// the mirrored torus's too (culled the other way, the layer
/// would lie 0.2–0.5 m off there, half the pixels); and with both tori upright, the converged
/// AO's error against the ray tracer is the full layer's at two radii.
#[test]
fn meshes_of_many_triangles_draw_their_back_faces_from_coarse_copies() {
    for (mirrored, radius) in [(true, 0.75), (false, 0.75), (false, 2.0)] {
        let scene = fine_tori_on_floor(mirrored);
        let ao = DynamicAo::default().with_radius(radius);
        let frames = converged_frames(&ao);
        let mut gpu = Gpu::new(&scene, ao);
        assert_eq!(large_meshes(&mut gpu).len(), 2);
        let coarse = gpu.frame(frames);
        gpu.set_ao(|ao| ao.coarse_back_faces = false);
        let full = gpu.frame(frames);

        let d = layer_difference(&coarse, &full, 0.02);
        println!(
            "mirrored {mirrored}, R = {radius}: back faces in both layers {}, in one only {}, \
             within 2 cm {}, moved {}",
            d.both, d.only_one, d.near, d.moved
        );
        d.assert_close(2000);
        assert!(
            d.moved * 2 > d.both,
            "the coarse copies were not drawn: {}",
            d.moved
        );
        if mirrored {
            continue;
        }
        let truth = coarse.ground_truth(&scene.bvh(), radius);
        let mask = coarse.geometry_mask();
        let error = |f: &Frame| rmse(&f.visibility, &truth, Some(&mask));
        let (coarse_error, full_error) = (error(&coarse), error(&full));
        println!("R = {radius}: RMSE coarse {coarse_error:.4}, full {full_error:.4}");
        assert!(
            coarse_error <= full_error * 1.02 + 0.0005,
            "coarse back faces {coarse_error} against {full_error}"
        );
    }
}

/// A mesh changed in place keeps its handle: its coarse copy is made again, so the layer follows
/// the new shape (a stale copy would leave the old torus's back faces where there are none).
#[test]
fn a_coarse_copy_follows_its_mesh_when_the_asset_changes() {
    let scene = fine_tori_on_floor(false);
    let mut gpu = Gpu::new(&scene, DynamicAo::default());
    gpu.frame(4);
    let thinner = Torus::new(0.3, 0.4)
        .mesh()
        .minor_resolution(128)
        .major_resolution(256)
        .build();
    for handle in large_meshes(&mut gpu) {
        gpu.app
            .world_mut()
            .resource_mut::<Assets<Mesh>>()
            .insert(handle.id(), thinner.clone())
            .unwrap();
    }
    let coarse = gpu.frame(4);
    gpu.set_ao(|ao| ao.coarse_back_faces = false);
    let full = gpu.frame(4);
    let d = layer_difference(&coarse, &full, 0.02);
    println!(
        "after the change: both {}, one only {}, within 2 cm {}",
        d.both, d.only_one, d.near
    );
    d.assert_close(1000);
}

//! `--technique voxels`: placing the voxel volume from what the camera sees.

use std::sync::{Arc, Mutex};

use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy_dynamic_ao::geometry::bvh::Bvh;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::nd_buffer::NdTexel;
use bevy_dynamic_ao::reference::posed::{descendants, posed_triangles_of};

use crate::options::FarTerm;
use crate::{Capture, Stage, capture_view, common, far_terms};

/// Frames rendered before the view's surfaces are read to place the voxel volume.
const FRAMES_BEFORE_PLACING: u32 = 3;

/// `--technique voxels`: one volume over what occludes the surfaces the camera sees within the
/// radius (`far_terms::occluder_bounds`, traced on the CPU against the posed scene), so its
/// cells are as fine as the occlusion allows; its rays reach as far as the radius. The view's
/// surfaces come from the front layer of the ND-buffer after a few frames. Where nothing
/// occludes them, the volume covers the whole scene.
pub fn place_volume(world: &mut World) {
    let capture = world.resource::<Capture>();
    let (Stage::Rendering { .. }, Some(FarTerm::Voxels), None, Some(root), Some(readback)) = (
        capture.stage,
        capture.options.far,
        capture.volume,
        capture.root,
        capture.readback.clone(),
    ) else {
        return;
    };
    let Some(placing) = capture.placing.clone() else {
        if capture.frames >= capture.stage_start + FRAMES_BEFORE_PLACING {
            let front: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
            let store = front.clone();
            world
                .spawn(Readback::texture(readback.front.clone()))
                .observe(move |done: On<ReadbackComplete>, mut commands: Commands| {
                    *store.lock().unwrap() = Some(done.data.clone());
                    commands.entity(done.entity).despawn();
                });
            world.resource_mut::<Capture>().placing = Some(front);
        }
        return;
    };
    let Some(bytes) = placing.lock().unwrap().take() else {
        return;
    };
    let (width, height) = (capture.options.width, capture.options.height);
    let radius = capture.options.radius;
    let falloff = capture.options.voxel_falloff;
    let texels: Vec<NdTexel> = common::unpad_f32(&bytes, width as usize, height as usize, 4)
        .chunks_exact(4)
        .map(|c| NdTexel::from_rgba([c[0], c[1], c[2], c[3]]))
        .collect();
    let below = descendants(world, root);
    let scene = posed_triangles_of(world, |e| below.contains(&e));
    let (lo, hi) = scene.bounds();
    if !lo.is_finite() || !hi.is_finite() {
        world.resource_mut::<Capture>().failure = Some("the scene has no triangles".into());
        return;
    }
    let view = capture_view(world);
    let bvh = Bvh::new(scene.triangles);
    let region = view
        .and_then(|view| far_terms::occluder_bounds(&bvh, &texels, width, height, &view, radius))
        .unwrap_or((lo, hi));
    let meshes: Vec<Entity> = below
        .iter()
        .copied()
        .filter(|e| world.get::<Mesh3d>(*e).is_some())
        .collect();
    let mut commands = world.commands();
    let volume = FarTerm::Voxels.attach(
        &mut commands,
        &meshes,
        region,
        far_terms::VOXEL_MARGIN * radius,
    );
    world.flush();
    if let Some(volume) = volume
        && let Some(mut settings) = world.get_mut::<VoxelAoVolume>(volume)
    {
        settings.falloff = falloff;
    }
    let mut capture = world.resource_mut::<Capture>();
    capture.volume = volume;
    // The frames to render are counted once the volume exists (`drive`).
    capture.stage = Stage::Rendering { until: None };
}

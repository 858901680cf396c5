//! Voxel volumes: the GPU grid against a CPU triangle–cell voxelization, the GPU AO against the
//! CPU evaluation of the same rays on the same grid, occluders the depth buffer misses against
//! ground truth, stability under a moving camera, and bad volumes.

use std::sync::{Arc, Mutex};

use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::storage::ShaderBuffer;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::voxels::VoxelGrid;
use bevy_dynamic_ao::voxels::{VoxelGridInfo, VoxelGridReadback};

use crate::harness::{Gpu, plain_ao};

mod against_cpu;
mod against_truth;
mod bad_volumes;
mod grid;

/// Voxel volumes alone, no image-space term.
fn voxels_only() -> DynamicAo {
    DynamicAo {
        technique: AoTechnique::Off,
        spheres: false,
        fields: false,
        ..plain_ao()
    }
}

fn spawn_volume(gpu: &mut Gpu, transform: Transform, volume: VoxelAoVolume) -> Entity {
    gpu.app.world_mut().spawn((transform, volume)).id()
}

/// Every volume's grid as the GPU built it on the last frame, in entity order.
fn read_grids(gpu: &mut Gpu, volumes: &[Entity]) -> Vec<(VoxelGridInfo, VoxelGrid)> {
    gpu.update(1);
    let infos: Vec<VoxelGridInfo> = volumes
        .iter()
        .map(|&v| {
            *gpu.app
                .world()
                .get::<VoxelGridInfo>(v)
                .expect("the volume is in use")
        })
        .collect();
    // Surface bits of every grid, then interior bits.
    let words: u32 = 2 * infos
        .iter()
        .map(|i| i.offset + i.words())
        .max()
        .unwrap_or(1);
    let world = gpu.app.world_mut();
    let buffer = world
        .resource_mut::<Assets<ShaderBuffer>>()
        .add(ShaderBuffer::with_size(
            words as usize * 4,
            RenderAssetUsages::RENDER_WORLD,
        ));
    world.insert_resource(VoxelGridReadback(buffer.clone()));
    // The copy needs the buffer on the GPU first.
    gpu.update(2);
    let data: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
    let slot = data.clone();
    let reader = gpu
        .app
        .world_mut()
        .spawn(Readback::buffer(buffer))
        .observe(move |done: On<ReadbackComplete>| {
            slot.lock()
                .unwrap()
                .get_or_insert_with(|| done.data.clone());
        })
        .id();
    for _ in 0..60 {
        gpu.update(1);
        if data.lock().unwrap().is_some() {
            break;
        }
    }
    gpu.app.world_mut().despawn(reader);
    gpu.app.world_mut().remove_resource::<VoxelGridReadback>();
    let bytes = data
        .lock()
        .unwrap()
        .take()
        .expect("the grid read-back completed");
    let all: Vec<u32> = bytes
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    infos
        .into_iter()
        .map(|info| {
            let (start, solid) = (info.offset as usize, info.solid_offset as usize);
            let count = info.words() as usize;
            let grid = VoxelGrid {
                resolution: info.resolution,
                grid_from_world: info.grid_from_world,
                words: all[start..start + count].to_vec(),
                solid: all[solid..solid + count].to_vec(),
            };
            (info, grid)
        })
        .collect()
}

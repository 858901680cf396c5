// Ambient occlusion sampled in the voxel grids (Reinbothe, Boubekeur & Alexa 2009, §6, eq. 2
// and 4), one value per pixel of a half-resolution AO map. Each pixel traces `rays` rays over its
// hemisphere (a cone of `spread`), jittered by a hash of its world-space position so the pattern
// sticks to surfaces when the camera moves; every ray tests `steps` evenly spaced points up to
// d_max and the first occupied cell counts with the Wendland weight of its distance (eq. 3) and
// the cosine to the normal (or fully, with `VoxelFalloff::None`). The sum is normalized by the sum of the cosines, so a surface
// enclosed at distance 0 reads 1. Where volumes overlap, the largest occlusion wins.
// `reference::voxels::voxel_occlusion` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position}
#import bevy_dynamic_ao::sampling::pcg_hash
#import bevy_dynamic_ao::voxel_grid::{
    VoxelParams, VoxelVolume, cell_hash, cell_index, ray_direction, tangent_frame, to_grid, unit_float, wendland,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var depth_texture: texture_depth_2d;
@group(0) @binding(2) var normal_texture: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> volumes: array<VoxelVolume>;
@group(0) @binding(4) var<storage, read> grid: array<u32>;
@group(0) @binding(5) var output: texture_storage_2d<r32float, write>;
@group(0) @binding(6) var<uniform> params: VoxelParams;

fn occupied(volume: VoxelVolume, p: vec3<f32>) -> bool {
    let i = cell_index(volume, vec3<i32>(floor(to_grid(volume, p))));
    if i < 0 {
        return false;
    }
    let word = volume.offset + u32(i) / 32u;
    return ((grid[word] | grid[params.solid_offset + word]) & (1u << (u32(i) % 32u))) != 0u;
}

fn volume_occlusion(volume: VoxelVolume, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let g = to_grid(volume, p);
    let size = vec3<f32>(f32(volume.resolution));
    if any(g < -volume.reach) || any(g > size + volume.reach) {
        return 0.0;
    }
    let h = cell_hash(p, volume.noise_cell);
    let j1 = unit_float(pcg_hash(h));
    let j2 = unit_float(pcg_hash(h + 1u));
    let j3 = unit_float(pcg_hash(h + 2u));
    let frame = tangent_frame(n);
    let origin = p + n * volume.bias;
    var occlusion = 0.0;
    var cosines = 0.0;
    for (var i = 0u; i < volume.rays; i++) {
        let local = ray_direction(i, volume.rays, volume.cos_spread, j1, j2);
        let direction = frame * local;
        cosines += local.z;
        for (var s = 0u; s < volume.steps; s++) {
            let t = volume.d_max * (f32(s) + j3) / f32(volume.steps);
            if occupied(volume, origin + direction * t) {
                let weight = select(wendland(t, volume.d_max), 1.0, (volume.flags & 2u) != 0u);
                occlusion += weight * local.z;
                break;
            }
        }
    }
    return select(0.0, occlusion / cosines, cosines > 0.0);
}

@compute @workgroup_size(8, 8, 1)
fn voxel_ao(@builtin(global_invocation_id) id: vec3<u32>) {
    let low_dims = textureDimensions(output);
    if any(id.xy >= low_dims) {
        return;
    }
    let dims = vec2<i32>(textureDimensions(depth_texture));
    // Low-resolution texel l stands for full-resolution pixel 2l, as the upsampling expects.
    let x = min(vec2<i32>(id.xy) * 2, dims - 1);
    let depth = textureLoad(depth_texture, x, 0);
    var occlusion = 0.0;
    if depth > 0.0 {
        let p = world_position(view, x, vec2<f32>(dims), depth);
        let n = decode_normal(textureLoad(normal_texture, x, 0).xyz);
        for (var v = 0u; v < params.volumes; v++) {
            let volume = volumes[v];
            if volume.resolution > 0u {
                occlusion = max(occlusion, volume_occlusion(volume, p, n));
            }
        }
    }
    textureStore(output, vec2<i32>(id.xy), vec4<f32>(occlusion));
}

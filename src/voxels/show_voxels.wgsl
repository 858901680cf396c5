// Debug view of the occupied voxels: each pixel walks its camera ray through the grid of every
// volume that asks to be shown (Amanatides & Woo 1987), up to the visible surface, and paints
// the first occupied cell it meets, shaded by the face it entered through.

#import bevy_core_pipeline::fullscreen_vertex_shader::FullscreenVertexOutput
#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::world_position
#import bevy_dynamic_ao::uniform::{DynamicAoUniform, seen_by_view}
#import bevy_dynamic_ao::voxel_grid::{VoxelParams, VoxelVolume, cell_index, to_grid}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var depth_texture: texture_depth_2d;
@group(0) @binding(2) var<storage, read> volumes: array<VoxelVolume>;
@group(0) @binding(3) var<storage, read> grid: array<u32>;
@group(0) @binding(4) var<uniform> params: VoxelParams;
@group(0) @binding(5) var<uniform> settings: DynamicAoUniform;

fn is_occupied(volume: VoxelVolume, cell: vec3<i32>) -> bool {
    let i = cell_index(volume, cell);
    if i < 0 {
        return false;
    }
    let word = volume.offset + u32(i) / 32u;
    return ((grid[word] | grid[params.solid_offset + word]) & (1u << (u32(i) % 32u))) != 0u;
}

// Where along the segment start + s·d, s ∈ [0, 1], the first occupied cell begins (> 1: none),
// and the axis of the face it is entered through (3 when the segment starts inside it).
fn first_occupied(volume: VoxelVolume, start: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    let n = f32(volume.resolution);
    // Clip the segment to the grid box.
    let inv = 1.0 / d;
    let t0 = (vec3<f32>(0.0) - start) * inv;
    let t1 = (vec3<f32>(n) - start) * inv;
    let s_in = max(0.0, max(max(min(t0.x, t1.x), min(t0.y, t1.y)), min(t0.z, t1.z)));
    let s_out = min(1.0, min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z)));
    if s_in > s_out {
        return vec2<f32>(2.0, 0.0);
    }
    let p = start + d * s_in;
    var cell = clamp(vec3<i32>(floor(p)), vec3<i32>(0), vec3<i32>(i32(volume.resolution) - 1));
    let step = vec3<i32>(select(vec3<f32>(-1.0), vec3<f32>(1.0), d >= vec3<f32>(0.0)));
    let delta = abs(inv);
    let next = vec3<f32>(cell) + select(vec3<f32>(0.0), vec3<f32>(1.0), d >= vec3<f32>(0.0));
    var t_max = select((next - start) * inv, vec3<f32>(1e30), d == vec3<f32>(0.0));
    var s = s_in;
    var axis = 3u;
    for (var i = 0u; i < 3u * volume.resolution + 3u; i++) {
        if is_occupied(volume, cell) {
            return vec2<f32>(s, f32(axis));
        }
        if t_max.x <= t_max.y && t_max.x <= t_max.z {
            axis = 0u;
        } else if t_max.y <= t_max.z {
            axis = 1u;
        } else {
            axis = 2u;
        }
        s = t_max[axis];
        if s > s_out {
            break;
        }
        cell[axis] += step[axis];
        t_max[axis] += delta[axis];
    }
    return vec2<f32>(2.0, 0.0);
}

@fragment
fn fragment(in: FullscreenVertexOutput) -> @location(0) vec4<f32> {
    // The pass covers the viewport; the front layer starts at the viewport's first pixel.
    let pixel = vec2<i32>(in.position.xy - view.viewport.xy);
    let size = vec2<f32>(textureDimensions(depth_texture));
    let depth = textureLoad(depth_texture, pixel, 0);
    let near = world_position(view, pixel, size, 1.0);
    // Reverse Z: 0 is infinitely far, so an empty pixel walks far enough to leave every grid.
    let far = world_position(view, pixel, size, max(depth, 1e-5));
    var best = vec2<f32>(2.0, 0.0);
    for (var v = 0u; v < params.volumes; v++) {
        let volume = volumes[v];
        if (volume.flags & 1u) == 0u || volume.resolution == 0u
            || !seen_by_view(settings, volume.layers) {
            continue;
        }
        let start = to_grid(volume, near);
        let hit = first_occupied(volume, start, to_grid(volume, far) - start);
        if hit.x < best.x {
            best = hit;
        }
    }
    if best.x > 1.0 {
        discard;
    }
    let shade = array<f32, 4>(0.8, 1.0, 0.6, 0.9)[u32(best.y)];
    return vec4<f32>(vec3<f32>(1.0, 0.55, 0.1) * shade, 0.75);
}

// Ambient occlusion sampled in the voxel grids (Reinbothe, Boubekeur & Alexa 2009, §6, eq. 2
// and 4), one value per pixel of a half-resolution AO map. Each pixel traces `rays` rays over its
// hemisphere (a cone of `spread`), jittered by a hash of its world-space position so the pattern
// sticks to surfaces when the camera moves (and turned every frame under temporal accumulation,
// whose pass follows this one, where it traces `accumulated_rays`). A ray is blocked once it has
// crossed most of a cell's width of occupied cells closer than the reach (the camera's radius R
// unless the volume sets d_max): by default found by walking every cell the ray crosses (empty
// bricks of 8³ cells in one step), or, as the paper does, at the first of `steps` evenly spaced
// tests that lands in one. A blocked ray counts with the cosine to the normal, fully (what
// ground truth measures) or with Wendland's weight of its distance (eq. 3). The sum is
// normalized by the sum of the cosines, so a surface enclosed at distance 0 reads 1. Counted
// once: under `FarFieldBlend::CountOnce` hits closer than the near field's reach go to the first
// channel unless the ND-buffer holds them (the near field counts those), farther ones to the
// second, as a share of the rays the near ones leave open. Where volumes overlap, the largest
// occlusion wins, per channel. `reference::voxels::volume_occlusion` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position, nd_buffer_holds}
#import bevy_dynamic_ao::sampling::{frame_offset, frame_step, pcg_hash}
#import bevy_dynamic_ao::uniform::{DynamicAoUniform, seen_by_view}
#import bevy_dynamic_ao::math::{tangent_frame, wendland}
#import bevy_dynamic_ao::voxel_grid::{
    BRICK_CELLS, VoxelParams, VoxelVolume, bricks_per_axis, cell_hash, cell_index, ray_direction,
    to_grid, to_grid_direction, unit_float,
}

// Cells a ray travels through occupied cells before it is blocked: `VoxelAoVolume::HIT_DEPTH`.
const HIT_DEPTH: f32 = 0.9;

// Bricks the reach must span for rays to cross empty bricks in one step (`first_hit_cells`).
const MIN_BRICKS_PER_REACH: f32 = 4.0;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var depth_texture: texture_depth_2d;
@group(0) @binding(2) var normal_texture: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> volumes: array<VoxelVolume>;
@group(0) @binding(4) var<storage, read> grid: array<u32>;
@group(0) @binding(5) var output: texture_storage_2d<rg32float, write>;
@group(0) @binding(6) var<uniform> params: VoxelParams;
@group(0) @binding(7) var<uniform> settings: DynamicAoUniform;
@group(0) @binding(8) var back_depth_texture: texture_depth_2d;

fn occupied_cell(volume: VoxelVolume, c: vec3<i32>) -> bool {
    let i = cell_index(volume, c);
    if i < 0 {
        return false;
    }
    let word = volume.offset + u32(i) / 32u;
    return ((grid[word] | grid[params.solid_offset + word]) & (1u << (u32(i) % 32u))) != 0u;
}

// Whether brick `b`, inside the grid, holds an occupied cell (`mark_bricks` in `voxelize.wgsl`).
fn occupied_brick(volume: VoxelVolume, b: vec3<i32>) -> bool {
    let bricks = i32(bricks_per_axis(volume));
    let i = u32(b.x + bricks * (b.y + bricks * b.z));
    return (grid[params.brick_offset + volume.brick_offset + i / 32u] & (1u << (i % 32u))) != 0u;
}

fn occupied(volume: VoxelVolume, p: vec3<f32>) -> bool {
    return occupied_cell(volume, vec3<i32>(floor(to_grid(volume, p))));
}

// 1 / v per component, with ±1e30 for components that are 0.
fn safe_inverse(v: vec3<f32>) -> vec3<f32> {
    let tiny = abs(v) < vec3<f32>(1e-20);
    let s = select(sign(v), vec3<f32>(1.0), v == vec3<f32>(0.0));
    return select(1.0 / v, s * 1e30, tiny);
}

// World distance along the ray to where it has travelled HIT_DEPTH cells through occupied cells
// in a row, walking every cell it crosses (Amanatides & Woo 1987); −1 when that lies beyond
// `reach`. A ray that only grazes the rim conservative voxelization adds to every occluder is
// not blocked. Where `bricked`, a brick with no occupied cell is crossed in one step, to the
// first cell past it: the cells the walk visits are those of the walk without bricks, less the
// empty ones it skips, so the hits are the same (`reference::voxels` walks every cell).
fn first_hit_cells(volume: VoxelVolume, origin: vec3<f32>, direction: vec3<f32>, reach: f32, bricked: bool) -> f32 {
    let g0 = to_grid(volume, origin);
    let gd = to_grid_direction(volume, direction);
    let inverse = safe_inverse(gd);
    let n = f32(volume.resolution);
    let t0 = -g0 * inverse;
    let t1 = (vec3<f32>(n) - g0) * inverse;
    let near = min(t0, t1);
    let far = max(t0, t1);
    var t = max(max(max(near.x, near.y), near.z), 0.0);
    let end = min(min(min(far.x, far.y), far.z), reach);
    if t > end {
        return -1.0;
    }
    let last = vec3<i32>(i32(volume.resolution) - 1);
    var cell = clamp(vec3<i32>(floor(g0 + gd * t)), vec3<i32>(0), last);
    let step = vec3<i32>(sign(gd));
    let ahead = gd > vec3<f32>(0.0);
    let boundary = vec3<f32>(cell) + select(vec3<f32>(0.0), vec3<f32>(1.0), ahead);
    var next = (boundary - g0) * inverse;
    let delta = abs(inverse);
    let grid_per_metre = length(gd);
    var inside = 0.0;
    let brick_cells = i32(BRICK_CELLS);
    var steps = 0u;
    // One brick a turn, `cell` inside the grid; without bricks, the grid is one brick.
    while steps < 3u * volume.resolution + 3u {
        let b = cell / brick_cells;
        let lo = select(vec3<i32>(0), b * brick_cells, bricked);
        let hi = select(last, min(lo + brick_cells, last + 1) - 1, bricked);
        if bricked && !occupied_brick(volume, b) {
            // Where the ray leaves the brick, and across which face (x before y before z on a
            // tie, as the walk steps). An axis the ray does not move along (`inverse` +1e30) is
            // never the one: its far face is ahead.
            let faces = select(lo, hi + 1, gd >= vec3<f32>(0.0));
            let exits = (vec3<f32>(faces) - g0) * inverse;
            let leave = min(min(exits.x, exits.y), exits.z);
            if leave > end {
                return -1.0;
            }
            let x_first = exits.x <= exits.y && exits.x <= exits.z;
            let y_first = !x_first && exits.y <= exits.z;
            let across = vec3<bool>(x_first, y_first, !x_first && !y_first);
            let past = select(lo - 1, hi + 1, ahead);
            cell = select(clamp(vec3<i32>(floor(g0 + gd * leave)), lo, hi), past, across);
            if any(cell < vec3<i32>(0)) || any(cell > last) {
                return -1.0;
            }
            t = leave;
            inside = 0.0;
            next = (vec3<f32>(cell) + select(vec3<f32>(0.0), vec3<f32>(1.0), ahead) - g0) * inverse;
            steps++;
            continue;
        }
        // Cell by cell until the ray leaves the brick; each step moves along one axis, so only
        // that axis can have left it.
        var left = false;
        while !left && steps < 3u * volume.resolution + 3u {
            steps++;
            let exit = min(min(next.x, next.y), min(next.z, end));
            if occupied_cell(volume, cell) {
                let through = (exit - t) * grid_per_metre;
                if inside + through >= HIT_DEPTH {
                    return t + (HIT_DEPTH - inside) / grid_per_metre;
                }
                inside += through;
            } else {
                inside = 0.0;
            }
            if next.x <= next.y && next.x <= next.z {
                t = next.x;
                next.x += delta.x;
                cell.x += step.x;
                left = cell.x < lo.x || cell.x > hi.x;
            } else if next.y <= next.z {
                t = next.y;
                next.y += delta.y;
                cell.y += step.y;
                left = cell.y < lo.y || cell.y > hi.y;
            } else {
                t = next.z;
                next.z += delta.z;
                cell.z += step.z;
                left = cell.z < lo.z || cell.z > hi.z;
            }
            if t > end {
                return -1.0;
            }
        }
        if any(cell < vec3<i32>(0)) || any(cell > last) {
            return -1.0;
        }
    }
    return -1.0;
}

// World distance of the first of `steps` evenly spaced tests (offset by `jitter`) that lands in
// an occupied cell, the paper's march; −1 when none does.
fn first_hit_steps(volume: VoxelVolume, origin: vec3<f32>, direction: vec3<f32>, reach: f32, jitter: f32) -> f32 {
    for (var s = 0u; s < volume.steps; s++) {
        let t = reach * (f32(s) + jitter) / f32(volume.steps);
        if occupied(volume, origin + direction * t) {
            return t;
        }
    }
    return -1.0;
}

// The occlusion of one volume: x, by occluders within the near field's reach that the ND-buffer
// does not hold; y, by the rest.
fn volume_occlusion(volume: VoxelVolume, p: vec3<f32>, n: vec3<f32>) -> vec2<f32> {
    let reach = select(settings.radius, volume.d_max, volume.d_max > 0.0);
    let g = to_grid(volume, p);
    let size = vec3<f32>(f32(volume.resolution));
    let margin = (reach + volume.bias) / volume.cell;
    if any(g < -margin) || any(g > size + margin) {
        return vec2<f32>(0.0);
    }
    // Under temporal accumulation the jitter moves every frame (frame 0, without, keeps it).
    let h = cell_hash(p, volume.noise_cell);
    let shift = frame_offset(settings.frame_index);
    let j1 = fract(unit_float(pcg_hash(h)) + shift.x);
    let j2 = fract(unit_float(pcg_hash(h + 1u)) + shift.y);
    let j3 = fract(unit_float(pcg_hash(h + 2u)) + frame_step(settings.frame_index));
    let frame = tangent_frame(n);
    let origin = p + n * volume.bias;
    // Bricks pay where the reach spans several: a walk through few, all of them occupied near
    // the surface, only adds their bookkeeping to every cell (on lavapipe the room of
    // `gpu_passes` at 64³ and 128³, R = 0.75 m, took 1.3× as long with bricks; at 256³, R = 2 m,
    // 0.6×, and the Fox on a floor 0.3×).
    let brick_size = f32(BRICK_CELLS) * (volume.cell.x + volume.cell.y + volume.cell.z) / 3.0;
    let bricked = reach >= MIN_BRICKS_PER_REACH * brick_size;
    var occlusion = vec2<f32>(0.0);
    var cosines = 0.0;
    // Cosines of the rays blocked within the near field's reach, held or not.
    var near_blocked = 0.0;
    // A view that accumulates (frame index 0 where nothing does) averages each frame's turned
    // pattern into its history, and traces the smaller budget.
    let rays = select(volume.rays, volume.accumulated_rays, settings.frame_index != 0u);
    for (var i = 0u; i < rays; i++) {
        let local = ray_direction(i, rays, volume.cos_spread, j1, j2);
        let direction = frame * local;
        cosines += local.z;
        var t: f32;
        if volume.steps == 0u {
            t = first_hit_cells(volume, origin, direction, reach, bricked);
        } else {
            t = first_hit_steps(volume, origin, direction, reach, j3);
        }
        if t < 0.0 {
            continue;
        }
        let weight = select(wendland(t, reach), 1.0, (volume.flags & 2u) != 0u) * local.z;
        if t < settings.near_field_radius {
            // The near field counts this occluder if the ND-buffer holds it.
            occlusion.x += weight * (1.0 - nd_buffer_holds(view, depth_texture,
                back_depth_texture, settings.seen_back_layer != 0u, origin + direction * t,
                volume.bias));
            near_blocked += local.z;
        } else {
            occlusion.y += weight;
        }
    }
    // The far part as a share of the rays the near part leaves open, so that the two join as
    // 1 − (1 − x)(1 − y).
    return vec2<f32>(
        select(0.0, occlusion.x / cosines, cosines > 0.0),
        select(0.0, occlusion.y / (cosines - near_blocked), cosines - near_blocked > 0.0),
    );
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
    var occlusion = vec2<f32>(0.0);
    if depth > 0.0 {
        let p = world_position(view, x, vec2<f32>(dims), depth);
        let n = decode_normal(textureLoad(normal_texture, x, 0).xyz);
        for (var v = 0u; v < params.volumes; v++) {
            let volume = volumes[v];
            if volume.resolution > 0u && seen_by_view(settings, volume.layers) {
                occlusion = max(occlusion, volume_occlusion(volume, p, n));
            }
        }
    }
    textureStore(output, vec2<i32>(id.xy), vec4<f32>(occlusion, 0.0, 0.0));
}

// Temporal accumulation of the image-space occlusion (and, with `PAIR`, of the voxel term's two
// channels): this frame's value joins the pixel's history, found where the surface was last
// frame through Bevy's motion vectors. The history is read bilinearly from the four texels around
// that place, each kept only where its depth and normal match this surface (a disocclusion keeps
// none), and clamped around this frame's values on the same plane nearby, so a
// change the motion vectors do not show (a shadow whose occluder moved away) leaves no trail.
// The image-space history is clamped on every other frame only (`temporal/mod.rs`, "Ghosting"),
// by the pipeline compiled with CLAMP (PAIR's always is); the frames between run one without the
// clamp's tile and window (`temporal/pipeline.rs`, `TemporalVariant::unclamped`).
// Under the ray march's checkerboard, a texel the march skipped this frame keeps its history
// without a new sample (`temporal/mod.rs`, "Checkerboard").

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, linear_depth}
#import bevy_dynamic_ao::history::{HistoryTexel, pack_history, unpack_history}

struct TemporalUniform {
    // 1: every history is dropped this frame.
    reset: u32,
    // Most frames a history averages.
    max_frames: f32,
    // Full-resolution pixels per texel of the accumulated texture, along each axis (1 or 2).
    scale: u32,
    // Under the ray march's checkerboard, the view's place in its sample sequence: the march
    // wrote texel t this frame where t.x and t.y + frame agree in parity (`march.wgsl`). 0 where
    // every texel was written.
    frame: u32,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> temporal: TemporalUniform;
// This frame's occlusion, as the technique wrote it. Under the checkerboard the texels the march
// skipped hold last frame's values there: the clamp's window reads them as this frame's (on a
// still view they are one frame old and as noisy), and a skipped texel's own is already in its
// history, so it is not added again.
@group(0) @binding(2) var current: texture_2d<f32>;
@group(0) @binding(3) var front_depth: texture_depth_2d;
@group(0) @binding(4) var front_normal: texture_2d<f32>;
// Bevy's motion vectors: this frame's UV minus last frame's.
@group(0) @binding(5) var motion_vectors: texture_2d<f32>;
// `HistoryTexel`s (occlusion as f32 bits, or both channels as 2 × 16-bit unorm with `PAIR`).
@group(0) @binding(6) var history_in: texture_2d<u32>;
@group(0) @binding(7) var history_out: texture_storage_2d<rgba32uint, write>;
// The accumulated occlusion the filter and compose read.
#ifdef PAIR
@group(0) @binding(8) var occlusion: texture_storage_2d<rg32float, write>;
#else
@group(0) @binding(8) var occlusion: texture_storage_2d<r32float, write>;
#endif

// A history texel counts where its linear depth is within this share of the surface's...
const DEPTH_TOLERANCE: f32 = 0.05;
// ... and the cosine between its normal and the surface's is at least this.
const NORMAL_AGREEMENT: f32 = 0.9;
// The image-space history is clamped to the mean of this frame's values on the texel's plane
// around it, give or take GAMMA standard errors of that mean plus CLAMP_MARGIN (for the shading's
// own slope across the window). The spread of single values would not do: from 2 rays a pixel
// reads 0, ½ or 1, so the values' range spans most of [0, 1] and a shadow whose occluder has
// moved away stays inside it (the motion benchmark's trail behind the sliding box: 95 pixels
// with the range, about 24 with this).
const GAMMA: f32 = 1.5;
const CLAMP_MARGIN: f32 = 0.05;
// A texel of the window lies on the texel's plane where its depth is within this share of the
// texel's linear depth off the plane (`plane_tolerance` carries it into reverse-Z depth).
const PLANE_TOLERANCE: f32 = 0.02;
// Texels each side of the window (5 × 5 at the accumulated texture's resolution).
const WINDOW: i32 = 2;
// A history the clamp moved by more than CUT saw a change: it counts as at most CLAMPED_FRAMES
// frames, so the new value takes over within a few frames instead of `max_frames`. A smaller
// move is the window's own noise or slope, and cutting there would keep creases noisy.
const CLAMPED_FRAMES: f32 = 4.0;
const CUT: f32 = 0.03;

// How far in reverse-Z depth a point may lie off the plane of a texel at linear depth `z` and
// reverse-Z depth `d`: PLANE_TOLERANCE of `z`, carried through the projection.
fn plane_tolerance(z: f32, d: f32) -> f32 {
    let p = view.clip_from_view;
    let farther = -z * (1.0 + PLANE_TOLERANCE);
    return abs((p[2][2] * farther + p[3][2]) / (p[2][3] * farther + p[3][3]) - d);
}

// Whether a point at linear depth `other_z` with normal `other_n` lies on the surface at `z`, `n`.
fn same_surface(other_z: f32, other_n: vec3<f32>, z: f32, n: vec3<f32>) -> bool {
    return abs(other_z - z) <= DEPTH_TOLERANCE * z && dot(other_n, n) >= NORMAL_AGREEMENT;
}

// The technique's value(s); a single channel keeps 0 in y.
fn load_value(texel: vec2<i32>) -> vec2<f32> {
#ifdef PAIR
    return textureLoad(current, texel, 0).rg;
#else
    return vec2<f32>(textureLoad(current, texel, 0).r, 0.0);
#endif
}

// A workgroup's texels along x and y (`@workgroup_size`), and along each side of its tile: its
// texels and the window around them.
const GROUP_X: i32 = 64;
const GROUP_Y: i32 = 1;
const TILE_X: i32 = GROUP_X + 2 * WINDOW;
const TILE_Y: i32 = GROUP_Y + 2 * WINDOW;
// Each texel of a workgroup's tile, read once: the 5 × 5 windows of its 64 texels overlap, and
// reading depth and value for each of the 25 taps was most of the pass. Two half floats per
// texel in one u32, because on lavapipe a read from workgroup memory costs about what a texture
// read does, per channel: this frame's value and its reverse-Z depth as stored (0 where no
// surface is), or both channels with PAIR. Reverse-Z depth is affine across the screen on a
// plane (linear depth is not, under perspective), and keeping it as stored spares the tile an
// unprojection per texel. The window tells surfaces apart by depth against the texel's plane,
// without normals: they were two more channels and a decoding per tap, and the plane test has a
// converged error no higher than theirs (BENCHMARKS.md, "The clamp window tests depth against a
// plane").
var<workgroup> tile: array<u32, TILE_X * TILE_Y>;

// Tile texel `i`, unpacked. Half floats keep 11 bits: a depth off by 0.05% against a plane
// tolerance of 2%.
fn tile_at(i: i32) -> vec2<f32> {
    return unpack2x16float(tile[i]);
}

// Fills the tile of the workgroup whose first texel is `corner`: tile texel t holds texel
// `corner - WINDOW + t`, clamped to the texture as the window's reads were.
fn load_tile(corner: vec2<i32>, lane: i32, dims: vec2<i32>, full: vec2<i32>) {
    for (var i = lane; i < TILE_X * TILE_Y; i += GROUP_X * GROUP_Y) {
        let q = clamp(corner - WINDOW + vec2<i32>(i % TILE_X, i / TILE_X), vec2<i32>(0), dims - 1);
#ifdef PAIR
        tile[i] = pack2x16float(load_value(q));
#else
        let q_pixel = min(q * i32(temporal.scale), full - 1);
        tile[i] = pack2x16float(vec2<f32>(load_value(q).x, textureLoad(front_depth, q_pixel, 0)));
#endif
    }
}

// The tile's index of the texel `offset` away from the workgroup's texel `local`.
fn tile_index(local: vec2<i32>, offset: vec2<i32>) -> i32 {
    let t = local + WINDOW + offset;
    return t.x + t.y * TILE_X;
}

fn pack_value(value: vec2<f32>) -> u32 {
#ifdef PAIR
    return pack2x16unorm(value);
#else
    return bitcast<u32>(value.x);
#endif
}

fn unpack_value(packed: u32) -> vec2<f32> {
#ifdef PAIR
    return unpack2x16unorm(packed);
#else
    return vec2<f32>(bitcast<f32>(packed), 0.0);
#endif
}

fn store(texel: vec2<i32>, value: vec2<f32>, depth: f32, frames: f32, normal: vec3<f32>) {
    let history = HistoryTexel(pack_value(value), depth, frames, normal);
    textureStore(history_out, texel, pack_history(history));
    textureStore(occlusion, texel, vec4<f32>(value, 0.0, 0.0));
}

// The voxel term clamps into the range of this frame's values in the 3 × 3 texels around it,
// widened by CLAMP_MARGIN, and cuts at any move: the window mean's box biased its converged
// value at the voxel grid's steps (RMSE against 64 rays 0.010 with the range, 0.033 with the
// mean, on the test's room corner).
fn range_bounds(local: vec2<i32>, value: vec2<f32>) -> array<vec2<f32>, 2> {
    var lo = value;
    var hi = value;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let v = tile_at(tile_index(local, vec2<i32>(dx, dy)));
            lo = min(lo, v);
            hi = max(hi, v);
        }
    }
    return array<vec2<f32>, 2>(lo - vec2<f32>(CLAMP_MARGIN), hi + vec2<f32>(CLAMP_MARGIN));
}

// The change of reverse-Z depth per texel along x and y at the workgroup's texel `local` (depth
// `d`), the plane the window's texels are held against: along each axis the smaller of the
// one-sided differences, so that a silhouette beside the texel does not tilt it.
fn depth_slope(local: vec2<i32>, d: f32) -> vec2<f32> {
    let ahead = vec2<f32>(
        tile_at(tile_index(local, vec2<i32>(1, 0))).y,
        tile_at(tile_index(local, vec2<i32>(0, 1))).y,
    ) - d;
    let behind = d - vec2<f32>(
        tile_at(tile_index(local, vec2<i32>(-1, 0))).y,
        tile_at(tile_index(local, vec2<i32>(0, -1))).y,
    );
    return select(behind, ahead, abs(ahead) < abs(behind));
}

// Mean of this frame's values on the texel's plane in the window, give or take GAMMA standard
// errors of it and CLAMP_MARGIN; `tolerance` is how far in reverse-Z depth a texel of the window
// may lie off the plane. A background texel (depth 0) lies on no plane. At a plane's edge (a
// fin's top, the rim of a panel line) the texels on the plane lie on one side of the texel, and
// their mean is not its value: there the band reaches to the mean of the pairs of texels placed
// symmetrically about it that both lie on the plane, which is its value wherever the occlusion
// varies linearly across the window. Clamped to the one-sided mean alone, a converged history
// at the edge was pulled toward the plane's inside (BENCHMARKS.md, "The clamp at a plane's
// edge"); clamped to the pairs' mean alone, fewer texels made a noisier mean.
fn mean_bounds(local: vec2<i32>, tolerance: f32) -> array<vec2<f32>, 2> {
    // The plane goes through the texel's depth as the tile holds it.
    let own = tile_at(tile_index(local, vec2<i32>(0)));
    let d = own.y;
    let slope = depth_slope(local, d);
    var sum = own.x;
    var sum_sq = own.x * own.x;
    var on_surface = 1.0;
    var pairs_sum = own.x;
    var pairs_count = 1.0;
    // Half the window (the rows above the texel, and the texels left of it on its row), each
    // with its mirror image.
    for (var dy = -WINDOW; dy <= 0; dy++) {
        for (var dx = -WINDOW; dx <= WINDOW; dx++) {
            if dy == 0 && dx >= 0 {
                break;
            }
            let offset = vec2<i32>(dx, dy);
            let a = tile_at(tile_index(local, offset));
            let b = tile_at(tile_index(local, -offset));
            let step = dot(slope, vec2<f32>(offset));
            let a_on = abs(a.y - (d + step)) <= tolerance;
            let b_on = abs(b.y - (d - step)) <= tolerance;
            let wa = select(0.0, 1.0, a_on);
            let wb = select(0.0, 1.0, b_on);
            sum += wa * a.x + wb * b.x;
            sum_sq += wa * a.x * a.x + wb * b.x * b.x;
            on_surface += wa + wb;
            let both = wa * wb;
            pairs_sum += both * (a.x + b.x);
            pairs_count += 2.0 * both;
        }
    }
    let mean = sum / on_surface;
    let pairs_mean = pairs_sum / pairs_count;
    let sigma = sqrt(max(sum_sq / on_surface - mean * mean, 0.0));
    let reach = GAMMA * sigma / sqrt(on_surface) + CLAMP_MARGIN;
    return array<vec2<f32>, 2>(
        vec2<f32>(min(mean, pairs_mean) - reach, 0.0),
        vec2<f32>(max(mean, pairs_mean) + reach, 0.0),
    );
}

// This frame's value and reverse-Z depth of texel `q`, the neighbour `offset` (within the
// window) away from the workgroup's texel `local`: from the tile where the pass filled one (half
// floats, as the clamp reads them), else from the textures. Image-space occlusion only.
fn neighbour(q: vec2<i32>, local: vec2<i32>, offset: vec2<i32>, full: vec2<i32>) -> vec2<f32> {
#ifdef CLAMP
    return tile_at(tile_index(local, offset));
#else
    let d = textureLoad(front_depth, min(q * i32(temporal.scale), full - 1), 0);
    return vec2<f32>(load_value(q).x, d);
#endif
}

// For a texel the march skipped this frame and that has no history: the mean of this frame's
// values of its four neighbours (all marched) on its surface, or `fallback` where none is.
fn neighbours_mean(
    texel: vec2<i32>,
    local: vec2<i32>,
    dims: vec2<i32>,
    full: vec2<i32>,
    z: f32,
    fallback: vec2<f32>,
) -> vec2<f32> {
    var sum = vec2<f32>(0.0);
    var count = 0.0;
    for (var i = 0; i < 4; i++) {
        let step = select(1, -1, (i & 1) == 1);
        let offset = select(vec2<i32>(0, step), vec2<i32>(step, 0), i < 2);
        let q = texel + offset;
        if any(q < vec2<i32>(0)) || any(q >= dims) {
            continue;
        }
        let v = neighbour(q, local, offset, full);
        if v.y <= 0.0 || abs(linear_depth(view, v.y) - z) > DEPTH_TOLERANCE * z {
            continue;
        }
        sum += vec2<f32>(v.x, 0.0);
        count += 1.0;
    }
    return select(fallback, sum / max(count, 1.0), count > 0.0);
}

// `dispatch::Workgroup::Row`, which GROUP_X and GROUP_Y state as well.
@compute @workgroup_size(64, 1, 1)
fn accumulate(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_id) local_id: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let dims = vec2<i32>(textureDimensions(current));
    let full = vec2<i32>(textureDimensions(front_depth));
    let texel = vec2<i32>(id.xy);
    let local = vec2<i32>(local_id.xy);
#ifdef CLAMP
    // Every lane helps fill the tile, those past the texture's edge included.
    load_tile(texel - local, i32(lane), dims, full);
    workgroupBarrier();
#endif
    if any(texel >= dims) {
        return;
    }
    let pixel = min(texel * i32(temporal.scale), full - 1);
    let uv = (vec2<f32>(pixel) + 0.5) / vec2<f32>(full);
    // The tile's depth is a half float; the history keeps the full one.
    let value = load_value(texel);
    let depth = textureLoad(front_depth, pixel, 0);
    let z = select(0.0, linear_depth(view, depth), depth > 0.0);
    let n = decode_normal(textureLoad(front_normal, pixel, 0).xyz);
    // One store at the end, whatever the path: lavapipe runs every branch under a mask, so each
    // store written in a branch costs every texel (BENCHMARKS.md, "Workgroups along rows").
    let surface = z > 0.0 && dot(n, n) != 0.0;

#ifdef PAIR
    let bounds = range_bounds(local, value);
    let cut = 0.0;
#else
#ifdef CLAMP
    let bounds = mean_bounds(local, plane_tolerance(z, depth));
#else
    let bounds = array<vec2<f32>, 2>(vec2<f32>(0.0), vec2<f32>(1.0));
#endif
    let cut = CUT;
#endif
    let lo = bounds[0];
    let hi = bounds[1];

    var history = vec2<f32>(0.0);
    var frames = 0.0;
    var weight = 0.0;
    if temporal.reset == 0u && surface {
        let motion = textureLoad(motion_vectors, pixel, 0).xy;
        // History texel t holds the surface at full-resolution pixel t × scale, so a place in
        // the last frame maps back through that scale (at half resolution, a texel's centre is
        // not its block's centre: mapping through the block would shift the history every frame).
        let previous = ((uv - motion) * vec2<f32>(full) - 0.5) / f32(temporal.scale);
        let base = vec2<i32>(floor(previous));
        let f = previous - floor(previous);
        for (var i = 0u; i < 4u; i++) {
            let corner = vec2<i32>(i32(i & 1u), i32(i >> 1u));
            let q = base + corner;
            if any(q < vec2<i32>(0)) || any(q >= dims) {
                continue;
            }
            let h = unpack_history(textureLoad(history_in, q, 0));
            if h.frames <= 0.0 || !same_surface(h.depth, h.normal, z, n) {
                continue;
            }
            let w = mix(1.0 - f.x, f.x, f32(corner.x)) * mix(1.0 - f.y, f.y, f32(corner.y));
            history += w * unpack_value(h.value);
            frames += w * h.frames;
            weight += w;
        }
    }
#ifdef PAIR
    let marched = true;
#else
    let marched =
        temporal.frame == 0u || (u32(texel.x) & 1u) == ((u32(texel.y) + temporal.frame) & 1u);
#endif
    var result = value;
    var count = 1.0;
    if !surface {
        // Background is open (a texel the checkerboard skipped may hold last frame's value).
        result = vec2<f32>(0.0);
        count = 0.0;
    } else if weight < 0.01 {
#ifndef PAIR
        if !marched {
            result = neighbours_mean(texel, local, dims, full, z, value);
            count = 0.5;
        }
#endif
    } else {
        let previous = history / weight;
        count = min(frames / weight + select(0.0, 1.0, marched), temporal.max_frames);
        let kept = clamp(previous, lo, hi);
        if any(abs(kept - previous) > vec2<f32>(cut)) {
            count = min(count, CLAMPED_FRAMES);
        }
        result = select(kept, mix(kept, value, 1.0 / count), marched);
    }
    store(texel, result, select(0.0, z, surface), count, select(vec3<f32>(0.0), n, surface));
}

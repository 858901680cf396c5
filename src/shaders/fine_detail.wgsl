// The fine-detail term (`AoBlur::detail_reach`), joined with the ray march's occlusion: by the
// ray march itself under temporal accumulation (one side a frame), else by the blur's Y pass
// (all four sides). `reference::fine_detail::fine_detail_sides` is the CPU twin.

#define_import_path bevy_dynamic_ao::fine_detail

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{position_in_view, position_at_linear_depth, linear_depth, pixel_world_size}

// Occlusion of the surfaces within `reach` pixels of `pixel` along its row and column in
// `depth` (the front layer at full resolution), over the `side_count` sides from `first_side`
// (0 +x, 1 −x, 2 +y, 3 −y; the whole term is all four's): on each side the highest of them as
// a horizon, the sine of its elevation above the tangent plane of the pixel (reverse-Z depth
// `depth_here`, world-space unit normal `world_normal`), falling to nothing at the reach's world
// size or at `radius` (metres); a cosine-weighted hemisphere bounded by that horizon is occluded
// by the sine's square. The ray march's steps, a sixth of R apart, step over grooves and creases
// a pixel or two wide; the front layer at full resolution holds them.
fn fine_detail(
    view: View,
    depth: texture_depth_2d,
    pixel: vec2<i32>,
    depth_here: f32,
    world_normal: vec3<f32>,
    reach: i32,
    radius: f32,
    first_side: i32,
    side_count: i32,
) -> f32 {
    if all(world_normal == vec3<f32>(0.0)) {
        return 0.0;
    }
    let dims = vec2<i32>(textureDimensions(depth));
    let size = vec2<f32>(dims);
    let n = normalize((view.view_from_world * vec4<f32>(world_normal, 0.0)).xyz);
    let p = position_in_view(view, (vec2<f32>(pixel) + 0.5) / size, depth_here);
    let footprint = pixel_world_size(view, -p.z, size.y);
    let reach_world = detail_reach_world(reach, footprint, radius);
    var occlusion = 0.0;
    for (var side = first_side; side < first_side + side_count; side++) {
        // The side's direction without an array: CPU rasterizers spill arrays indexed at run
        // time to memory.
        let along = select(vec2<i32>(0, 1), vec2<i32>(1, 0), side < 2) * (1 - 2 * (side & 1));
        var highest = 0.0;
        for (var k = 1; k <= reach; k++) {
            let q = pixel + along * k;
            if any(q < vec2<i32>(0)) || any(q >= dims) {
                break;
            }
            let d = textureLoad(depth, q, 0);
            if d <= 0.0 {
                continue;
            }
            let q_uv = (vec2<f32>(q) + 0.5) / size;
            let v = position_at_linear_depth(view, q_uv, linear_depth(view, d)) - p;
            highest = max(highest, rise(v, n, reach_world));
        }
        occlusion += highest * highest;
    }
    return occlusion / f32(side_count);
}

// The reach of the term in metres for a pixel `footprint` metres wide: `reach` pixels and a half,
// at most `radius`.
fn detail_reach_world(reach: i32, footprint: f32, radius: f32) -> f32 {
    return min((f32(reach) + 0.5) * footprint, radius);
}

// How far a surface point at `v` from the pixel (metres, in the space of the pixel's unit normal
// `n`) rises above the pixel's tangent plane, as the term counts it: the sine of its elevation,
// falling to nothing at `reach_world` metres (negative below the plane; 0 at or past the reach).
fn rise(v: vec3<f32>, n: vec3<f32>, reach_world: f32) -> f32 {
    let distance = length(v);
    if distance <= 0.0 || distance >= reach_world {
        return 0.0;
    }
    let t = distance / reach_world;
    return dot(v, n) / distance * (1.0 - t * t);
}

// `occlusion` with the fine-detail term `detail` (scaled by `intensity`) joined as an independent
// occluder: 1 − (1 − occlusion)(1 − detail).
fn with_fine_detail(occlusion: f32, detail: f32, intensity: f32) -> f32 {
    return 1.0 - (1.0 - occlusion) * (1.0 - min(intensity * detail, 1.0));
}

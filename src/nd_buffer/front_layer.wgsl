// Copies the viewport's pixels of Bevy's prepass into a single-sampled front layer the size of
// the viewport (see `front_layer.rs` for why).

#import bevy_core_pipeline::fullscreen_vertex_shader::FullscreenVertexOutput
#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position_at}

@group(0) @binding(0) var<uniform> view: View;
#ifdef MULTISAMPLED
@group(0) @binding(1) var prepass_depth: texture_depth_multisampled_2d;
@group(0) @binding(2) var prepass_normal: texture_multisampled_2d<f32>;
#ifdef MOTION_VECTORS
@group(0) @binding(3) var prepass_motion_vectors: texture_multisampled_2d<f32>;
#endif
// The meshes of Bevy's prepass drawn again single-sampled, the size of the viewport: the depth a
// single-sampled prepass would hold at each pixel's centre, and the vertex normal there, its
// alpha 0 where the surface is alpha-masked (or absent), which the prepass may have discarded.
@group(0) @binding(4) var centre_depth: texture_depth_2d;
@group(0) @binding(5) var centre_normal: texture_2d<f32>;
// The depth's screen-space gradient there, per pixel: the plane of the triangle at the centre.
@group(0) @binding(6) var centre_depth_gradient: texture_2d<f32>;
#else
@group(0) @binding(1) var prepass_depth: texture_depth_2d;
@group(0) @binding(2) var prepass_normal: texture_2d<f32>;
#ifdef MOTION_VECTORS
@group(0) @binding(3) var prepass_motion_vectors: texture_2d<f32>;
#endif
#endif

struct FrontLayer {
    @builtin(frag_depth) depth: f32,
    @location(0) normal: vec4<f32>,
#ifdef MOTION_VECTORS
    @location(1) motion_vectors: vec4<f32>,
#endif
}

#ifdef MULTISAMPLED
// Samples per pixel: a constant, so that the loops over the samples unroll and index the
// sample positions statically (twice as fast on lavapipe as a count read from the texture).
const SAMPLES: i32 = #{SAMPLES};

// Where sample `s` lies in its pixel: the standard positions, which WebGPU requires
// for 4 samples and Vulkan's standard sample locations give for 2 and 8.
fn sample_position(s: i32) -> vec2<f32> {
    if SAMPLES == 2 {
        return select(vec2(0.25), vec2(0.75), s == 0);
    }
    if SAMPLES == 4 {
        let positions = array(vec2(0.375, 0.125), vec2(0.875, 0.375), vec2(0.125, 0.625), vec2(0.625, 0.875));
        return positions[s];
    }
    if SAMPLES == 8 {
        let positions = array(
            vec2(0.5625, 0.3125), vec2(0.4375, 0.6875), vec2(0.8125, 0.5625), vec2(0.3125, 0.1875),
            vec2(0.1875, 0.8125), vec2(0.0625, 0.4375), vec2(0.6875, 0.9375), vec2(0.9375, 0.0625),
        );
        return positions[s];
    }
    return vec2(0.5);
}

// World position at viewport position `local` (pixels) and reverse-Z depth `depth`.
fn unproject(local: vec2<f32>, depth: f32) -> vec3<f32> {
    return world_position_at(view, local / view.viewport.zw, depth);
}

// The depth at the centre of the pixel at `local` of the surface that sample `s` shows: where
// the ray through the centre meets the plane through the sample's point along its normal `n`.
// The sample's own depth where that ray runs along the plane.
fn depth_at_centre(local: vec2<f32>, s: i32, depth: f32, n: vec3<f32>) -> f32 {
    let centre = local + 0.5;
    let on_surface = unproject(local + sample_position(s), depth);
    let near = unproject(centre, 1.0);
    let along = unproject(centre, depth) - near;
    let facing = dot(n, along);
    if abs(facing) <= 1e-3 * length(along) || depth <= 0.0 {
        return depth;
    }
    let hit = near + along * (dot(n, on_surface - near) / facing);
    let clip = view.clip_from_world * vec4(hit, 1.0);
    let centred = clip.z / clip.w;
    return select(depth, centred, clip.w > 0.0 && centred > 0.0 && centred <= 1.0);
}

// Whether the samples of `pixel` lie on one plane in screen space, as the depths of one triangle
// do, so that their mean is the depth at the pixel's centre: the standard sample positions of
// every count are centred on it. With 4 samples (the standard pattern pairs samples 0 and 3, 1
// and 2 about the centre) that is tested exactly; with other counts, by their spread.
fn one_surface(pixel: vec2<i32>) -> bool {
    if SAMPLES == 4 {
        let d = vec4<f32>(
            textureLoad(prepass_depth, pixel, 0),
            textureLoad(prepass_depth, pixel, 1),
            textureLoad(prepass_depth, pixel, 2),
            textureLoad(prepass_depth, pixel, 3),
        );
        return abs(d.x + d.w - d.y - d.z) <= 1e-4 * max(max(d.x, d.y), max(d.z, d.w)) + 1e-9;
    }
    var lo = 1e30;
    var hi = 0.0;
    for (var s = 0; s < SAMPLES; s += 1) {
        let d = textureLoad(prepass_depth, pixel, s);
        lo = min(lo, d);
        hi = max(hi, d);
    }
    return hi - lo <= 0.02 * hi;
}
#endif

// Relative difference within which two reverse-Z depths lie on one surface.
const SAME_SURFACE: f32 = 0.01;
// Cosine within which a prepass normal (normal-mapped) and a vertex normal are of one surface:
// 37°, more than most normal maps tilt.
const SAME_NORMAL: f32 = 0.8;

@fragment
fn fragment(in: FullscreenVertexOutput) -> FrontLayer {
    // The prepass has the size of the render target; the viewport starts at `view.viewport.xy`.
    let local = floor(in.position.xy);
    let pixel = vec2<i32>(local + view.viewport.xy);
#ifdef MULTISAMPLED
    let centre = textureLoad(centre_depth, vec2<i32>(local), 0);
    let centre_n = textureLoad(centre_normal, vec2<i32>(local), 0);
    // Of the samples on the centre's surface (depth within `SAME_SURFACE`, normal within
    // `SAME_NORMAL` of the vertex normal there), the one nearest the plane of the centre's
    // triangle: on that triangle where any is, whose fragment MSAA shades once, at the pixel's
    // centre, so its normal (normal-mapped) is what a single-sampled prepass holds there. An
    // empty centre matches empty samples.
    let n = decode_normal(centre_n.xyz);
    let gradient = textureLoad(centre_depth_gradient, vec2<i32>(local), 0).xy;
    var best = -1;
    var best_off_plane = 0.0;
    for (var s = 0; s < SAMPLES; s += 1) {
        let d = textureLoad(prepass_depth, pixel, s);
        let off_plane = abs(d - centre - dot(gradient, sample_position(s) - 0.5));
        let facing = dot(decode_normal(textureLoad(prepass_normal, pixel, s).xyz), n);
        let on_it = abs(d - centre) <= SAME_SURFACE * centre && facing >= SAME_NORMAL;
        let same = select(on_it, d == 0.0, centre == 0.0);
        if same && (best < 0 || off_plane < best_off_plane) {
            best = s;
            best_off_plane = off_plane;
        }
    }
    if best >= 0 {
        var out: FrontLayer;
        out.depth = centre;
        out.normal = textureLoad(prepass_normal, pixel, best);
#ifdef MOTION_VECTORS
        out.motion_vectors = textureLoad(prepass_motion_vectors, pixel, best);
#endif
        return out;
    }
    // No sample on it: a sliver between the samples, whose depth and vertex normal only the
    // centre sample has (its motion is taken from the sample nearest in depth). Unless it is
    // alpha-masked, or empty: then the prepass may not show it.
    if centre_n.a > 0.5 {
        var out: FrontLayer;
        out.depth = centre;
        out.normal = centre_n;
#ifdef MOTION_VECTORS
        var nearest = 0;
        for (var s = 1; s < SAMPLES; s += 1) {
            let d = textureLoad(prepass_depth, pixel, s);
            if abs(d - centre) < abs(textureLoad(prepass_depth, pixel, nearest) - centre) {
                nearest = s;
            }
        }
        out.motion_vectors = textureLoad(prepass_motion_vectors, pixel, nearest);
#endif
        return out;
    }
    return from_samples(local, pixel);
#else
    var out: FrontLayer;
    out.depth = textureLoad(prepass_depth, pixel, 0);
    out.normal = textureLoad(prepass_normal, pixel, 0);
#ifdef MOTION_VECTORS
    out.motion_vectors = textureLoad(prepass_motion_vectors, pixel, 0);
#endif
    return out;
#endif
}

#ifdef MULTISAMPLED
// The front layer at a pixel whose centre sample shows an alpha-masked surface (or none) that no
// sample lies on, from the samples alone.
fn from_samples(local: vec2<f32>, pixel: vec2<i32>) -> FrontLayer {
    var out: FrontLayer;
    // Every pass reconstructs a pixel's position at its centre, but no sample lies there (those
    // of 4 samples lie 0.4 px away), and on a floor seen at a grazing angle a depth read that far
    // off tilts the reconstructed surface away from its normal enough to occlude itself. Where
    // the samples lie on one surface their mean is the centre's depth. At silhouettes (two
    // surfaces, whose average would be a point on neither) one sample's surface is carried to
    // the centre along its plane.
    if one_surface(pixel) {
        var depth = 0.0;
        var normal = vec4<f32>(0.0);
        var motion = vec4<f32>(0.0);
        for (var s = 0; s < SAMPLES; s += 1) {
            depth += textureLoad(prepass_depth, pixel, s);
            normal += textureLoad(prepass_normal, pixel, s);
#ifdef MOTION_VECTORS
            motion += textureLoad(prepass_motion_vectors, pixel, s);
#endif
        }
        out.depth = depth / f32(SAMPLES);
#ifdef MOTION_VECTORS
        out.motion_vectors = motion / f32(SAMPLES);
#endif
        // Passes normalise what they decode, so the mean of the encodings is the mean normal:
        // on a normal-mapped surface, closer to the centre's than any one sample's.
        out.normal = normal / f32(SAMPLES);
        return out;
    }
    // At a silhouette the surface that covers most samples most likely covers the centre,
    // which is what a single-sampled prepass would show.
    var nearest = 0;
    var nearest_depth = textureLoad(prepass_depth, pixel, 0);
    for (var s = 1; s < SAMPLES; s += 1) {
        let d = textureLoad(prepass_depth, pixel, s);
        // Reverse-Z: the larger depth is the nearer surface.
        if d > nearest_depth {
            nearest = s;
            nearest_depth = d;
        }
    }
    var covered = 0;
    var behind = -1;
    var behind_depth = 0.0;
    for (var s = 0; s < SAMPLES; s += 1) {
        let d = textureLoad(prepass_depth, pixel, s);
        if nearest_depth - d <= SAME_SURFACE * nearest_depth {
            covered += 1;
        } else if behind < 0 || d > behind_depth {
            behind = s;
            behind_depth = d;
        }
    }
    if 2 * covered <= SAMPLES && behind >= 0 {
        nearest = behind;
        nearest_depth = behind_depth;
    }
    var normal = vec4<f32>(0.0);
    var same = 0.0;
    for (var s = 0; s < SAMPLES; s += 1) {
        if abs(textureLoad(prepass_depth, pixel, s) - nearest_depth) <= SAME_SURFACE * nearest_depth {
            normal += textureLoad(prepass_normal, pixel, s);
            same += 1.0;
        }
    }
    out.normal = normal / same;
    let n = decode_normal(out.normal.xyz);
    out.depth = depth_at_centre(local, nearest, nearest_depth, n);
#ifdef MOTION_VECTORS
    out.motion_vectors = textureLoad(prepass_motion_vectors, pixel, nearest);
#endif
    return out;
}
#endif

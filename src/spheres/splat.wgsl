// Distant-occluder splatting (Shanmugam & Arikan 2007, §5.2): one billboard per sphere covers
// every pixel whose surface point can lie within d_far (eq. 5) of the sphere; the fragment reads
// the ND-buffer and adds A_ψ (eq. 2–3, 1 inside the sphere) into the far-field buffer through
// additive blending. `reference::spheres` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position}
#import bevy_dynamic_ao::sphere_occlusion::sphere_occlusion

struct Sphere {
    // Centre (world space, metres) and radius (metres).
    center_radius: vec4<f32>,
    // x: d_far, metres.
    reach: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(2) var front_depth: texture_depth_2d;
@group(0) @binding(3) var front_normal: texture_2d<f32>;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) sphere: u32,
}

// The screen rectangle (NDC min.xy, max.xy) of the sphere of radius `reach` around the view-space
// point `center`. Perspective: per axis, the two planes through the eye that contain the other
// image axis and touch the sphere bound its image exactly; for the x axis, the plane
// x = k·(−z) touches it where (c_x + k c_z)² = reach² (1 + k²), a quadratic in k whose roots are
// the tangents of the silhouette. A sphere that reaches the eye's plane covers the whole screen;
// one wholly behind it, nothing.
fn reach_rectangle(center: vec3<f32>, reach: f32) -> vec4<f32> {
    let p = view.clip_from_view;
    if p[3][3] == 1.0 {
        // Orthographic.
        let ndc = (p * vec4<f32>(center, 1.0)).xy;
        let extent = abs(vec2<f32>(p[0][0], p[1][1])) * reach;
        return vec4<f32>(ndc - extent, ndc + extent);
    }
    let depth = -center.z;
    if depth + reach <= 0.0 {
        return vec4<f32>(2.0, 2.0, 2.0, 2.0);
    }
    let d2 = depth * depth - reach * reach;
    if depth <= 0.0 || d2 <= 1e-4 * reach * reach {
        return vec4<f32>(-1.0, -1.0, 1.0, 1.0);
    }
    var tangents: array<vec2<f32>, 2>;
    for (var axis = 0; axis < 2; axis += 1) {
        let c = center[axis];
        // Roots of k²(c_z² − R²) + 2k c c_z + c² − R² = 0, with c_z = −depth.
        let root = reach * sqrt(c * c + d2);
        tangents[axis] = vec2<f32>(c * depth - root, c * depth + root) / d2;
    }
    // ndc = P00·(x / −z) + P20·(z / −z), and likewise for y.
    let scale = vec2<f32>(p[0][0], p[1][1]);
    let shift = -vec2<f32>(p[2][0], p[2][1]);
    let a = scale * vec2<f32>(tangents[0].x, tangents[1].x) + shift;
    let b = scale * vec2<f32>(tangents[0].y, tangents[1].y) + shift;
    return vec4<f32>(min(a, b), max(a, b));
}

@vertex
fn vertex(
    @builtin(vertex_index) vertex_index: u32,
    @builtin(instance_index) instance_index: u32,
) -> VertexOutput {
    let sphere = spheres[instance_index];
    let reach = sphere.reach.x;
    let center = (view.view_from_world * vec4<f32>(sphere.center_radius.xyz, 1.0)).xyz;

    let bounds = reach_rectangle(center, reach);
    var lo = bounds.xy;
    var hi = bounds.zw;
    lo = clamp(lo, vec2<f32>(-1.0), vec2<f32>(1.0));
    hi = clamp(hi, vec2<f32>(-1.0), vec2<f32>(1.0));

    var corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    var out: VertexOutput;
    out.position = vec4<f32>(mix(lo, hi, corners[vertex_index]), 0.0, 1.0);
    out.sphere = instance_index;
    return out;
}

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(floor(in.position.xy));
    let depth = textureLoad(front_depth, pixel, 0);
    let normal = decode_normal(textureLoad(front_normal, pixel, 0).xyz);
    if depth <= 0.0 || all(normal == vec3<f32>(0.0)) {
        // Background: nothing receives occlusion.
        discard;
    }
    let sphere = spheres[in.sphere];
    let size = vec2<f32>(textureDimensions(front_depth));
    let p = world_position(view, pixel, size, depth);
    if distance(p, sphere.center_radius.xyz) > sphere.reach.x {
        // Below ε: cut off, as eq. 5 defines the reach.
        discard;
    }
    let a = sphere_occlusion(sphere.center_radius.xyz, sphere.center_radius.w, p, normal);
    return vec4<f32>(a, 0.0, 0.0, 0.0);
}

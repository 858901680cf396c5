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

@vertex
fn vertex(
    @builtin(vertex_index) vertex_index: u32,
    @builtin(instance_index) instance_index: u32,
) -> VertexOutput {
    let sphere = spheres[instance_index];
    let reach = sphere.reach.x;
    let center = (view.view_from_world * vec4<f32>(sphere.center_radius.xyz, 1.0)).xyz;

    // The screen rectangle of the reach sphere, from the corners of its view-space bounding
    // cube: conservative, and exact enough that the fragment's distance test does the rest.
    var lo = vec2<f32>(1e30);
    var hi = vec2<f32>(-1e30);
    var in_front = 0u;
    for (var k = 0u; k < 8u; k += 1u) {
        let sign = vec3<f32>(
            select(-1.0, 1.0, (k & 1u) != 0u),
            select(-1.0, 1.0, (k & 2u) != 0u),
            select(-1.0, 1.0, (k & 4u) != 0u),
        );
        let clip = view.clip_from_view * vec4<f32>(center + reach * sign, 1.0);
        if clip.w > 1e-6 {
            in_front += 1u;
            let ndc = clip.xy / clip.w;
            lo = min(lo, ndc);
            hi = max(hi, ndc);
        }
    }
    if in_front < 8u {
        // Part of the cube is behind the eye: its projection is unbounded.
        lo = vec2<f32>(-1.0);
        hi = vec2<f32>(1.0);
    }
    if in_front == 0u {
        // Wholly behind the eye: no visible point is within reach.
        hi = lo;
    }
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

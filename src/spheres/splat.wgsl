// Distant-occluder splatting (Shanmugam & Arikan 2007, §5.2): one billboard per proxy covers
// every pixel whose surface point its occlusion can reach (the proxy's bounding sphere grown by
// the camera's radius R, or by eq. 5's d_far under `ProxyReach::Epsilon`); the fragment reads the
// ND-buffer and multiplies the visibility buffer by 1 − the proxy's occlusion
// (`proxy_occlusion`), per channel; at half resolution (`DynamicAo::half_resolution`) each texel
// does so for one pixel of its 2 × 2 and compose upsamples the buffer. Counted once: under `FarFieldBlend::CountOnce` the part of the
// proxy within the near field's reach goes to the red channel where the ND-buffer does not hold it
// (the near field counts the rest of that part), the part beyond to the green one.
// `reference::spheres` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position, nd_buffer_holds}
#import bevy_dynamic_ao::proxy_occlusion::{face_normal, face_occlusion, sphere_occlusion_within}
#import bevy_dynamic_ao::uniform::{DynamicAoUniform, seen_by_view}
#import bevy_dynamic_ao::cap_occlusion::share_beyond
#import bevy_dynamic_ao::union_join::{joins_by_union, union_channels}

struct Proxy {
    // Centre (world space, metres) and the radius of a sphere holding the whole proxy.
    centre_bound: vec4<f32>,
    // Half-extent vectors of a box (world space, metres); a sphere's radius × the identity.
    axes: array<vec4<f32>, 3>,
    // x: 0 box, 1 sphere; y: eq. 5's d_far (metres), or 0 for the camera's radius; z: how the
    // proxy joins the others (`spheres::join`): 0 as an independent occluder, 1 by their union,
    // 2 by their union where the receiver lies outside `union_bounds`.
    kind: vec4<f32>,
    // xy: the mesh's RenderLayers as bits (`seen_by_view`).
    layers: vec4<u32>,
    // The lower and upper corners of the box of `kind.z` 2 (world space, metres).
    union_bounds: array<vec4<f32>, 2>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> proxies: array<Proxy>;
@group(0) @binding(2) var front_depth: texture_depth_2d;
@group(0) @binding(3) var front_normal: texture_2d<f32>;
@group(0) @binding(4) var back_depth: texture_depth_2d;
@group(0) @binding(5) var<uniform> settings: DynamicAoUniform;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) proxy: u32,
    // The settings the fragment stage branches on (`ViewSettings`): x R, y the near field's
    // reach, z 1 where the back layer is drawn, w 1 for an orthographic view. They reach it as
    // flat inputs, not as uniform reads: lavapipe (Mesa 22.3) folds uniform values that decide
    // branches into the fragment shader and, for this shader, compiled and kept a new variant at
    // every draw, about 6.6 MB and 25 ms each (the soak benchmark's growth, BENCHMARKS.md).
    @location(1) @interpolate(flat) view_settings: vec4<f32>,
    // Pixels per texel of the target in each axis (`far_resolution_scale`), flat for the same
    // reason.
    @location(2) @interpolate(flat) scale: i32,
}

// The view's settings as the fragment stage reads them (`VertexOutput::view_settings`).
struct ViewSettings {
    radius: f32,
    near: f32,
    use_back: bool,
    orthographic: bool,
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

// How far from its centre a proxy's occlusion reaches, metres.
fn influence(proxy: Proxy) -> f32 {
    if proxy.kind.y > 0.0 {
        return proxy.kind.y;
    }
    return proxy.centre_bound.w + settings.radius;
}

@vertex
fn vertex(
    @builtin(vertex_index) vertex_index: u32,
    @builtin(instance_index) instance_index: u32,
) -> VertexOutput {
    let proxy = proxies[instance_index];
    let center = (view.view_from_world * vec4<f32>(proxy.centre_bound.xyz, 1.0)).xyz;
    var bounds = reach_rectangle(center, influence(proxy));
    if !seen_by_view(settings, proxy.layers.xy) {
        // Off screen: the billboard covers nothing.
        bounds = vec4<f32>(2.0, 2.0, 2.0, 2.0);
    }
    let lo = clamp(bounds.xy, vec2<f32>(-1.0), vec2<f32>(1.0));
    let hi = clamp(bounds.zw, vec2<f32>(-1.0), vec2<f32>(1.0));
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    var out: VertexOutput;
    out.position = vec4<f32>(mix(lo, hi, corners[vertex_index]), 0.0, 1.0);
    out.proxy = instance_index;
    out.view_settings = vec4<f32>(
        settings.radius,
        settings.near_field_radius,
        f32(settings.seen_back_layer != 0u),
        f32(view.clip_from_view[3][3] == 1.0),
    );
    out.scale = i32(settings.far_resolution_scale);
    return out;
}

// How much of the near field's share the ND-buffer holds at `x`.
fn held(vs: ViewSettings, x: vec3<f32>, tolerance: f32) -> f32 {
    return nd_buffer_holds(view, front_depth, back_depth, vs.use_back, x, tolerance);
}

// How fully the camera sees a face with unit normal `f` at `x`: image-space samples are spread
// over the screen, so a face seen edge-on gets almost none of them, even where the ND-buffer
// holds it.
fn seen_face(vs: ViewSettings, x: vec3<f32>, f: vec3<f32>) -> f32 {
    var to_eye = view.world_from_view[2].xyz;
    if !vs.orthographic {
        to_eye = view.world_position - x;
    }
    return clamp(abs(dot(normalize(to_eye), f)) / 0.3, 0.0, 1.0);
}

// The proxy's occlusion within `reach`, in two parts: x, the part within the near field's reach
// where the ND-buffer does not hold it; y, the part beyond the near field's reach, as a share of
// the directions the near part leaves open (the two parts cover different directions, so they
// join back into the whole as 1 − (1 − x)(1 − y)). Where the far field counts every occluder, y is
// all of it. `by_union`: the proxy joins the others by their union here (`joins_by_union`).
fn proxy_occlusion(vs: ViewSettings, proxy: Proxy, by_union: bool, p: vec3<f32>, n: vec3<f32>, reach: f32) -> vec2<f32> {
    let near = vs.near;
    let tolerance = 0.1 * near;
    let centre = proxy.centre_bound.xyz;
    if proxy.kind.x != 0.0 {
        let radius = length(proxy.axes[0].xyz);
        let all = sphere_occlusion_within(p, n, centre, radius, reach);
        if near > 0.0 {
            let inner = sphere_occlusion_within(p, n, centre, radius, near);
            return vec2<f32>(
                inner * (1.0 - held(vs, centre, radius + tolerance)),
                share_beyond(all, inner),
            );
        }
        return vec2<f32>(0.0, all);
    }
    var occlusion = vec2<f32>(0.0);
    // Nothing to do where the whole box lies beyond reach.
    var outside = vec3<f32>(0.0);
    for (var i = 0u; i < 3u; i++) {
        let half = length(proxy.axes[i].xyz);
        let along = select(0.0, dot(p - centre, proxy.axes[i].xyz) / half, half > 0.0);
        outside[i] = max(abs(along) - half, 0.0);
    }
    if reach > 0.0 && length(outside) >= reach {
        return occlusion;
    }
    // Where R is no longer than the near field's reach (the defaults), the whole and the near
    // part are the same.
    let one_part = near > 0.0 && reach > 0.0 && reach <= near;
    // A receiver must lie clearly in front of a face: on a flat box's own plane (a floor under
    // its own receivers) depth precision would otherwise put it just behind one face, under the
    // other, which then covers its whole sky.
    let margin = 1e-4 + 1e-3 * proxy.centre_bound.w;
    for (var i = 0u; i < 3u; i++) {
        let a = proxy.axes[i].xyz;
        let b = proxy.axes[(i + 1u) % 3u].xyz;
        let c = proxy.axes[(i + 2u) % 3u].xyz;
        let normal = face_normal(a, b, c);
        for (var s = 0u; s < 2u; s++) {
            let side = f32(s) * 2.0 - 1.0;
            let f = normal * side;
            let face_centre = centre + a * side;
            if dot(f, p - face_centre) <= margin {
                continue;
            }
            if near <= 0.0 {
                occlusion.y += face_occlusion(p, n, face_centre, f, b, c, reach).occlusion;
                continue;
            }
            let inner = face_occlusion(p, n, face_centre, f, b, c, select(near, min(near, reach), reach > 0.0));
            // The boxes that join by their union (a skinned mesh's, one solid's that got several,
            // an object's seen from outside) fill it between them, each fitting its part loosely: a receiver within the ND-buffer's tolerance of one's
            // face lies on that solid's surface, and the face, tilted against it, would cover up
            // to half its sky. What occludes it that near is the solid's own relief, which the
            // near field reads from the ND-buffer; counted here as well, it drew the outlines of
            // a character's leg boxes on its legs and on the floor between them. A lone box fits
            // its mesh exactly, and what stands that near its face (a floor at a wall) is occluded.
            if inner.occlusion > 0.0 && (!by_union || dot(f, p - face_centre) > tolerance) {
                occlusion.x += inner.occlusion * (1.0 - held(vs, inner.centre, tolerance) * seen_face(vs, inner.centre, f));
            }
            if !one_part {
                let all = face_occlusion(p, n, face_centre, f, b, c, reach).occlusion;
                occlusion.y += share_beyond(all, inner.occlusion);
            }
        }
    }
    return occlusion;
}

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    // At half resolution texel l stands for pixel 2l (as `joint_upsample` expects).
    let pixel = vec2<i32>(floor(in.position.xy)) * in.scale;
    let depth = textureLoad(front_depth, pixel, 0);
    let normal = decode_normal(textureLoad(front_normal, pixel, 0).xyz);
    if depth <= 0.0 || all(normal == vec3<f32>(0.0)) {
        // Background: nothing receives occlusion.
        discard;
    }
    let proxy = proxies[in.proxy];
    let size = vec2<f32>(textureDimensions(front_depth));
    let p = world_position(view, pixel, size, depth);
    let vs = ViewSettings(
        in.view_settings.x,
        in.view_settings.y,
        in.view_settings.z != 0.0,
        in.view_settings.w != 0.0,
    );
    var reach = vs.radius;
    if proxy.kind.y > 0.0 {
        // Eq. 5: cut off beyond d_far, unlimited within.
        if distance(p, proxy.centre_bound.xyz) > proxy.kind.y {
            discard;
        }
        reach = 0.0;
    }
    let by_union = joins_by_union(proxy.kind.z, proxy.union_bounds[0].xyz, proxy.union_bounds[1].xyz, p);
    let occlusion = clamp(proxy_occlusion(vs, proxy, by_union, p, normal, reach), vec2<f32>(0.0), vec2<f32>(1.0));
    return union_channels(occlusion, by_union);
}

// Reading the two-layer ND-buffer (Shanmugam & Arikan 2007, §4.1): positions from reverse-Z depth,
// world-space normals from the `n * 0.5 + 0.5` encoding, and the world size of a pixel.
// `reference::nd_buffer` is the CPU twin of this file.

#define_import_path bevy_dynamic_ao::nd_buffer

#import bevy_render::view::{View, uv_to_ndc, ndc_to_uv}

// World-space unit normal from its `n * 0.5 + 0.5` encoding; zero where nothing was written.
fn decode_normal(encoded: vec3<f32>) -> vec3<f32> {
    let n = encoded * 2.0 - 1.0;
    let len2 = dot(n, n);
    if len2 < 1e-6 {
        return vec3<f32>(0.0);
    }
    return n * inverseSqrt(len2);
}

// World position at viewport coordinates `uv` (0..1, y down) and reverse-Z depth `depth`.
fn world_position_at(view: View, uv: vec2<f32>, depth: f32) -> vec3<f32> {
    let world = view.world_from_clip * vec4<f32>(uv_to_ndc(uv), depth, 1.0);
    return world.xyz / world.w;
}

// World position of the centre of `pixel` at reverse-Z depth `depth`, in a viewport of `size`.
fn world_position(view: View, pixel: vec2<i32>, size: vec2<f32>, depth: f32) -> vec3<f32> {
    return world_position_at(view, (vec2<f32>(pixel) + 0.5) / size, depth);
}

// View-space position at viewport coordinates `uv` (0..1, y down) and reverse-Z depth `depth`.
fn position_in_view(view: View, uv: vec2<f32>, depth: f32) -> vec3<f32> {
    let p = view.view_from_clip * vec4<f32>(uv_to_ndc(uv), depth, 1.0);
    return p.xyz / p.w;
}

// View-space position at viewport coordinates `uv` (0..1, y down) and linear depth `z` (metres in
// front of the camera): `position_in_view` for a depth already made linear, read off the
// projection instead of inverting it (Bevy's projections have no skew: x and y each depend on one
// view-space coordinate and on depth).
fn position_at_linear_depth(view: View, uv: vec2<f32>, z: f32) -> vec3<f32> {
    let p = view.clip_from_view;
    let ndc = uv_to_ndc(uv);
    // View space looks down −z; clip w is −z for a perspective projection and 1 for an
    // orthographic one.
    let view_z = -z;
    let w = p[2][3] * view_z + p[3][3];
    let x = (ndc.x * w - p[2][0] * view_z - p[3][0]) / p[0][0];
    let y = (ndc.y * w - p[2][1] * view_z - p[3][1]) / p[1][1];
    return vec3<f32>(x, y, view_z);
}

// Distance in front of the camera along its view axis of a point at reverse-Z depth `depth`,
// metres. Bevy's projections do not mix the viewport position into depth, so two rows of the
// inverse projection give it, wherever the point is on the screen.
fn linear_depth(view: View, depth: f32) -> f32 {
    let m = view.view_from_clip;
    return -(m[2].z * depth + m[3].z) / (m[2].w * depth + m[3].w);
}

// Distance in front of the camera along its view axis, metres.
fn view_depth(view: View, world_position: vec3<f32>) -> f32 {
    return -(view.view_from_world * vec4<f32>(world_position, 1.0)).z;
}

// World-space height of one pixel at view depth `depth`, metres.
fn pixel_world_size(view: View, depth: f32, height: f32) -> f32 {
    let p11 = view.clip_from_view[1][1];
    if view.clip_from_view[3][3] == 1.0 {
        // Orthographic: constant footprint.
        return 2.0 / (p11 * height);
    }
    return 2.0 * depth / (p11 * height);
}

// How far the ND-buffer already holds the geometry at world point `x`, so that the image-space
// technique counts it (the far field's "counted once"): 1 where `x` projects into the image and
// lies no deeper than the first solid interval of its pixel (the front layer, or the back layer
// where `use_back` says one is drawn) plus `tolerance` metres; 0 where `x` is off-screen, behind
// the camera or deeper than that; a ramp over a second `tolerance` between. A point in front of
// the visible surface, or on a pixel showing no geometry, counts as held: the camera sees through
// it, so nothing there was missed. `reference::nd_buffer::nd_buffer_holds` is the CPU twin.
fn nd_buffer_holds(
    view: View,
    front: texture_depth_2d,
    back: texture_depth_2d,
    use_back: bool,
    x: vec3<f32>,
    tolerance: f32,
) -> f32 {
    let clip = view.clip_from_world * vec4<f32>(x, 1.0);
    if clip.w <= 0.0 {
        return 0.0;
    }
    let ndc = clip.xy / clip.w;
    if any(abs(ndc) >= vec2<f32>(1.0)) {
        return 0.0;
    }
    let dims = textureDimensions(front);
    let size = vec2<f32>(dims);
    let uv = ndc_to_uv(ndc);
    let pixel = min(vec2<i32>(uv * size), vec2<i32>(dims) - 1);
    let front_depth = textureLoad(front, pixel, 0);
    if front_depth <= 0.0 {
        return 1.0;
    }
    var deepest = front_depth;
    if use_back {
        let back_depth = textureLoad(back, pixel, 0);
        if back_depth > 0.0 {
            // Reverse-Z: the smaller depth lies farther away.
            deepest = min(deepest, back_depth);
        }
    }
    let surface = view_depth(view, world_position(view, pixel, size, deepest));
    let beyond = view_depth(view, x) - surface - tolerance;
    return 1.0 - clamp(beyond / max(tolerance, 1e-6), 0.0, 1.0);
}

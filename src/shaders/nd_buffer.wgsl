// Reading the two-layer ND-buffer (Shanmugam & Arikan 2007, §4.1): positions from reverse-Z depth,
// world-space normals from the `n * 0.5 + 0.5` encoding, and the world size of a pixel.
// `reference::nd_buffer` is the CPU twin of this file.

#define_import_path bevy_dynamic_ao::nd_buffer

#import bevy_render::view::View

// World-space unit normal from its `n * 0.5 + 0.5` encoding; zero where nothing was written.
fn decode_normal(encoded: vec3<f32>) -> vec3<f32> {
    let n = encoded * 2.0 - 1.0;
    let len2 = dot(n, n);
    if len2 < 1e-6 {
        return vec3<f32>(0.0);
    }
    return n * inverseSqrt(len2);
}

// World position of the centre of `pixel` at reverse-Z depth `depth`, in a viewport of `size`.
fn world_position(view: View, pixel: vec2<i32>, size: vec2<f32>, depth: f32) -> vec3<f32> {
    let uv = (vec2<f32>(pixel) + 0.5) / size;
    let ndc = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, depth, 1.0);
    let world = view.world_from_clip * ndc;
    return world.xyz / world.w;
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

// The bindings every image-space technique reads (`image_space/pipeline.rs` builds the layout): the view,
// the per-view settings, both ND-buffer layers, the occlusion buffer the technique writes and the
// copy of the front layer's normals it writes for the blur at full resolution; and the receiver
// start-up and the view-space reconstruction they share.

#define_import_path bevy_dynamic_ao::image_space_bindings

#import bevy_render::view::View
#import bevy_dynamic_ao::uniform::DynamicAoUniform
#import bevy_dynamic_ao::nd_buffer::{decode_normal, position_in_view}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> settings: DynamicAoUniform;
@group(0) @binding(2) var front_depth: texture_depth_2d;
@group(0) @binding(3) var front_normal: texture_2d<f32>;
@group(0) @binding(4) var back_depth: texture_depth_2d;
@group(0) @binding(5) var back_normal: texture_2d<f32>;
@group(0) @binding(6) var occlusion: texture_storage_2d<r32float, write>;
// The blur's copy of the front layer's normals (`DynamicAoTextures::blur_normal`), encoded as the
// layer encodes them. At half resolution the upsampling writes it.
@group(0) @binding(7) var blur_normals: texture_storage_2d<rgba16float, write>;

// Full-resolution pixels per texel of the occlusion buffer along each axis, compiled in
// (`image_space::pipeline::ImageSpacePipelines`): read from the uniform, the branches on it still cost
// their reads and stores on lavapipe, which runs an `if`'s body under a mask.
#ifdef HALF_RESOLUTION
const RESOLUTION_SCALE: u32 = 2u;
#else
const RESOLUTION_SCALE: u32 = 1u;
#endif

// View-space position at viewport coordinates `uv` (0..1, y down) and reverse-Z depth `depth`.
fn view_position_at(uv: vec2<f32>, depth: f32) -> vec3<f32> {
    return position_in_view(view, uv, depth);
}

// View-space position of the centre of `pixel` at reverse-Z depth `depth`.
fn view_position(pixel: vec2<i32>, size: vec2<f32>, depth: f32) -> vec3<f32> {
    return view_position_at((vec2<f32>(pixel) + 0.5) / size, depth);
}

// The surface one invocation shades.
struct Receiver {
    // Its full-resolution pixel.
    pixel: vec2<i32>,
    // The texel of the occlusion buffer it writes (half resolution: half of `pixel`).
    out_pixel: vec2<i32>,
    // The full-resolution image size, pixels.
    size: vec2<f32>,
    // Reverse-Z depth of the front layer.
    depth: f32,
    // World-space unit normal of the front layer.
    normal: vec3<f32>,
    // The same surface in view space: its position and unit normal.
    view_position: vec3<f32>,
    view_normal: vec3<f32>,
    // False where there is nothing to shade: outside the image, or background (written as open
    // by `store_occlusion`).
    shade: bool,
}

// Copies the front layer's normal at `pixel` into `blur_normals` at full resolution, for a pixel
// no receiver is made for this frame (the ray march's checkerboard skips it).
fn copy_blur_normal(pixel: vec2<i32>) {
#ifndef HALF_RESOLUTION
    if any(pixel >= vec2<i32>(textureDimensions(front_depth))) {
        return;
    }
    textureStore(blur_normals, pixel, vec4<f32>(textureLoad(front_normal, pixel, 0).xyz, 0.0));
#endif
}

// The receiver of `invocation`. At half resolution each invocation computes the full-resolution
// pixel at twice its index and writes one texel of the half-size buffer.
fn receiver(invocation: vec3<u32>) -> Receiver {
    var r: Receiver;
    let id = invocation.xy * RESOLUTION_SCALE;
    let dims = textureDimensions(front_depth);
    r.out_pixel = vec2<i32>(invocation.xy);
    r.pixel = vec2<i32>(id);
    r.size = vec2<f32>(dims);
    r.shade = false;
    if id.x >= dims.x || id.y >= dims.y {
        return r;
    }
    r.depth = textureLoad(front_depth, r.pixel, 0);
    let encoded = textureLoad(front_normal, r.pixel, 0).xyz;
#ifndef HALF_RESOLUTION
    textureStore(blur_normals, r.pixel, vec4<f32>(encoded, 0.0));
#endif
    r.normal = decode_normal(encoded);
    if r.depth <= 0.0 || dot(r.normal, r.normal) == 0.0 {
        return r;
    }
    r.view_position = view_position(r.pixel, r.size, r.depth);
    r.view_normal = normalize((view.view_from_world * vec4<f32>(r.normal, 0.0)).xyz);
    r.shade = true;
    return r;
}

// Writes receiver `r`'s occlusion `value`, clamped to [0, 1], or open where it shades nothing.
// Each technique stores through this once, after its branches: lavapipe runs every branch under
// a mask, so a store in each would cost every invocation (BENCHMARKS.md, "Workgroups along
// rows").
fn store_occlusion(r: Receiver, value: f32) {
    if all(r.out_pixel < vec2<i32>(textureDimensions(occlusion))) {
        let stored = select(0.0, clamp(value, 0.0, 1.0), r.shade);
        textureStore(occlusion, r.out_pixel, vec4<f32>(stored));
    }
}

// Copies the AO buffer and both ND-buffer layers into plain float images for the CPU.

#import bevy_dynamic_ao::nd_buffer::decode_normal
#import bevy_dynamic_ao::uniform::{DynamicAoUniform, visibility_pixel}

@group(0) @binding(0) var visibility: texture_2d<f32>;
@group(0) @binding(1) var front_depth: texture_depth_2d;
@group(0) @binding(2) var front_normal: texture_2d<f32>;
@group(0) @binding(3) var back_depth: texture_depth_2d;
@group(0) @binding(4) var back_normal: texture_2d<f32>;
@group(0) @binding(5) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(6) var front_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(7) var back_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(8) var<uniform> settings: DynamicAoUniform;

@compute @workgroup_size(8, 8, 1)
fn readback(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = textureDimensions(visibility_out);
    if id.x >= dims.x || id.y >= dims.y {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let depth = textureLoad(front_depth, pixel, 0);
    // Where no geometry is, nothing is occluded.
    let at = visibility_pixel(settings, pixel, textureDimensions(visibility), dims);
#ifdef AO_NOT_WRITTEN
    // Nothing wrote the AO texture this frame (its passes are still compiling): what it holds
    // is no frame's AO, and the sentinel says so.
    let open = -1.0;
#else
    let open = select(textureLoad(visibility, at, 0).r, 1.0, depth <= 0.0);
#endif
    textureStore(visibility_out, pixel, vec4<f32>(open));
    textureStore(front_out, pixel, vec4<f32>(decode_normal(textureLoad(front_normal, pixel, 0).xyz), depth));
    let back = textureLoad(back_depth, pixel, 0);
    // Only the near field's layer holds normals; the others draw depth alone.
    var back_n = vec3<f32>(0.0);
    if settings.near_field_back_layer != 0u {
        back_n = decode_normal(textureLoad(back_normal, pixel, 0).xyz);
    }
    textureStore(back_out, pixel, vec4<f32>(back_n, back));
}

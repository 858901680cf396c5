// What the last filter passes write (`blur.wgsl`, `upsample.wgsl`): occlusion (one channel, or
// two with TWO_CHANNELS), or with VISIBILITY the visibility Bevy's PBR reads, at the viewport's
// place in its texture (`DynamicAoView::filter_is_last`). The including pipeline sets
// OUTPUT_BINDING, the output's binding in its group 0.

#define_import_path bevy_dynamic_ao::filter_output

#import bevy_dynamic_ao::uniform::{DynamicAoUniform, visibility_pixel, visibility_of}

#ifdef VISIBILITY_R16FLOAT
@group(0) @binding(#{OUTPUT_BINDING}) var output: texture_storage_2d<r16float, write>;
#else ifdef VISIBILITY
@group(0) @binding(#{OUTPUT_BINDING}) var output: texture_storage_2d<r32float, write>;
#else ifdef TWO_CHANNELS
@group(0) @binding(#{OUTPUT_BINDING}) var output: texture_storage_2d<rg32float, write>;
#else
@group(0) @binding(#{OUTPUT_BINDING}) var output: texture_storage_2d<r32float, write>;
#endif

// Writes the filtered `value` of `pixel` of a viewport of `viewport_size` pixels.
fn store_filtered(
    settings: DynamicAoUniform,
    pixel: vec2<i32>,
    value: vec2<f32>,
    viewport_size: vec2<u32>,
) {
#ifdef VISIBILITY
    let at = visibility_pixel(settings, pixel, textureDimensions(output), viewport_size);
    textureStore(output, at, vec4<f32>(visibility_of(value.x)));
#else
    textureStore(output, pixel, vec4<f32>(value, 0.0, 0.0));
#endif
}

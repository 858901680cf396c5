// Separable cross-bilateral blur of the occlusion buffer (Bavoil & Sainz 2008, "Cross Bilateral
// Filter"), of one channel or, with TWO_CHANNELS, of the two of far-field occlusion. Each tap is
// weighted by its distance, its depth difference and, for one channel, the angle between its
// normal and the centre's: the paper's depth weight alone carries occlusion across creases and
// panel lines, where the depth hardly changes. The Y pass of one channel then multiplies in the
// fine-detail term (`AoBlur::detail_reach`, all four sides; `blur_detail_reach` is 0 under
// temporal accumulation, where the ray march adds it a side a frame). With VISIBILITY the Y
// pass writes the texture Bevy's PBR reads, as compose would have
// (`DynamicAoView::filter_is_last`). `reference::filter` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::uniform::DynamicAoUniform
#import bevy_dynamic_ao::filter_output::store_filtered
#import bevy_dynamic_ao::nd_buffer::{linear_depth, decode_normal}
#import bevy_dynamic_ao::fine_detail::{fine_detail, with_fine_detail}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> settings: DynamicAoUniform;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var normal: texture_2d<f32>;
@group(0) @binding(4) var input: texture_2d<f32>;
// Binding 5 is `output` (`shaders/filter_output.wgsl`).

fn store(pixel: vec2<i32>, value: vec2<f32>) {
    store_filtered(settings, pixel, value, textureDimensions(depth));
}

// The channels a texel of `input` carries.
fn input_value(q: vec2<i32>) -> vec2<f32> {
#ifdef TWO_CHANNELS
    return textureLoad(input, q, 0).rg;
#else
    return vec2<f32>(textureLoad(input, q, 0).r, 0.0);
#endif
}

fn blur(pixel: vec2<i32>, step: vec2<i32>) {
    let dims = vec2<i32>(textureDimensions(depth));
    if any(pixel >= dims) {
        return;
    }
    let center_depth = textureLoad(depth, pixel, 0);
    if center_depth <= 0.0 {
        store(pixel, vec2<f32>(0.0));
        return;
    }
    let z0 = linear_depth(view, center_depth);
#ifdef TWO_CHANNELS
    // The voxel term's (see `DynamicAoUniform::voxel_blur_radius`); it weighs by depth alone
    // (`AoBlur::normal_sharpness`).
    let radius = i32(settings.voxel_blur_radius);
    let normal_sharpness = 0.0;
#else
    let radius = i32(settings.blur_radius);
    let normal_sharpness = settings.blur_normal_sharpness;
#endif
    var n0 = vec3<f32>(0.0);
    if normal_sharpness > 0.0 {
        n0 = decode_normal(textureLoad(normal, pixel, 0).xyz);
    }
    let sigma = (f32(radius) + 1.0) * 0.5;
    let falloff = 1.0 / (2.0 * sigma * sigma);
    var sum = vec2<f32>(0.0);
    var weights = 0.0;
    for (var i = -radius; i <= radius; i++) {
        let q = pixel + step * i;
        if any(q < vec2<i32>(0)) || any(q >= dims) {
            continue;
        }
        let d = textureLoad(depth, q, 0);
        if d <= 0.0 {
            continue;
        }
        let dz = (linear_depth(view, d) - z0) / z0 * settings.blur_sharpness;
        var bend = 0.0;
        if normal_sharpness > 0.0 {
            bend = (1.0 - dot(n0, decode_normal(textureLoad(normal, q, 0).xyz))) * normal_sharpness;
        }
        let w = exp(-f32(i * i) * falloff - dz * dz - bend * bend);
        sum += w * input_value(q);
        weights += w;
    }
    var value = sum / weights;
#ifndef TWO_CHANNELS
    if step.y == 1 && settings.blur_detail_reach > 0u {
        if normal_sharpness <= 0.0 {
            n0 = decode_normal(textureLoad(normal, pixel, 0).xyz);
        }
        let reach = i32(settings.blur_detail_reach);
        let r = settings.image_space_radius;
        let detail = fine_detail(view, depth, pixel, center_depth, n0, reach, r, 0, 4);
        value.x = with_fine_detail(value.x, detail, settings.intensity);
    }
#endif
    store(pixel, value);
}

@compute @workgroup_size(8, 8, 1)
fn blur_x(@builtin(global_invocation_id) id: vec3<u32>) {
    blur(vec2<i32>(id.xy), vec2<i32>(1, 0));
}

@compute @workgroup_size(8, 8, 1)
fn blur_y(@builtin(global_invocation_id) id: vec3<u32>) {
    blur(vec2<i32>(id.xy), vec2<i32>(0, 1));
}

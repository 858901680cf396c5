// Joint bilateral upsampling of a half-resolution occlusion buffer (Reinbothe, Boubekeur & Alexa
// 2009, §7, eq. 5–7): each full-resolution pixel x averages the low-resolution texels y of a
// window around it, weighted by the Wendland kernel (eq. 3) over screen distance, normal
// difference, world distance and AO difference (of the summed channels, with TWO_CHANNELS).
// The window is the 2 × 2 texels that bracket x (those bilinear interpolation would read)
// rather than 3 × 3: less than half the loads and position reconstructions, for the pass that
// cost more than the half-resolution AO it upsampled (`joint_upsample::bracket` gives the
// window and the weights but the AO difference's). `reference::filter` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position}
#import bevy_dynamic_ao::uniform::DynamicAoUniform
#import bevy_dynamic_ao::math::wendland
#import bevy_dynamic_ao::joint_upsample::{bracket, bracket_texel}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> settings: DynamicAoUniform;
@group(0) @binding(2) var depth_texture: texture_depth_2d;
@group(0) @binding(3) var normal_texture: texture_2d<f32>;
@group(0) @binding(4) var low: texture_2d<f32>;
#ifdef TWO_CHANNELS
@group(0) @binding(5) var output: texture_storage_2d<rg32float, write>;
#else
@group(0) @binding(5) var output: texture_storage_2d<r32float, write>;
#endif

// The channels a texel of `low` carries.
fn low_value(l: vec2<i32>) -> vec2<f32> {
#ifdef TWO_CHANNELS
    return textureLoad(low, l, 0).rg;
#else
    return vec2<f32>(textureLoad(low, l, 0).r, 0.0);
#endif
}

@compute @workgroup_size(8, 8, 1)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = vec2<i32>(textureDimensions(depth_texture));
    let x = vec2<i32>(id.xy);
    if any(x >= dims) {
        return;
    }
    let depth = textureLoad(depth_texture, x, 0);
    if depth <= 0.0 {
        textureStore(output, x, vec4<f32>(0.0));
        return;
    }
    let p = world_position(view, x, vec2<f32>(dims), depth);
    let n = decode_normal(textureLoad(normal_texture, x, 0).xyz);
    let b = bracket(view, depth_texture, normal_texture, x, p, n, vec2<i32>(textureDimensions(low)), settings.image_space_radius, 2.0);
    let v_x = low_value(b.nearest);
    let h_x = v_x.x + v_x.y;
    let v = array<vec2<f32>, 4>(
        low_value(bracket_texel(b, 0)),
        low_value(bracket_texel(b, 1)),
        low_value(bracket_texel(b, 2)),
        low_value(bracket_texel(b, 3)),
    );
    let w = b.weights * vec4<f32>(
        wendland(abs(h_x - (v[0].x + v[0].y)), 1.0),
        wendland(abs(h_x - (v[1].x + v[1].y)), 1.0),
        wendland(abs(h_x - (v[2].x + v[2].y)), 1.0),
        wendland(abs(h_x - (v[3].x + v[3].y)), 1.0),
    );
    let sum = w.x * v[0] + w.y * v[1] + w.z * v[2] + w.w * v[3];
    let weights = w.x + w.y + w.z + w.w;
    textureStore(output, x, vec4<f32>(select(v_x, sum / weights, weights > 0.0), 0.0, 0.0));
}

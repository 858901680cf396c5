// Joint bilateral upsampling of a half-resolution occlusion buffer (Reinbothe, Boubekeur & Alexa
// 2009, §7, eq. 5–7): each full-resolution pixel x averages the low-resolution texels y of a
// window around it, weighted by the Wendland kernel (eq. 3) over screen distance, normal
// difference, world distance and AO difference (of the summed channels, with TWO_CHANNELS).
// The window is the 2 × 2 texels that bracket x (those bilinear interpolation would read)
// rather than 3 × 3: less than half the loads and position reconstructions, for the pass that
// cost more than the half-resolution AO it upsampled. `reference::filter` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position}
#import bevy_dynamic_ao::uniform::DynamicAoUniform
#import bevy_dynamic_ao::math::wendland

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

// Screen-space support of w_d, full-resolution pixels (the m of eq. 6).
const WINDOW: f32 = 4.0;

@compute @workgroup_size(8, 8, 1)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = vec2<i32>(textureDimensions(depth_texture));
    let low_dims = vec2<i32>(textureDimensions(low));
    let x = vec2<i32>(id.xy);
    if any(x >= dims) {
        return;
    }
    let size = vec2<f32>(dims);
    let depth = textureLoad(depth_texture, x, 0);
    if depth <= 0.0 {
        textureStore(output, x, vec4<f32>(0.0));
        return;
    }
    let p = world_position(view, x, size, depth);
    let n = decode_normal(textureLoad(normal_texture, x, 0).xyz);
    let nearest = min(x / 2, low_dims - 1);
    let v_x = low_value(nearest);
    let h_x = v_x.x + v_x.y;
    // Texel l was computed at pixel 2l: an odd x lies between l and l + 1, an even one on l.
    let toward = select(vec2<i32>(-1), vec2<i32>(1), (x & vec2<i32>(1)) == vec2<i32>(1));
    var sum = vec2<f32>(0.0);
    var weights = 0.0;
    for (var j = 0; j <= 1; j++) {
        for (var i = 0; i <= 1; i++) {
            let l = nearest + toward * vec2<i32>(i, j);
            // The full-resolution pixel each low-resolution texel was computed at.
            let y = l * 2;
            if any(l < vec2<i32>(0)) || any(l >= low_dims) || any(y >= dims) {
                continue;
            }
            let dq = textureLoad(depth_texture, y, 0);
            if dq <= 0.0 {
                continue;
            }
            let v_y = low_value(l);
            let h_y = v_y.x + v_y.y;
            let w_d = wendland(length(vec2<f32>(x - y)), WINDOW);
            let w_n = wendland(1.0 - dot(n, decode_normal(textureLoad(normal_texture, y, 0).xyz)), 2.0);
            let w_p = wendland(distance(p, world_position(view, y, size, dq)), settings.image_space_radius);
            let w_h = wendland(abs(h_x - h_y), 1.0);
            let w = w_d * w_n * w_p * w_h;
            sum += w * v_y;
            weights += w;
        }
    }
    textureStore(output, x, vec4<f32>(select(v_x, sum / weights, weights > 0.0), 0.0, 0.0));
}

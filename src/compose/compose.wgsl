// Combined ambient occlusion, handed to Bevy's PBR lighting as visibility, 1 − occlusion.
//
// Every far-field term arrives in two channels: red, the occluders within the near field's reach
// that the ND-buffer does not hold (so the near field misses them); green, the occluders beyond
// that reach (under `FarFieldBlend::CountOnce`; with the other blends everything is in green).
// Spheres and AO fields arrive as visibilities, the products over their occluders (Malmer et al.
// §3.3.2); voxel volumes (Reinbothe et al. §4) as occlusion. Per channel the terms join as
// independent occluders, 1 − Π(1 − term). The proxies of a skinned mesh are not independent:
// parts of one character stand one behind another as a receiver sees them (an arm before its
// torso), and the product counts the hidden part too; their union is taken halfway between the
// largest single proxy (everything else hidden behind it) and the product (nothing hidden), a
// rule measured against ray-traced proxies (see `spheres`); a closed rigid mesh with several
// proxies (a ring) joins them the same way, and an open one (a frame, a room) where the receiver
// lies outside its proxies' bounds, with whatever stands inside them (`spheres::join`); so do
// the AO fields of objects that fill one another's bounds, where the receiver lies outside them
// (`fields::join`). Other occluders (walls, floors, boxy props) multiply: inside a room the
// walls lie in different directions and hide nothing of one another. Counted
// once: within the near field's reach the larger of the near field and the red
// channel counts, because what the ND-buffer misses is most often the hidden side of what it
// shows (the two cover the same directions); beyond it, the green channel joins as an
// independent occluder, but for the part the proxies joined by their union cast: that joins
// what counts within the reach by the same union, because the near field has counted the
// solid's near side, which hides its far side from receivers beside it (a floor beside a ring:
// joined to the default at R = 2 m, `ring.glb` read 0.0484 RMSE independent, 0.0341 so; the
// default alone 0.0318; BENCHMARKS.md, "Near and far sides of one solid"). `Add` adds the near
// and far terms and clamps (Shanmugam & Arikan 2007, §6); `Max` takes the larger. The sphere and
// field splats may arrive at half resolution: each pixel then blends the texels that bracket it
// (`joint_upsample`).

#import bevy_render::view::View
#import bevy_dynamic_ao::uniform::{DynamicAoUniform, visibility_pixel, visibility_of}
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position}
#import bevy_dynamic_ao::joint_upsample::{Bracket, bracket, bracket_texel}

@group(0) @binding(0) var<uniform> settings: DynamicAoUniform;
@group(0) @binding(1) var near_occlusion: texture_2d<f32>;
@group(0) @binding(2) var sphere_visibility: texture_2d<f32>;
@group(0) @binding(3) var field_visibility: texture_2d<f32>;
@group(0) @binding(4) var voxel_occlusion: texture_2d<f32>;
#ifdef VISIBILITY_R16FLOAT
@group(0) @binding(5) var visibility: texture_storage_2d<r16float, write>;
#else
@group(0) @binding(5) var visibility: texture_storage_2d<r32float, write>;
#endif
@group(0) @binding(6) var<uniform> view: View;
@group(0) @binding(7) var front_depth: texture_depth_2d;
@group(0) @binding(8) var front_normal: texture_2d<f32>;

// With UPSAMPLE_SPLATS (the splats at half resolution), the bracket of `pixel` in them; its
// weights are all 0 (read `nearest` alone) at full resolution and on the background. A variant of
// its own: on lavapipe the upsampling costs every pixel even where a uniform skips it.
fn splat_bracket(pixel: vec2<i32>, dims: vec2<u32>) -> Bracket {
    var none = Bracket(pixel, vec2<i32>(0), vec4<f32>(0.0));
#ifdef UPSAMPLE_SPLATS
    none.nearest = pixel / 2;
    let depth = textureLoad(front_depth, pixel, 0);
    if depth <= 0.0 {
        return none;
    }
    let p = world_position(view, pixel, vec2<f32>(dims), depth);
    let n = decode_normal(textureLoad(front_normal, pixel, 0).xyz);
    let low_dims = vec2<i32>((dims + 1u) / 2u);
    // A support of a few pixels' footprint measured worse (more pixels fall back to the nearest
    // texel, which may lie on another surface) than the near field's reach. No normal weight past
    // a right angle: of the supports 2, 1 and 0.3 tried on the open room at 2 m, 1 came closest
    // to ground truth (`far_field::half_resolution_splats_stay_as_close_to_ground_truth`).
    return bracket(view, front_depth, front_normal, pixel, p, n, low_dims, settings.image_space_radius);
#else
    return none;
#endif
}

// The value of a splat buffer at the pixel `b` was made for.
fn splat_value(splat: texture_2d<f32>, b: Bracket) -> vec4<f32> {
    let weights = dot(b.weights, vec4<f32>(1.0));
    if weights <= 0.0 {
        return textureLoad(splat, b.nearest, 0);
    }
    let sum = b.weights.x * textureLoad(splat, bracket_texel(b, 0), 0)
        + b.weights.y * textureLoad(splat, bracket_texel(b, 1), 0)
        + b.weights.z * textureLoad(splat, bracket_texel(b, 2), 0)
        + b.weights.w * textureLoad(splat, bracket_texel(b, 3), 0);
    return sum / weights;
}

// The union of occluders that may hide one another, taken halfway between the largest of them
// (`largest`: everything else hidden behind it) and their product as independent occluders
// (`product`: nothing hidden).
fn halfway(largest: f32, product: f32) -> f32 {
    return largest + 0.5 * (product - largest);
}

// Both channels of the occluders' product `occlusion` scaled so that those that join by their
// union here (`spheres::join`, `fields::join`; their product leaves `articulated_open` open, the
// largest single one blocks `largest`) count halfway between that largest one and their product,
// and every other occluder joins as an independent one.
fn occluder_union(occlusion: vec2<f32>, articulated_open: f32, largest: f32) -> vec2<f32> {
    let product = 1.0 - (1.0 - occlusion.x) * (1.0 - occlusion.y);
    if product <= 0.0 {
        return occlusion;
    }
    let articulated = 1.0 - articulated_open;
    let together = halfway(min(largest, articulated), articulated);
    let rigid_open = clamp((1.0 - product) / max(articulated_open, 1e-6), 0.0, 1.0);
    let total = 1.0 - (1.0 - together) * rigid_open;
    return occlusion * (total / product);
}

@compute @workgroup_size(8, 8, 1)
fn compose(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = textureDimensions(near_occlusion);
    if id.x >= dims.x || id.y >= dims.y {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    var near = 0.0;
    if settings.image_space != 0u {
        near = clamp(textureLoad(near_occlusion, pixel, 0).r, 0.0, 1.0);
    }
    // Per channel: what the far-field occluders leave open.
    var open = vec2<f32>(1.0);
    let splat = splat_bracket(pixel, dims);
    // The share of the green channel the proxies joined by their union cast (`solid_beyond`).
    var solid_beyond = 0.0;
    if settings.spheres != 0u {
        let spheres = splat_value(sphere_visibility, splat);
        let joined = occluder_union(1.0 - spheres.rg, spheres.b, spheres.a);
        let solid_share = (1.0 - spheres.b) / max(1.0 - spheres.r * spheres.g, 1e-6);
        solid_beyond = joined.y * clamp(solid_share, 0.0, 1.0);
        open *= 1.0 - joined;
    }
    if settings.fields != 0u {
        let fields = splat_value(field_visibility, splat);
        open *= 1.0 - occluder_union(1.0 - fields.rg, fields.b, fields.a);
    }
    if settings.voxels != 0u {
        open *= 1.0 - textureLoad(voxel_occlusion, pixel, 0).rg;
    }
    let far = 1.0 - clamp(open, vec2<f32>(0.0), vec2<f32>(1.0));
    var occlusion = near;
    if settings.spheres != 0u || settings.fields != 0u || settings.voxels != 0u {
        let all_far = 1.0 - (1.0 - far.x) * (1.0 - far.y);
        switch settings.far_field_blend {
            case 0u: {
                occlusion = near + all_far;
            }
            case 1u: {
                occlusion = max(near, all_far);
            }
            default: {
                let within = max(near, far.x);
                let rest = clamp(1.0 - (1.0 - far.y) / max(1.0 - solid_beyond, 1e-6), 0.0, 1.0);
                let both = 1.0 - (1.0 - within) * (1.0 - solid_beyond);
                let together = halfway(max(within, solid_beyond), both);
                occlusion = 1.0 - (1.0 - together) * (1.0 - rest);
            }
        }
    }
    let at = visibility_pixel(settings, pixel, textureDimensions(visibility), dims);
    textureStore(visibility, at, vec4<f32>(visibility_of(occlusion)));
}

// The texels of a half-resolution buffer that a full-resolution pixel blends, and their weights
// (Reinbothe, Boubekeur & Alexa 2009, §7, eq. 5–7): the 2 × 2 texels that bracket the pixel
// (those bilinear interpolation would read), each weighted by the Wendland kernel (eq. 3) over
// screen distance, normal difference and world distance to the pixel it was computed at (texel l
// at pixel 2l). Used by compose for the sphere and field splats (`bracket`), and by the filter's
// upsampling of the image-space and voxel terms (`texel_guide` and `guide_weight`, over the 3 × 3
// texels around a 2 × 2 quad of pixels' own, weighing the distance from the pixel's tangent
// plane in place of the world distance, `plane_surface_weight`).
// `reference::filter` is the CPU twin.

#define_import_path bevy_dynamic_ao::joint_upsample

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position}
#import bevy_dynamic_ao::math::wendland

// Screen-space support of w_d, full-resolution pixels (the m of eq. 6).
const WINDOW: f32 = 4.0;
// Support of w_n over 1 − cos of the angle between a texel's normal and the pixel's: a surface at
// a right angle to the pixel's counts a twentieth, one at 60° a half. At 2 a right angle counted
// a fifth, and the image-space terms carried occlusion across edges a pixel or two wide, such as
// a heat sink's bright fin tops between its dark gaps (converged high-frequency error 6% lower
// there, 3% on DamagedHelmet on a floor). At 1 (nothing at a right angle) the fins gained twice
// as much, but a room's creases lost more detail than Bevy's SSAO does (BENCHMARKS.md, "Past the
// screen's edge, and fins").
const NORMAL_SUPPORT: f32 = 1.5;
// Support of the upsampling's plane weight (`plane_surface_weight`) over a texel's distance from the
// pixel's tangent plane, in the pixel's footprints (its world size at its depth).
const PLANE_SUPPORT: f32 = 2.0;

// The bracketing texels of one full-resolution pixel: texel k (`bracket_texel`) counts with
// `weights[k]` (0 where it lies off the buffer, on the background, or on another surface);
// `nearest` is the texel holding the pixel, for when no weight counts. No arrays and no
// dynamic indices: CPU rasterizers spill those to memory.
struct Bracket {
    nearest: vec2<i32>,
    // Towards the other texels of the bracket, ±1 per axis.
    toward: vec2<i32>,
    weights: vec4<f32>,
}

// Texel `k` (0–3) of bracket `b`.
fn bracket_texel(b: Bracket, k: i32) -> vec2<i32> {
    return b.nearest + b.toward * vec2<i32>(k & 1, k >> 1u);
}

// The surface texel `l` of a half-resolution buffer was computed at: full-resolution pixel
// `y` = 2l, its world position `p` and unit normal `n`; `on_surface` is false where the texel
// lies off the buffer or on the background (it then counts for no pixel).
struct Guide {
    y: vec2<i32>,
    p: vec3<f32>,
    n: vec3<f32>,
    on_surface: bool,
}

// The guide of texel `l` in a buffer of `low_dims` texels, over the ND-buffer `depth_texture` /
// `normal_texture`.
fn texel_guide(
    view: View,
    depth_texture: texture_depth_2d,
    normal_texture: texture_2d<f32>,
    l: vec2<i32>,
    low_dims: vec2<i32>,
) -> Guide {
    let dims = vec2<i32>(textureDimensions(depth_texture));
    var g = Guide(l * 2, vec3<f32>(0.0), vec3<f32>(0.0), false);
    if any(l < vec2<i32>(0)) || any(l >= low_dims) || any(g.y >= dims) {
        return g;
    }
    let dq = textureLoad(depth_texture, g.y, 0);
    if dq <= 0.0 {
        return g;
    }
    g.p = world_position(view, g.y, vec2<f32>(dims), dq);
    g.n = decode_normal(textureLoad(normal_texture, g.y, 0).xyz);
    g.on_surface = true;
    return g;
}

// The weight of the texel with guide `g` for pixel `x` (world position `p`, unit normal `n`):
// `reach` (metres) is the support of the world-distance weight.
fn guide_weight(g: Guide, x: vec2<i32>, p: vec3<f32>, n: vec3<f32>, reach: f32) -> f32 {
    return screen_weight(length(vec2<f32>(x - g.y))) * surface_weight(g, p, n, reach);
}

// w_d of a texel `distance` full-resolution pixels from the pixel it counts for.
fn screen_weight(distance: f32) -> f32 {
    return wendland(distance, WINDOW);
}

// `guide_weight` without w_d: how far the texel's surface agrees with the pixel's.
fn surface_weight(g: Guide, p: vec3<f32>, n: vec3<f32>, reach: f32) -> f32 {
    if !g.on_surface {
        return 0.0;
    }
    return normal_weight(g, n) * wendland(distance(p, g.p), reach);
}

// w_n: how far the normal of the texel with guide `g` agrees with the pixel's, `n`.
fn normal_weight(g: Guide, n: vec3<f32>) -> f32 {
    return wendland(1.0 - dot(n, g.n), NORMAL_SUPPORT);
}

// `surface_weight` as the upsampling of the image-space and voxel terms weighs it: the texel's
// distance from the tangent plane of the pixel (at `p`, with unit normal `plane_n`, both in the
// guide's space; world-space normal `n`; `footprint` metres wide) in place of its world distance
// to the pixel. The world distance's support is R, and texels 2.5 pixels away lie well inside it
// whatever surface they show: a fin's top a pixel wide took the occlusion of the gap's floor
// beside it, 5 cm lower and facing the same way. Measured against the plane, not the pixel, a
// floor seen at a grazing angle, whose texels lie many footprints away along it, keeps them all,
// and a texel on another surface far away lies far off the plane as well.
fn plane_surface_weight(
    g: Guide,
    p: vec3<f32>,
    n: vec3<f32>,
    plane_n: vec3<f32>,
    footprint: f32,
) -> f32 {
    if !g.on_surface {
        return 0.0;
    }
    return normal_weight(g, n) * wendland(abs(dot(plane_n, g.p - p)), PLANE_SUPPORT * footprint);
}

// The weight of texel `l` for pixel `x` (world position `p`, unit normal `n`).
fn texel_weight(
    view: View,
    depth_texture: texture_depth_2d,
    normal_texture: texture_2d<f32>,
    x: vec2<i32>,
    p: vec3<f32>,
    n: vec3<f32>,
    l: vec2<i32>,
    low_dims: vec2<i32>,
    reach: f32,
) -> f32 {
    let g = texel_guide(view, depth_texture, normal_texture, l, low_dims);
    return guide_weight(g, x, p, n, reach);
}

// The bracket of pixel `x` (world position `p`, unit normal `n`) in a buffer of `low_dims`
// texels, over the ND-buffer `depth_texture` / `normal_texture`; `reach` (metres) is the support
// of the world-distance weight.
fn bracket(
    view: View,
    depth_texture: texture_depth_2d,
    normal_texture: texture_2d<f32>,
    x: vec2<i32>,
    p: vec3<f32>,
    n: vec3<f32>,
    low_dims: vec2<i32>,
    reach: f32,
) -> Bracket {
    // Texel l was computed at pixel 2l: an odd x lies between l and l + 1, an even one on l.
    let toward = select(vec2<i32>(-1), vec2<i32>(1), (x & vec2<i32>(1)) == vec2<i32>(1));
    var b = Bracket(min(x / 2, low_dims - 1), toward, vec4<f32>(0.0));
    b.weights = vec4<f32>(
        texel_weight(view, depth_texture, normal_texture, x, p, n, bracket_texel(b, 0), low_dims, reach),
        texel_weight(view, depth_texture, normal_texture, x, p, n, bracket_texel(b, 1), low_dims, reach),
        texel_weight(view, depth_texture, normal_texture, x, p, n, bracket_texel(b, 2), low_dims, reach),
        texel_weight(view, depth_texture, normal_texture, x, p, n, bracket_texel(b, 3), low_dims, reach),
    );
    return b;
}

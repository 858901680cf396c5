// Joint bilateral upsampling of a half-resolution occlusion buffer (Reinbothe, Boubekeur & Alexa
// 2009, §7, eq. 5–7): each full-resolution pixel x averages the low-resolution texels y of a
// window around it, weighted by the Wendland kernel (eq. 3) over screen distance, normal
// difference and the texel's distance from the pixel's tangent plane (in place of the paper's
// world distance: `plane_surface_weight`), without the paper's AO difference (`weight`).
// One invocation upsamples the 2 × 2 pixels of one texel, reading the texels of the 3 × 3 around
// it once for the four (their depth, normal, position and value), and each pixel blends those
// within 2.5 pixels of it (`gather_quad`). They reach past the 2 × 2 that bracket the pixel, and
// average the accumulated noise over a wider footprint where the guides agree (converged
// high-frequency error 9–13% lower on flat scenes, none higher on DamagedHelmet; BENCHMARKS.md,
// "The default runs no blur"). The quad's first pixel is the texel's own. With VISIBILITY it
// writes the texture Bevy's PBR reads, as compose would have (`DynamicAoView::filter_is_last`).
// With GUIDE_TEXELS it reads the temporal
// pass's history of this frame, whose texels carry their linear depth and normal beside the
// occlusion: one read per texel instead of three, and no unprojection (the guide's normal is then
// 8-bit). With WRITE_NORMALS it also copies each pixel's front-layer normal, as read, into
// `blur_normals`, which the blur weighs by (`DynamicAoTextures::blur_normal`).
// With GUIDE_TEXELS and the ray march's fine-detail term on, a pixel between texels that lies
// below the surface they span also joins the term as the texels around it give it
// (`sub_texel_detail`).
// `reference::filter` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position, position_in_view, position_at_linear_depth, linear_depth, pixel_world_size}
#import bevy_dynamic_ao::uniform::DynamicAoUniform
#import bevy_dynamic_ao::filter_output::store_filtered
#import bevy_dynamic_ao::joint_upsample::{Guide, texel_guide, screen_weight, plane_surface_weight, normal_weight}
#import bevy_dynamic_ao::history::unpack_history
#import bevy_dynamic_ao::fine_detail::{with_fine_detail, rise, detail_reach_world}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> settings: DynamicAoUniform;
@group(0) @binding(2) var depth_texture: texture_depth_2d;
@group(0) @binding(3) var normal_texture: texture_2d<f32>;
#ifdef GUIDE_TEXELS
// `HistoryTexel`s of one channel, which `temporal.wgsl` writes.
@group(0) @binding(4) var low: texture_2d<u32>;
#else
@group(0) @binding(4) var low: texture_2d<f32>;
#endif
// Binding 5 is `output` (`shaders/filter_output.wgsl`).
#ifdef WRITE_NORMALS
@group(0) @binding(6) var blur_normals: texture_storage_2d<rgba16float, write>;
#endif

// Writes pixel `x`'s upsampled `value`, and with WRITE_NORMALS its front-layer normal as
// `normal_texture` encodes it.
fn store(x: vec2<i32>, value: vec2<f32>, encoded_normal: vec3<f32>) {
    store_filtered(settings, x, value, textureDimensions(depth_texture));
#ifdef WRITE_NORMALS
    textureStore(blur_normals, x, vec4<f32>(encoded_normal, 0.0));
#endif
}

#ifndef GUIDE_TEXELS
// The channels a texel of `low` carries.
fn low_value(l: vec2<i32>) -> vec2<f32> {
#ifdef TWO_CHANNELS
    return textureLoad(low, l, 0).rg;
#else
    return vec2<f32>(textureLoad(low, l, 0).r, 0.0);
#endif
}
#endif

// One texel of `low`: where it was computed, and its channels.
struct Texel {
    guide: Guide,
    value: vec2<f32>,
}

fn texel(l: vec2<i32>, low_dims: vec2<i32>) -> Texel {
#ifdef GUIDE_TEXELS
    let h = unpack_history(textureLoad(low, clamp(l, vec2<i32>(0), low_dims - 1), 0));
    let y = l * 2;
    let dims = vec2<f32>(textureDimensions(depth_texture));
    let on_surface = all(l >= vec2<i32>(0)) && all(l < low_dims) && h.depth > 0.0;
    let p = position_at_linear_depth(view, (vec2<f32>(y) + 0.5) / dims, h.depth);
    let g = Guide(y, p, h.normal, on_surface);
    // A texel off the buffer has no weight; its value is never read.
    return Texel(g, vec2<f32>(bitcast<f32>(h.value), 0.0));
#else
    let g = texel_guide(view, depth_texture, normal_texture, l, low_dims);
    // A texel off the buffer has no weight; its value is never read.
    return Texel(g, low_value(clamp(l, vec2<i32>(0), low_dims - 1)));
#endif
}

// The surface a full-resolution pixel shows, in the space the texels' guides are in: view space
// where they come from linear depths, world space where from the ND-buffer (distances are the same
// in both).
struct Pixel {
    p: vec3<f32>,
    // World-space unit normal, as the guides' normals are.
    n: vec3<f32>,
    // The same normal in the guides' space, for the distance to the pixel's tangent plane.
    plane_n: vec3<f32>,
    // World size of the pixel at its depth, metres.
    footprint: f32,
}

// Pixel `x` at reverse-Z `depth` with world-space unit normal `n`.
fn pixel_at(x: vec2<i32>, dims: vec2<i32>, depth: f32, n: vec3<f32>) -> Pixel {
    let footprint = pixel_world_size(view, linear_depth(view, depth), f32(dims.y));
#ifdef GUIDE_TEXELS
    let p = position_in_view(view, (vec2<f32>(x) + 0.5) / vec2<f32>(dims), depth);
    let plane_n = (view.view_from_world * vec4<f32>(n, 0.0)).xyz;
    return Pixel(p, n, plane_n, footprint);
#else
    return Pixel(world_position(view, x, vec2<f32>(dims), depth), n, n, footprint);
#endif
}

// The pixel a texel was computed at (quad pixel 0), as its guide `g` holds it: its own texel
// then weighs 1 on the surface terms.
fn own_pixel(g: Guide, x: vec2<i32>, dims: vec2<i32>) -> Pixel {
#ifdef GUIDE_TEXELS
    let footprint = pixel_world_size(view, -g.p.z, f32(dims.y));
    return Pixel(g.p, g.n, (view.view_from_world * vec4<f32>(g.n, 0.0)).xyz, footprint);
#else
    let footprint =
        pixel_world_size(view, linear_depth(view, textureLoad(depth_texture, x, 0)), f32(dims.y));
    return Pixel(g.p, g.n, g.n, footprint);
#endif
}

// The weight of texel `t` for pixel `x`; `screen` is w_d of the texel's distance to the pixel.
// No weight on the difference of occlusion from the quad's own texel (the paper's fourth term,
// support 1): it held back the texels whose noise differed most from the own texel's, so the
// average kept more of it, and without it the converged error was the same or lower on all eleven
// scenes measured (BENCHMARKS.md, "The upsampling against the pixel's plane").
fn weight(t: Texel, screen: f32, x: Pixel) -> f32 {
    return screen * plane_surface_weight(t.guide, x.p, x.n, x.plane_n, x.footprint);
}

// The texels around one texel `oo` that a pixel of its quad blends, named by their offsets
// (m = −1, o = 0, p = +1; x first). The corner (−1, −1) lies 2.8 pixels or more from all four
// pixels and counts for none (see `gather_quad`). No arrays: CPU rasterizers spill those to
// memory.
struct Window {
    om: Texel,
    pm: Texel,
    mo: Texel,
    oo: Texel,
    po: Texel,
    mp: Texel,
    op: Texel,
    pp: Texel,
}

// What a quad pixel gathers from the texels of its window: the weighted channels with the weights
// in z, and the highest rise on each side of the pixel (+x, −x, +y, −y) for the fine-detail term
// between the texels (`sub_texel_detail`; zero where it is not gathered).
struct Gathered {
    sum: vec3<f32>,
    highest: vec4<f32>,
}

// `g` with texel `t`, `offset` full-resolution pixels from the pixel `x`, added: its weight, w_d
// of the offset's length times the surface terms, and where `reach_world` (metres) is above 0 its
// rise on the sides it lies on. The rise is weighted by w_n, so only texels facing the pixel's way
// count: a wall beside a floor rises above the floor's pixels, but its occlusion is already in the
// floor's texels, whose own rays and term saw it.
fn gather(g: Gathered, t: Texel, offset: vec2<i32>, x: Pixel, reach_world: f32) -> Gathered {
    let w = weight(t, screen_weight(length(vec2<f32>(offset))), x);
    var out = Gathered(g.sum + vec3<f32>(w * t.value, w), g.highest);
#ifdef GUIDE_TEXELS
    if reach_world > 0.0 && t.guide.on_surface {
        let r = rise(t.guide.p - x.p, x.plane_n, reach_world) * normal_weight(t.guide, x.n);
        let ahead = offset > vec2<i32>(0);
        let behind = offset < vec2<i32>(0);
        let sides = vec4<bool>(ahead.x, behind.x, ahead.y, behind.y);
        out.highest = max(out.highest, select(vec4<f32>(0.0), vec4<f32>(r), sides));
    }
#endif
    return out;
}

// What quad pixel `quad` (0 the texel's own, 1 right of it, 2 below, 3 diagonal), showing the
// surface `x`, gathers (`gather`): the texels less than 2.5 pixels away (5, 6, 6 and 4 of the
// 3 × 3), each named once with its offset from the pixel. w_d of those farther is under 0.03,
// against 0.4–1 for the nearest, and skipping them spares 15 of 36 weights a quad. The rises are
// gathered over the same texels, for pixels 1–3 only, and only where `reach_world` is above 0.
// `reference::filter` adds the same texels in another order, which moves the last bits only.
fn gather_quad(quad: u32, x: Pixel, w: Window, reach_world: f32) -> Gathered {
    var g = Gathered(vec3<f32>(0.0), vec4<f32>(0.0));
    switch quad {
        case 0u: {
            g = gather(g, w.oo, vec2<i32>(0, 0), x, 0.0);
            g = gather(g, w.om, vec2<i32>(0, -2), x, 0.0);
            g = gather(g, w.mo, vec2<i32>(-2, 0), x, 0.0);
            g = gather(g, w.po, vec2<i32>(2, 0), x, 0.0);
            g = gather(g, w.op, vec2<i32>(0, 2), x, 0.0);
        }
        case 1u: {
            g = gather(g, w.oo, vec2<i32>(-1, 0), x, reach_world);
            g = gather(g, w.po, vec2<i32>(1, 0), x, reach_world);
            g = gather(g, w.om, vec2<i32>(-1, -2), x, reach_world);
            g = gather(g, w.pm, vec2<i32>(1, -2), x, reach_world);
            g = gather(g, w.op, vec2<i32>(-1, 2), x, reach_world);
            g = gather(g, w.pp, vec2<i32>(1, 2), x, reach_world);
        }
        case 2u: {
            g = gather(g, w.oo, vec2<i32>(0, -1), x, reach_world);
            g = gather(g, w.op, vec2<i32>(0, 1), x, reach_world);
            g = gather(g, w.mo, vec2<i32>(-2, -1), x, reach_world);
            g = gather(g, w.mp, vec2<i32>(-2, 1), x, reach_world);
            g = gather(g, w.po, vec2<i32>(2, -1), x, reach_world);
            g = gather(g, w.pp, vec2<i32>(2, 1), x, reach_world);
        }
        default: {
            g = gather(g, w.oo, vec2<i32>(-1, -1), x, reach_world);
            g = gather(g, w.po, vec2<i32>(1, -1), x, reach_world);
            g = gather(g, w.op, vec2<i32>(-1, 1), x, reach_world);
            g = gather(g, w.pp, vec2<i32>(1, 1), x, reach_world);
        }
    }
    return g;
}

// The blended channels of `g`, or the quad's own texel's where no texel of the window `w` lies on
// the pixel's surface.
fn blended(g: Gathered, w: Window) -> vec2<f32> {
    return select(w.oo.value, g.sum.xy / g.sum.z, g.sum.z > 0.0);
}

#ifdef GUIDE_TEXELS
// How far below the surface of its bracketing texels a pixel must lie, in its footprints, for
// `sub_texel_detail` to count at all, and from how much deeper it counts in full.
const SUNKEN_FROM: f32 = 0.1;
const SUNKEN_RAMP: f32 = 0.4;

// How far quad pixel `quad` (1–3) showing `x` lies below the surface its bracketing texels span
// (their positions averaged as bilinear filtering weighs them), 0–1 (`SUNKEN_FROM`). A smooth
// surface, curved or not, runs through its texels, and its pixels keep the blend of theirs; a
// groove between them does not. Without this the term laid a grid over the bumpy ring's smooth
// dimples, whose pixels between texels see the texels around them rise a little (BENCHMARKS.md,
// "Grooves between the texels").
fn sunken(x: Pixel, quad: u32, w: Window) -> f32 {
    var spanned: vec3<f32>;
    var on_surface = w.oo.guide.on_surface;
    if quad == 1u {
        spanned = 0.5 * (w.oo.guide.p + w.po.guide.p);
        on_surface = on_surface && w.po.guide.on_surface;
    } else if quad == 2u {
        spanned = 0.5 * (w.oo.guide.p + w.op.guide.p);
        on_surface = on_surface && w.op.guide.on_surface;
    } else {
        spanned = 0.25 * (w.oo.guide.p + w.po.guide.p + w.op.guide.p + w.pp.guide.p);
        on_surface = on_surface && w.po.guide.on_surface && w.op.guide.on_surface
            && w.pp.guide.on_surface;
    }
    let depth = dot(spanned - x.p, x.plane_n) / x.footprint;
    return select(0.0, clamp((depth - SUNKEN_FROM) / SUNKEN_RAMP, 0.0, 1.0), on_surface);
}

// The fine-detail term (`shaders/fine_detail.wgsl`) of a quad pixel 1–3 from the highest rises
// `gather_quad` found on its sides among the texels it blends, in place of its full-resolution
// neighbours: their squares averaged over the four sides. The texels hold the march's term at
// their own pixels; a pixel between them, in a groove a pixel wide across a panel whose texels
// lie on either side, took the panel's occlusion (BENCHMARKS.md, "Grooves between the texels").
// `reference::fine_detail::sub_texel_detail` is the CPU twin.
fn sub_texel_detail(g: Gathered) -> f32 {
    return dot(g.highest, g.highest) * 0.25;
}
#endif

// Quad pixel `quad` (1–3, `gather_quad`), pixel `x` at `depth`, blended from the window `w`. One
// store whatever the pixel: lavapipe runs every branch under a mask, so a store in each branch
// costs every pixel (BENCHMARKS.md, "Workgroups along rows").
fn blend(x: vec2<i32>, quad: u32, dims: vec2<i32>, depth: f32, w: Window) {
    if any(x >= dims) {
        return;
    }
    var value = vec2<f32>(0.0);
    var encoded = vec3<f32>(0.0);
    if depth > 0.0 {
        encoded = textureLoad(normal_texture, x, 0).xyz;
        let px = pixel_at(x, dims, depth, decode_normal(encoded));
        var reach_world = 0.0;
#ifdef GUIDE_TEXELS
        if settings.march_detail_reach > 0u {
            reach_world = detail_reach_world(
                i32(settings.march_detail_reach),
                px.footprint,
                settings.image_space_radius,
            );
        }
#endif
        let g = gather_quad(quad, px, w, reach_world);
        value = blended(g, w);
#ifdef GUIDE_TEXELS
        if reach_world > 0.0 {
            let detail = sub_texel_detail(g) * sunken(px, quad, w);
            value.x = with_fine_detail(value.x, detail, settings.intensity);
        }
#endif
    }
    store(x, value, encoded);
}

// Rows of quads (`dispatch::Workgroup::Row`): on lavapipe most texels a quad reads are then in the
// cache from the quads before it in its row.
@compute @workgroup_size(64, 1, 1)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = vec2<i32>(textureDimensions(depth_texture));
    let low_dims = vec2<i32>(textureDimensions(low));
    let l = vec2<i32>(id.xy);
    let x = l * 2;
    if any(x >= dims) {
        return;
    }
    let w = Window(
        texel(l + vec2<i32>(0, -1), low_dims),
        texel(l + vec2<i32>(1, -1), low_dims),
        texel(l + vec2<i32>(-1, 0), low_dims),
        texel(l, low_dims),
        texel(l + vec2<i32>(1, 0), low_dims),
        texel(l + vec2<i32>(-1, 1), low_dims),
        texel(l + vec2<i32>(0, 1), low_dims),
        texel(l + vec2<i32>(1, 1), low_dims),
    );
    var value = vec2<f32>(0.0);
    var encoded = vec3<f32>(0.0);
    if w.oo.guide.on_surface {
#ifdef WRITE_NORMALS
        // The guide's own normal may be the history's 8-bit one; the blur gets the layer's.
        encoded = textureLoad(normal_texture, x, 0).xyz;
#endif
        value = blended(gather_quad(0u, own_pixel(w.oo.guide, x, dims), w, 0.0), w);
    }
    store(x, value, encoded);
    let x1 = x + vec2<i32>(1, 0);
    blend(x1, 1u, dims, textureLoad(depth_texture, min(x1, dims - 1), 0), w);
    let x2 = x + vec2<i32>(0, 1);
    blend(x2, 2u, dims, textureLoad(depth_texture, min(x2, dims - 1), 0), w);
    let x3 = x + vec2<i32>(1, 1);
    blend(x3, 3u, dims, textureLoad(depth_texture, min(x3, dims - 1), 0), w);
}

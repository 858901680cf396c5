// Ray-marched ambient occlusion through both ND-buffer layers (Bavoil & Sainz 2008,
// "Ray-Marched Ambient Occlusion"). `reference::ray_march` is the CPU twin.

#import bevy_dynamic_ao::image_space_bindings::{
    view, settings, front_depth, front_normal, back_depth, back_normal, receiver, Receiver,
    store_occlusion, copy_blur_normal, view_position,
}
#import bevy_render::view::ndc_to_uv
#import bevy_dynamic_ao::nd_buffer::{linear_depth, pixel_world_size, decode_normal}
#import bevy_dynamic_ao::sampling::{pixel_pattern, frame_jitter}
#import bevy_dynamic_ao::math::{TAU, tangent_frame}
#import bevy_dynamic_ao::fine_detail::{fine_detail, with_fine_detail}

// Whether the point at view-space depth `z` and clip-space position `clip` lies inside the
// geometry the two layers bound, less than `settings.ray_march_thickness` metres behind the
// back-face layer (less than `radius` behind a two-sided sheet), or behind a sheet thinner than
// a step (`step`, metres) that the previous step, at depth `previous_z`, lay in front of:
// 1 blocked, 0 free behind the front layer, 2 free in front of it (or where it holds nothing),
// −1 off the screen.
fn blocked(
    z: f32,
    previous_z: f32,
    step: f32,
    clip: vec4<f32>,
    size: vec2<f32>,
    dims: vec2<i32>,
    radius: f32,
) -> i32 {
    if clip.w <= 0.0 {
        return -1;
    }
    let ndc = clip.xyz / clip.w;
    let q = vec2<i32>(floor(ndc_to_uv(ndc.xy) * size));
    if any(q < vec2<i32>(0)) || any(q >= dims) {
        // The ray left the screen: nothing more is known along it.
        return -1;
    }
    let front = textureLoad(front_depth, q, 0);
    // Depths are compared as stored (reverse-Z: a larger depth is nearer), not as view-space z:
    // Bevy's projections map depth to view-space z alone, whatever the pixel, so the tests agree,
    // and most steps end at the first one without unprojecting anything. No tolerance in depth:
    // the rays' start height already keeps the receiver's own surface from blocking them, and a
    // tolerance (it was a hundredth of R) hid grooves shallower than it, many pixels wide at high
    // resolutions.
    if front <= 0.0 || ndc.z >= front {
        return 2;
    }
    let back = textureLoad(back_depth, q, 0);
    let front_z = -linear_depth(view, front);
    if back > 0.0 {
        if ndc.z > back {
            return 1;
        }
        // The layer holds only the nearest back face: behind it may be air or more of the
        // model (a shell's inner surface lies millimetres behind its outer one), so a step just
        // behind it counts as blocked (`RayMarchParams::thickness` says why).
        let back_z = -linear_depth(view, back);
        // Where the back face lies where the front one does (`TWO_SIDED_GAP`), the layer tells
        // nothing of what lies behind: the step is judged as where no back face was drawn.
        let two_sided = abs(front_z - back_z) < TWO_SIDED_GAP * -front_z;
        if back_z - z < select(settings.ray_march_thickness, radius, two_sided) {
            return 1;
        }
        // A sheet thinner than a step (a heat sink's fin): no step may land inside it, so a ray
        // through it shows only as a step in front and the next one behind.
        let crossed = front_z - back_z < step && previous_z >= front_z;
        return select(0, 1, crossed);
    }
    return select(0, 1, front_z - z < radius);
}

// How far, in view-space z, a ray's crossing of a sheet's plane may lie outside the sheet the
// layers hold where it crosses (`came_through_from_behind`), as a share of a step: the sheet is
// a plane only near the pixel that showed it.
const SHEET_TOLERANCE: f32 = 0.05;

// How far apart, as a share of their distance from the camera, the two layers may lie and still
// hold the same polygon: a two-sided sheet (a wall of one polygon with a double-sided material)
// is drawn into both at one depth, equal to a few ulps. Behind such a sheet the back layer tells
// nothing; counted as air beyond `RayMarchParams::thickness`, the CornellBox's ceiling, seen from
// above, hid its upper walls, and every ray from inside the room through them read as open (RMSE
// at 160×120, R = 0.73 m: 0.0684, 0.0475 with this; BENCHMARKS.md, "Behind a two-sided sheet").
// Either side of the front layer, not only behind it: the coarse copies' back faces
// (`DynamicAo::coarse_back_faces`) can lie in front of a model's surface, and a test of one side
// took them for sheets there and blocked rays up to R behind DamagedHelmet (0.0339 → 0.0350 at
// R = 2 m). Thin solids lie further apart: at 0.02 R the heat sink's 8 mm fins counted as
// sheets, and their error rose from 0.0676 to 0.0832.
const TWO_SIDED_GAP: f32 = 1e-4;

// Whether a ray now at view-space `point` (clip-space `point_clip`), in front of the surface the
// front layer shows there, came through that surface from behind since its previous step, at
// `previous` (`previous_clip`), `step` metres back: the surface is a sheet thinner than a step;
// `previous` lies behind the plane of its back face and `point` in front of the plane of its
// front face (both with the front layer's normal); and where the ray crosses the back face's
// plane, the front layer shows the sheet again. A ray from a heat sink's fin towards the camera
// goes through the next fin with no step inside it, from hidden to in front, and read as open:
// the fins' faces were lighter than the truth all over (RMSE at 640×480 0.0716, 0.0435 with
// this; BENCHMARKS.md, "Rays through a sheet towards the camera, in the default"). The sides are
// told by planes, not depths: the steps either side project to other pixels, and across a sheet
// seen at a grazing angle the depth changes faster than along the ray. The sheet must be thin:
// without the back face, rays from the valleys of a bumpy ring crossed the tangent planes of the
// bumps before them and darkened the valleys. The crossing is checked because the plane runs on
// past the sheet's edges: with the plane alone, rays passing beside CesiumMan's limbs counted as
// blocked. The march tests one step a ray, after its loop (the first in front of the front layer
// after the start or a hidden step): tested at every step in front, the test doubled the march's
// time on lavapipe, which runs every branch; once a ray it costs about a fifth more there.
fn came_through_from_behind(
    point: vec3<f32>,
    previous: vec3<f32>,
    point_clip: vec4<f32>,
    previous_clip: vec4<f32>,
    step: f32,
    size: vec2<f32>,
) -> bool {
    let q = vec2<i32>(floor(ndc_to_uv(point_clip.xy / point_clip.w) * size));
    let front = textureLoad(front_depth, q, 0);
    let back = textureLoad(back_depth, q, 0);
    if front <= 0.0 || back <= 0.0 {
        return false;
    }
    // The two faces where the line of sight through `point` meets them, as the pixel holds them.
    let orthographic = view.clip_from_view[3][3] == 1.0;
    let f = along_sight(point, -linear_depth(view, front), orthographic);
    let b = along_sight(point, -linear_depth(view, back), orthographic);
    let world_normal = decode_normal(textureLoad(front_normal, q, 0).xyz);
    let up = facing_the_eye((view.view_from_world * vec4<f32>(world_normal, 0.0)).xyz, f);
    let before = dot(previous - b, up);
    let after = dot(point - b, up);
    if !(dot(f - b, up) < step && before < 0.0 && dot(point - f, up) > 0.0) {
        return false;
    }
    // Clip space is linear along the ray.
    let share = before / (before - after);
    let crossing_z = mix(previous.z, point.z, share);
    let c = mix(previous_clip, point_clip, share);
    let at = vec2<i32>(floor(ndc_to_uv(c.xy / c.w) * size));
    if c.w <= 0.0 || any(at < vec2<i32>(0)) || any(at >= vec2<i32>(size)) {
        return false;
    }
    let front_there = textureLoad(front_depth, at, 0);
    if front_there <= 0.0 {
        return false;
    }
    // The sheet there, as deep along the line of sight as at `q`.
    let front_z = -linear_depth(view, front_there);
    let back_z = front_z - (f.z - b.z);
    let tolerance = SHEET_TOLERANCE * step;
    return crossing_z <= front_z + tolerance && crossing_z >= back_z - tolerance;
}

// The view-space normal `m` of the surface at view-space `p`, turned to the side the camera sees.
fn facing_the_eye(m: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    let orthographic = view.clip_from_view[3][3] == 1.0;
    let to_eye = select(-p, vec3<f32>(0.0, 0.0, 1.0), orthographic);
    return select(m, -m, dot(m, to_eye) < 0.0);
}

// The point at view-space depth `z` on the line of sight through view-space `p`.
fn along_sight(p: vec3<f32>, z: f32, orthographic: bool) -> vec3<f32> {
    return vec3<f32>(p.xy * select(z / p.z, 1.0, orthographic), z);
}

// The share of the way from the last step on screen to the edge crossing that `edge_crossing`
// returns: at the crossing itself the point may project a rounding past the edge.
const INSIDE_THE_EDGE: f32 = 0.999;

// How far along the ray (from view-space origin at clip-space `clip`, clip-space direction
// `clip_dir`), between `on_screen` (a step on screen) and `left_at` (the next, off it), its image
// leaves the screen, a little short of that: where the first of w − x, w + x, w − y and w + y,
// each linear along the ray, falls to zero (a step past the camera's plane has no image, but the
// ray's image leaves the screen before it gets there). The march judges the ray there as at a
// step, since the steps either side can lie far apart: from a counter's front face, a ray down
// towards the camera passes under the floor in front of it, on screen, and its next step
// projects below the view. Judged only past the edge, where it had met the floor's plane on
// screen, it read as open, and the face lighter than the truth (`toasters.glb` at R = 2 m: RMSE
// 0.0382, 0.0214 with this; BENCHMARKS.md, "A ray judged where it leaves the screen").
fn edge_crossing(clip: vec4<f32>, clip_dir: vec4<f32>, on_screen: f32, left_at: f32) -> f32 {
    let start = clip.wwww + vec4<f32>(-clip.x, clip.x, -clip.y, clip.y);
    let rate = clip_dir.wwww + vec4<f32>(-clip_dir.x, clip_dir.x, -clip_dir.y, clip_dir.y);
    let falling = rate < vec4<f32>(0.0);
    let zero = select(vec4<f32>(left_at), -start / select(vec4<f32>(-1.0), rate, falling), falling);
    let t = clamp(min(min(zero.x, zero.y), min(zero.z, zero.w)), on_screen, left_at);
    return mix(on_screen, t, INSIDE_THE_EDGE);
}

// Whether the ray from view-space `origin` along unit `dir` (clip-space `clip` and `clip_dir`),
// whose image reached the screen's edge at distance `edge` (`edge_crossing`), is blocked within
// `radius` by the surface at the screen's edge there, continued as that surface's tangent
// plane. What lies past the edge is not in the ND-buffer; counted as open,
// a floor running out of the view left a plate beside the edge without the floor's occlusion
// (0.26 occluded against the truth's 0.40; 0.37 with the plane). The plane counts only where the
// ray meets it off screen: on screen the layers say what is there. A convex surface lies behind
// its tangent planes, so a ray leaving it never crosses one from the front.
fn beyond_the_edge(
    origin: vec3<f32>,
    dir: vec3<f32>,
    clip: vec4<f32>,
    clip_dir: vec4<f32>,
    edge: f32,
    radius: f32,
    size: vec2<f32>,
    dims: vec2<i32>,
) -> bool {
    // Clip space is linear along the ray, as in the march.
    let exit = clip + clip_dir * edge;
    if exit.w <= 0.0 {
        // Only a ray through the eye itself reaches the edge there.
        return false;
    }
    let pixel = clamp(vec2<i32>(floor(ndc_to_uv(exit.xy / exit.w) * size)), vec2<i32>(0), dims - 1);
    let depth = textureLoad(front_depth, pixel, 0);
    let world_normal = decode_normal(textureLoad(front_normal, pixel, 0).xyz);
    if depth <= 0.0 || all(world_normal == vec3<f32>(0.0)) {
        return false;
    }
    let e = view_position(pixel, size, depth);
    // The side of the plane the camera is on is the open one.
    let up = facing_the_eye((view.view_from_world * vec4<f32>(world_normal, 0.0)).xyz, e);
    let start = dot(origin + dir * edge - e, up);
    let end = dot(origin + dir * radius - e, up);
    if !(start > 0.0 && end < 0.0) {
        return false;
    }
    let meet = clip + clip_dir * (edge + (radius - edge) * start / (start - end));
    if meet.w <= 0.0 {
        return true;
    }
    let uv = ndc_to_uv(meet.xy / meet.w);
    return any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0));
}

// Where step `s` of `steps` samples a ray, metres along it, and how far it lies from the step
// before (x, y): `offset` (0–1) of a `step` (R / steps) into its stride, and the last at R
// itself. A ray's samples then reach R whatever the offset. With the last in its stride too, a
// surface the ray met after it went unseen: a floor met in the last stride, as rays from a box's
// upright faces and from a floor beside a wall meet it, was missed on the frames whose offset
// put the last sample before it (a share f of them for a surface at (steps − 1 + f) steps), and
// such faces read lighter than the truth (RMSE on `toasters.glb` 0.0210 with that, 0.0170 with
// this; BENCHMARKS.md, "The march reaches R"). Branch-free: CPU rasterizers run every branch of
// a loop's body on every step.
fn step_at(s: u32, steps: u32, offset: f32, step: f32, radius: f32) -> vec2<f32> {
    let last = s + 1u == steps;
    let t = select((f32(s) + offset) * step, radius, last);
    let stride = select(step, radius - (f32(s) - 1.0 + offset) * step, last);
    return vec2<f32>(t, stride);
}

// How far above the surface at view-space `p` with normal `n` rays start, metres, where a pixel
// there is `footprint` wide. Across half a pixel a surface whose normal makes the angle θ with the
// direction to the eye changes depth along the view ray by (footprint / 2) tan θ, and a point at
// height h above it lies h / cos θ nearer: a step lower than (footprint / 2) sin θ can read as
// behind the depth at the centre of the pixel it projects to (a floor far off, seen at a grazing
// angle, would occlude itself). Rays start at twice that. On a surface facing the camera that is
// almost on it, so they start inside grooves a pixel wide (a model's panel lines) instead of a
// whole pixel above them.
fn start_height(p: vec3<f32>, n: vec3<f32>, footprint: f32) -> f32 {
    let orthographic = view.clip_from_view[3][3] == 1.0;
    let to_eye = select(normalize(-p), vec3<f32>(0.0, 0.0, 1.0), orthographic);
    let cos_view = min(abs(dot(n, to_eye)), 1.0);
    return footprint * sqrt(1.0 - cos_view * cos_view);
}

@compute @workgroup_size(8, 8, 1)
fn ray_march(@builtin(global_invocation_id) invocation: vec3<u32>) {
    // With the checkerboard (`RayMarchParams::checkerboard`) the dispatch covers half the
    // columns, and invocation x marches texel 2x or 2x + 1, whichever agrees in parity with
    // y + frame (`temporal.wgsl` tells the two apart the same way). A texel is marched every
    // other frame, so it moves along the sample sequence every other frame: each of its marches
    // takes the next pattern, and the fine-detail term the next side.
    var texel = invocation;
    var sequence = settings.frame_index;
    if settings.ray_march_checkerboard != 0u {
        texel.x = invocation.x * 2u + ((invocation.y + settings.frame_index) & 1u);
        sequence = (settings.frame_index >> 1u) + 1u;
        // The blur, where it runs, reads every pixel's normal.
        copy_blur_normal(vec2<i32>(i32(texel.x ^ 1u), i32(texel.y)));
    }
    let r = receiver(texel);
    var value = 0.0;
    if r.shade {
        value = march(r, sequence);
    }
    store_occlusion(r, value);
}

// The rays' occlusion at receiver `r`, which has a surface, and under accumulation its fine-detail
// term's; `sequence` is the receiver's place in its sample sequence.
fn march(r: Receiver, sequence: u32) -> f32 {
    // The march works in view space.
    let p = r.view_position;
    let n = r.view_normal;
    let dims = vec2<i32>(r.size);
    let frame = tangent_frame(n);
    let t1 = frame[0];
    let t2 = frame[1];

    let radius = settings.image_space_radius;
    let pattern = pixel_pattern(r.pixel, 0x2c1b3c6du, sequence);
    let rotation = pattern.rotation;
    let jitter = pattern.jitter;
    // Where along each step a sample sits: under accumulation it moves every frame, so a few
    // steps per frame add up to a fine march.
    let step_offset = frame_jitter(pattern.hash, sequence);
    let origin = p + n * start_height(p, n, pixel_world_size(view, -p.z, r.size.y));
    let clip = view.clip_from_view * vec4<f32>(origin, 1.0);
    let step = radius / f32(settings.ray_march_steps);
    let directions = settings.ray_march_directions;
    let elevations = settings.ray_march_elevations;
    var hits = 0u;
    // One loop over the rays, not one over directions around one over elevations: with the
    // march's loop of steps and its breaks inside, lavapipe spent about a sixth more of the
    // march's time on the nested pair, for the same rays in the same order and the same image
    // bit for bit (BENCHMARKS.md, "One loop over the rays").
    for (var k = 0u; k < directions * elevations; k++) {
        let i = k / elevations;
        let j = k % elevations;
        let phi = (f32(i) + rotation) * TAU / f32(directions);
        // Cosine-weighted: sin²θ uniform in [0, 1).
        let u = (f32(j) + jitter) / f32(elevations);
        let sin_theta = sqrt(u);
        let cos_theta = sqrt(1.0 - u);
        let dir = t1 * (sin_theta * cos(phi)) + t2 * (sin_theta * sin(phi)) + n * cos_theta;
        // Clip space is linear in view space: each step adds to the receiver's clip position.
        let clip_dir = view.clip_from_view * vec4<f32>(dir, 0.0);
        // How far the ray got on screen, and where it left it (`beyond_the_edge`).
        var on_screen = 0.0;
        var left_at = -1.0;
        var hit = false;
        // The first step in front of the front layer after the start or a hidden step
        // (`came_through_from_behind`); `ray_march_steps` while there is none.
        var sheet = settings.ray_march_steps;
        var was_hidden = true;
        for (var s = 0u; s < settings.ray_march_steps; s++) {
            let at = step_at(s, settings.ray_march_steps, step_offset, step, radius);
            let t = at.x;
            let z = origin.z + dir.z * t;
            let previous_z = origin.z + dir.z * max(t - at.y, 0.0);
            let state = blocked(z, previous_z, at.y, clip + clip_dir * t, r.size, dims, radius);
            sheet = select(sheet, s, state == 2 && was_hidden && sheet == settings.ray_march_steps);
            was_hidden = state == 0;
            if state == 1 || state == -1 {
                hit = state == 1;
                left_at = select(-1.0, t, state == -1);
                break;
            }
            on_screen = t;
        }
        // Once per ray, after its loop: CPU rasterizers run a branch inside the loop for
        // every step.
        if !hit && (sheet < settings.ray_march_steps || left_at >= 0.0) {
            let at = step_at(sheet, settings.ray_march_steps, step_offset, step, radius);
            let before = max(at.x - at.y, 0.0);
            // The ray at the screen's edge is judged as a step: what it passed on screen after
            // its last step there.
            let edge = edge_crossing(clip, clip_dir, on_screen, max(left_at, on_screen));
            let z = origin.z + dir.z * edge;
            let on_screen_z = origin.z + dir.z * on_screen;
            hit = (sheet < settings.ray_march_steps && came_through_from_behind(
                origin + dir * at.x,
                origin + dir * before,
                clip + clip_dir * at.x,
                clip + clip_dir * before,
                at.y,
                r.size,
            )) || (left_at >= 0.0
                && (blocked(z, on_screen_z, edge - on_screen, clip + clip_dir * edge, r.size, dims, radius) == 1
                || beyond_the_edge(origin, dir, clip, clip_dir, edge, radius, r.size, dims)));
        }
        hits += u32(hit);
    }
    var value = settings.intensity * f32(hits) / f32(directions * elevations);
    // Under accumulation, the fine-detail term (`AoBlur::detail_reach`) of one side a frame:
    // the term is the mean of its four sides' and joins the rays' occlusion as
    // 1 − (1 − rays)(1 − term), linear in each, so the history's average over frames is the
    // whole term's, for a quarter of its reads.
    if settings.march_detail_reach > 0u {
        let reach = i32(settings.march_detail_reach);
        let side = i32(sequence & 3u);
        let detail =
            fine_detail(view, front_depth, r.pixel, r.depth, r.normal, reach, radius, side, 1);
        value = with_fine_detail(value, detail, settings.intensity);
    }
    return value;
}

// Ambient occlusion fields (Malmer et al. 2005, §3.1–3.3): for each occluder, the back faces of
// its grid box are drawn without depth test; each covered pixel rebuilds its world position from
// the ND-buffer, moves it into the grid and interpolates the stored occlusion a and average
// occluded direction d trilinearly, from grid points outside the object only (their signed
// distance is positive), so that a point on a thin object never mixes values from its two sides.
// The object's own surface gets only what lies beyond the near field's reach: the occlusion fades
// out over the half cell next to it, by the interpolated signed distance, where the receiver lies
// along that surface (a surface touching the object across it keeps all of it), and the near field
// shades that surface within its reach; beyond it, the share the grid points next to the surface
// baked over their nearest surface point's hemisphere fades in, from the points whose surface faces
// the way the receiver does (so a thin object's two sides stay apart). a and d become the share of
// ambient light blocked: 2a (occlusion only, §3.2) or the cone of fraction a around d
// clipped by the receiver's tangent plane (T_clip of §3.3.1, `cap_occlusion`). The field holds
// them twice, for hits within R and within the near field's reach; under `FarFieldBlend::CountOnce`
// the near part goes to the red channel where the ND-buffer does not hold its occluders, the
// rest to the green one. Blending multiplies the field buffer by 1 − that (§3.3.2); the fields of
// objects that fill one another's bounds also go to blue and alpha where the receiver lies
// outside those bounds, for compose's union (`fields::join`). At half
// resolution (`DynamicAo::half_resolution`) each texel does so for one pixel of its 2 × 2 and
// compose upsamples the buffer.
// `reference::fields` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position, nd_buffer_holds}
#import bevy_dynamic_ao::cap_occlusion::{cap_occlusion, share_beyond}
#import bevy_dynamic_ao::uniform::{DynamicAoUniform, seen_by_view}
#import bevy_dynamic_ao::union_join::{joins_by_union, union_channels}

struct FieldInstance {
    // Unit cube [-1, 1]³ to world: places the grid box.
    world_from_box: mat4x4<f32>,
    // World to grid coordinates [0, 1]³.
    grid_from_world: mat4x4<f32>,
    // Mesh-space directions to world space (columns; w unused).
    world_from_mesh: mat3x4<f32>,
    // Cells per axis, and the first cell in `cells` (each cell is seven vec4).
    resolution: vec3<u32>,
    offset: u32,
    // x: how far from the object's surface its own surface's fade ends, mesh units; yzw: grid
    // units per mesh unit along each axis (resolution / box size).
    params: vec4<f32>,
    // xy: the occluder's RenderLayers as bits (`seen_by_view`).
    layers: vec4<u32>,
    // How the field joins the others (`fields::join`): the lower corner of its union's box with
    // the kind in w (0 independent, 1 union, 2 union outside the box), then the upper corner.
    union_bounds: array<vec4<f32>, 2>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> instances: array<FieldInstance>;
@group(0) @binding(2) var<storage, read> cells: array<vec4<f32>>;
@group(0) @binding(3) var front_depth: texture_depth_2d;
@group(0) @binding(4) var front_normal: texture_2d<f32>;
@group(0) @binding(5) var back_depth: texture_depth_2d;
@group(0) @binding(6) var<uniform> settings: DynamicAoUniform;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) instance: u32,
}

// The 12 triangles of the unit cube, counter-clockwise seen from outside.
const CUBE = array<vec3<f32>, 36>(
    vec3(1., -1., -1.), vec3(1., 1., -1.), vec3(1., 1., 1.), vec3(1., -1., -1.), vec3(1., 1., 1.), vec3(1., -1., 1.),
    vec3(-1., -1., 1.), vec3(-1., 1., 1.), vec3(-1., 1., -1.), vec3(-1., -1., 1.), vec3(-1., 1., -1.), vec3(-1., -1., -1.),
    vec3(-1., 1., -1.), vec3(-1., 1., 1.), vec3(1., 1., 1.), vec3(-1., 1., -1.), vec3(1., 1., 1.), vec3(1., 1., -1.),
    vec3(-1., -1., 1.), vec3(-1., -1., -1.), vec3(1., -1., -1.), vec3(-1., -1., 1.), vec3(1., -1., -1.), vec3(1., -1., 1.),
    vec3(-1., -1., 1.), vec3(1., -1., 1.), vec3(1., 1., 1.), vec3(-1., -1., 1.), vec3(1., 1., 1.), vec3(-1., 1., 1.),
    vec3(1., -1., -1.), vec3(-1., -1., -1.), vec3(-1., 1., -1.), vec3(1., -1., -1.), vec3(-1., 1., -1.), vec3(1., 1., -1.),
);

@vertex
fn vertex(
    @builtin(vertex_index) vertex_index: u32,
    @builtin(instance_index) instance_index: u32,
) -> VertexOutput {
    var cube = CUBE;
    let instance = instances[instance_index];
    let world = instance.world_from_box * vec4<f32>(cube[vertex_index], 1.0);
    var out: VertexOutput;
    out.position = view.clip_from_world * world;
    if !seen_by_view(settings, instance.layers.xy) {
        // Every corner on one point beyond the far plane: the box covers nothing.
        out.position = vec4<f32>(0.0, 0.0, 2.0, 1.0);
    }
    out.instance = instance_index;
    return out;
}

// The interpolated content of a field at one point.
struct FieldSample {
    // Occlusion a and average occluded direction (mesh space), hits within R.
    far: vec4<f32>,
    // The same within the near field's reach.
    near: vec4<f32>,
    // Mean offset to the points the near rays meet, mesh units.
    near_offset: vec3<f32>,
    // Signed distance to the object's surface, mesh units.
    signed_distance: f32,
    // On the object's own surface, the share of its hemisphere blocked beyond the near reach.
    own_surface: f32,
    // How far the receiver lies along the object's surface there: 1 where its normal is the
    // surface's (either side, the signed distance's gradient), 0 where it stands across it (a
    // wall standing on a floor).
    along: f32,
    // The cone's errors on the axis hemispheres +x, +y, +z and −x, −y, −z, within R and within
    // the near field's reach.
    far_positive: vec3<f32>,
    far_negative: vec3<f32>,
    near_positive: vec3<f32>,
    near_negative: vec3<f32>,
}

// Own-surface grid points whose surface normal is this close to the receiver's count.
const SAME_SIDE: f32 = 0.5;
// The receiver lies along the object's surface (its own) where the cosine between its normal and
// the surface's is above ALONG, and across it (another surface touching the object) below
// SIDEWAYS; a smooth step between.
const SIDEWAYS: f32 = 0.3;
const ALONG: f32 = 0.7;

// Trilinear interpolation between cell centres, clamped at the outer cells, over the corners
// outside the object (the signed distance over all eight; the own surface's share over those
// whose surface faces the way mesh-space normal `n` does).
fn sample_field(field: FieldInstance, uvw: vec3<f32>, n: vec3<f32>) -> FieldSample {
    let r = vec3<f32>(field.resolution);
    let g = clamp(uvw * r - 0.5, vec3<f32>(0.0), r - 1.0);
    let i0 = vec3<u32>(floor(g));
    let i1 = min(i0 + 1u, field.resolution - 1u);
    let f = g - vec3<f32>(i0);
    var out: FieldSample;
    out.far = vec4<f32>(0.0);
    out.near = vec4<f32>(0.0);
    out.near_offset = vec3<f32>(0.0);
    out.signed_distance = 0.0;
    out.own_surface = 0.0;
    out.along = 0.0;
    out.far_positive = vec3<f32>(0.0);
    out.far_negative = vec3<f32>(0.0);
    out.near_positive = vec3<f32>(0.0);
    out.near_negative = vec3<f32>(0.0);
    var outside = 0.0;
    var facing = 0.0;
    // The signed distance's gradient, per grid unit.
    var gradient = vec3<f32>(0.0);
    for (var corner = 0u; corner < 8u; corner++) {
        let pick = vec3<bool>((corner & 1u) != 0u, (corner & 2u) != 0u, (corner & 4u) != 0u);
        let c = select(i0, i1, pick);
        let w3 = select(1.0 - f, f, pick);
        let w = w3.x * w3.y * w3.z;
        let at = 7u * (field.offset + (c.z * field.resolution.y + c.y) * field.resolution.x + c.x);
        let distances = cells[at + 2u];
        out.signed_distance += w * distances.x;
        let own = cells[at + 3u];
        let same_side = dot(own.yzw, n) > SAME_SIDE;
        if same_side {
            facing += w;
            out.own_surface += w * own.x;
        }
        // d w / d g per axis: the corner's weight along the two other axes, signed by its side.
        let side = select(vec3<f32>(-1.0), vec3<f32>(1.0), pick);
        gradient += distances.x * side * vec3<f32>(w3.y * w3.z, w3.x * w3.z, w3.x * w3.y);
        if distances.x > 0.0 {
            outside += w;
            out.far += w * cells[at];
            out.near += w * cells[at + 1u];
            out.near_offset += w * distances.yzw;
            // +x, −x, +y, −y | +z, −z, near +x, −x | near +y, −y, +z, −z.
            let a = cells[at + 4u];
            let b = cells[at + 5u];
            let c = cells[at + 6u];
            out.far_positive += w * vec3<f32>(a.x, a.z, b.x);
            out.far_negative += w * vec3<f32>(a.y, a.w, b.y);
            out.near_positive += w * vec3<f32>(b.z, c.x, c.z);
            out.near_negative += w * vec3<f32>(b.w, c.y, c.w);
        }
    }
    if outside > 0.0 {
        out.far /= outside;
        out.near /= outside;
        out.near_offset /= outside;
        out.far_positive /= outside;
        out.far_negative /= outside;
        out.near_positive /= outside;
        out.near_negative /= outside;
    }
    if facing > 0.0 {
        out.own_surface /= facing;
    }
    // Per mesh unit: a grid unit spans 2 half_extent / resolution along each axis.
    let per_mesh = gradient * field.params.yzw;
    let length2 = dot(per_mesh, per_mesh);
    out.along = select(1.0, smoothstep(SIDEWAYS, ALONG, abs(dot(per_mesh, n)) * inverseSqrt(length2)), length2 > 1e-20);
    return out;
}

// The share of light a cone of fraction `a` of the sphere around mesh-space `d` blocks at a
// receiver with world normal `n` (mesh-space unit normal `n_mesh`), plus the baked corrections
// of the cone on the axis hemispheres (`positive`, `negative`) weighted by the squared components
// of `n_mesh`: exact where the receiver faces an axis (`fields::baker::axes`).
fn cone_occlusion(
    field: FieldInstance,
    a: f32,
    d: vec3<f32>,
    n: vec3<f32>,
    n_mesh: vec3<f32>,
    positive: vec3<f32>,
    negative: vec3<f32>,
) -> f32 {
#ifdef CONE
    let m = mat3x3<f32>(field.world_from_mesh[0].xyz, field.world_from_mesh[1].xyz, field.world_from_mesh[2].xyz);
    let axis = m * d;
    let length2 = dot(axis, axis);
    let cos_beta = select(0.0, dot(axis, n) * inverseSqrt(length2), length2 > 1e-12);
    let correction = dot(n_mesh * n_mesh, select(negative, positive, n_mesh >= vec3<f32>(0.0)));
    return clamp(cap_occlusion(1.0 - 2.0 * clamp(a, 0.0, 1.0), cos_beta) + correction, 0.0, 1.0);
#else
    return min(2.0 * a, 1.0);
#endif
}

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    // At half resolution texel l stands for pixel 2l (as `joint_upsample` expects).
    let pixel = vec2<i32>(floor(in.position.xy)) * i32(settings.far_resolution_scale);
    let depth = textureLoad(front_depth, pixel, 0);
    let normal = decode_normal(textureLoad(front_normal, pixel, 0).xyz);
    if depth <= 0.0 || all(normal == vec3<f32>(0.0)) {
        return vec4<f32>(0.0);
    }
    let p = world_position(view, pixel, vec2<f32>(textureDimensions(front_depth)), depth);
    let field = instances[in.instance];
    let uvw = (field.grid_from_world * vec4<f32>(p, 1.0)).xyz;
    if any(uvw < vec3<f32>(0.0)) || any(uvw > vec3<f32>(1.0)) {
        return vec4<f32>(0.0);
    }
    let m = mat3x3<f32>(field.world_from_mesh[0].xyz, field.world_from_mesh[1].xyz, field.world_from_mesh[2].xyz);
    // Normals go to mesh space by the transpose (the inverse of the inverse transpose).
    let n_mesh = normalize(normal * m);
    let s = sample_field(field, uvw, n_mesh);
    // Nothing from the field on the object's own surface, fading in over the half cell next to it.
    // Only the object's own surface fades: another object's surface that touches it (a wall
    // standing on a floor) faces another way and gets the field's full value there.
    let fade = 1.0 - s.along * (1.0 - smoothstep(0.0, field.params.x, s.signed_distance));
    let all = cone_occlusion(field, s.far.x, s.far.yzw, normal, n_mesh, s.far_positive, s.far_negative) * fade;
    let by_union = joins_by_union(field.union_bounds[0].w, field.union_bounds[0].xyz, field.union_bounds[1].xyz, p);
    let near = settings.near_field_radius;
    if near <= 0.0 {
        return union_channels(vec2<f32>(0.0, all), by_union);
    }
    let inner = cone_occlusion(field, s.near.x, s.near.yzw, normal, n_mesh, s.near_positive, s.near_negative) * fade;
    // The near part's occluders lie about its mean hit point.
    let at = p + m * s.near_offset;
    let held = nd_buffer_holds(view, front_depth, back_depth, settings.seen_back_layer != 0u, at, 0.1 * near);
    let beyond = min(share_beyond(all, inner) + s.own_surface * (1.0 - fade), 1.0);
    return union_channels(vec2<f32>(inner * (1.0 - held), beyond), by_union);
}

// Ambient occlusion fields (Malmer et al. 2005, §3.1–3.3): for each occluder, the back faces of
// its grid box are drawn without depth test; each covered pixel rebuilds its world position from
// the ND-buffer, moves it into the grid, interpolates occlusion a and the average occluded
// direction d trilinearly, and turns them into the share of ambient light blocked: 2a (occlusion
// only, §3.2) or T_clip(a, cos β) (cone, §3.3.1). Blending multiplies the field buffer by 1 − that
// (§3.3.2). `reference::fields` is the CPU twin.

#import bevy_render::view::View
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position}

struct FieldInstance {
    // Unit cube [-1, 1]³ to world: places the grid box.
    world_from_box: mat4x4<f32>,
    // World to grid coordinates [0, 1]³.
    grid_from_world: mat4x4<f32>,
    // Mesh-space directions to world space (columns; w unused).
    world_from_mesh: mat3x4<f32>,
    // Cells per axis, and the first cell in `cells`.
    resolution: vec3<u32>,
    offset: u32,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> instances: array<FieldInstance>;
@group(0) @binding(2) var<storage, read> cells: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> t_clip_table: array<f32>;
@group(0) @binding(4) var front_depth: texture_depth_2d;
@group(0) @binding(5) var front_normal: texture_2d<f32>;

const T_CLIP_SIZE: u32 = 32u;

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
    let world = instances[instance_index].world_from_box * vec4<f32>(cube[vertex_index], 1.0);
    var out: VertexOutput;
    out.position = view.clip_from_world * world;
    out.instance = instance_index;
    return out;
}

fn cell(field: FieldInstance, c: vec3<u32>) -> vec4<f32> {
    let r = field.resolution;
    return cells[field.offset + (c.z * r.y + c.y) * r.x + c.x];
}

// Trilinear interpolation between cell centres, clamped at the outer cells.
fn sample_field(field: FieldInstance, uvw: vec3<f32>) -> vec4<f32> {
    let r = vec3<f32>(field.resolution);
    let g = clamp(uvw * r - 0.5, vec3<f32>(0.0), r - 1.0);
    let i0 = vec3<u32>(floor(g));
    let i1 = min(i0 + 1u, field.resolution - 1u);
    let f = g - vec3<f32>(i0);
    let c00 = mix(cell(field, vec3(i0.x, i0.y, i0.z)), cell(field, vec3(i1.x, i0.y, i0.z)), f.x);
    let c10 = mix(cell(field, vec3(i0.x, i1.y, i0.z)), cell(field, vec3(i1.x, i1.y, i0.z)), f.x);
    let c01 = mix(cell(field, vec3(i0.x, i0.y, i1.z)), cell(field, vec3(i1.x, i0.y, i1.z)), f.x);
    let c11 = mix(cell(field, vec3(i0.x, i1.y, i1.z)), cell(field, vec3(i1.x, i1.y, i1.z)), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

fn t_clip(a: f32, cos_beta: f32) -> f32 {
    let n = f32(T_CLIP_SIZE - 1u);
    let x = clamp(a, 0.0, 1.0) * n;
    let y = (clamp(cos_beta, -1.0, 1.0) * 0.5 + 0.5) * n;
    let x0 = min(u32(floor(x)), T_CLIP_SIZE - 2u);
    let y0 = min(u32(floor(y)), T_CLIP_SIZE - 2u);
    let fx = x - f32(x0);
    let fy = y - f32(y0);
    let top = mix(t_clip_table[x0 * T_CLIP_SIZE + y0], t_clip_table[x0 * T_CLIP_SIZE + y0 + 1u], fy);
    let bottom = mix(t_clip_table[(x0 + 1u) * T_CLIP_SIZE + y0], t_clip_table[(x0 + 1u) * T_CLIP_SIZE + y0 + 1u], fy);
    return mix(top, bottom, fx);
}

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(floor(in.position.xy));
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
    let s = sample_field(field, uvw);
#ifdef CONE
    let axis = mat3x3<f32>(field.world_from_mesh[0].xyz, field.world_from_mesh[1].xyz, field.world_from_mesh[2].xyz) * s.yzw;
    let length2 = dot(axis, axis);
    let cos_beta = select(0.0, dot(axis, normal) * inverseSqrt(length2), length2 > 1e-12);
    let occlusion = t_clip(s.x, cos_beta);
#else
    let occlusion = min(2.0 * s.x, 1.0);
#endif
    return vec4<f32>(occlusion, 0.0, 0.0, 0.0);
}

// Occlusion of one far-field proxy, as the share of a receiver's ambient light it blocks within a
// distance `reach` (what ray-traced ground truth measures; `reach` ≤ 0: no limit).
//
// A box blocks the cosine-weighted solid angle of the faces it turns towards the receiver
// (outside a convex box these never overlap), each face clipped to the part a ray shorter than
// `reach` can meet and to the receiver's tangent plane, then integrated exactly with Lambert's
// formula for polygons: Σ_edges γ_i (n · ĝ_i) / 2π, γ_i the angle an edge subtends and ĝ_i the unit
// normal of the plane through it and the receiver. The part of a face within `reach` is a disk
// around the receiver's foot point; it is taken as the square of the same area, so that the
// clipped face stays a rectangle. A sphere (Shanmugam & Arikan 2007, §5) blocks a cone: the
// whole sphere when `reach` passes its tangent points, else the cap whose rays meet it within
// `reach` (by the law of cosines, cos γ = (reach² + d² − r²) / 2 d reach), through
// `cap_occlusion`. `reference::spheres` is the CPU twin.

#define_import_path bevy_dynamic_ao::proxy_occlusion

#import bevy_dynamic_ao::cap_occlusion::cap_occlusion
#import bevy_dynamic_ao::math::TAU
// √π / 2: half the side of the square with the area of the unit disk.
const SQUARE_OF_DISK: f32 = 0.886226925452758;

// The occlusion of one face and the centre of the part that counted.
struct FacePart {
    occlusion: f32,
    centre: vec3<f32>,
}

// One edge of Lambert's formula: the angle it subtends at `p` times the cosine between the
// normal `n` and the plane through `p` and the edge, over 2π (signed by the winding).
fn lambert_edge(p: vec3<f32>, n: vec3<f32>, start: vec3<f32>, end: vec3<f32>) -> f32 {
    let a = normalize(start - p);
    let b = normalize(end - p);
    let g = cross(a, b);
    let length_g = length(g);
    if length_g <= 1e-12 {
        return 0.0;
    }
    return atan2(length_g, dot(a, b)) * dot(n, g) / (length_g * TAU);
}

// The rectangle `centre` ± `u` ± `v` (half-extent vectors) on a face with outward unit normal
// `f`, which the receiver at `p` lies in front of.
fn face_occlusion(
    p: vec3<f32>,
    n: vec3<f32>,
    centre: vec3<f32>,
    f: vec3<f32>,
    u: vec3<f32>,
    v: vec3<f32>,
    reach: f32,
) -> FacePart {
    var part: FacePart;
    part.occlusion = 0.0;
    part.centre = centre;
    let hu = length(u);
    let hv = length(v);
    if hu <= 0.0 || hv <= 0.0 {
        return part;
    }
    let eu = u / hu;
    let ev = v / hv;
    var lo = vec2<f32>(-hu, -hv);
    var hi = vec2<f32>(hu, hv);
    if reach > 0.0 {
        let height = dot(f, p - centre);
        if height >= reach {
            return part;
        }
        let half = sqrt(reach * reach - height * height) * SQUARE_OF_DISK;
        let foot = p - f * height - centre;
        let q = vec2<f32>(dot(foot, eu), dot(foot, ev));
        lo = max(lo, q - half);
        hi = min(hi, q + half);
        if any(lo >= hi) {
            return part;
        }
    }
    part.centre = centre + eu * (0.5 * (lo.x + hi.x)) + ev * (0.5 * (lo.y + hi.y));
    let c0 = centre + eu * lo.x + ev * lo.y;
    let c1 = centre + eu * hi.x + ev * lo.y;
    let c2 = centre + eu * hi.x + ev * hi.y;
    let c3 = centre + eu * lo.x + ev * hi.y;
    let h = vec4<f32>(dot(n, c0 - p), dot(n, c1 - p), dot(n, c2 - p), dot(n, c3 - p));
    if all(h <= vec4<f32>(0.0)) {
        // Wholly below the tangent plane.
        return part;
    }
    // Sutherland–Hodgman against the tangent plane (what lies below cannot block), streamed
    // into Lambert's formula edge by edge: each kept or cut vertex closes an edge with the one
    // before it. Written out per edge: no arrays, which CPU rasterizers spill to memory.
    var polygon: Polygon;
    polygon.sum = 0.0;
    polygon.count = 0u;
    polygon = clip_edge(polygon, p, n, c0, c1, h.x, h.y);
    polygon = clip_edge(polygon, p, n, c1, c2, h.y, h.z);
    polygon = clip_edge(polygon, p, n, c2, c3, h.z, h.w);
    polygon = clip_edge(polygon, p, n, c3, c0, h.w, h.x);
    if polygon.count >= 3u {
        let sum = polygon.sum + lambert_edge(p, n, polygon.previous, polygon.first);
        part.occlusion = min(abs(sum), 1.0);
    }
    return part;
}

// A clipped polygon being integrated: Lambert's sum over its edges so far, its first and last
// vertices, and how many it has.
struct Polygon {
    sum: f32,
    first: vec3<f32>,
    previous: vec3<f32>,
    count: u32,
}

fn add_vertex(polygon: Polygon, p: vec3<f32>, n: vec3<f32>, x: vec3<f32>) -> Polygon {
    var out = polygon;
    if polygon.count == 0u {
        out.first = x;
    } else {
        out.sum += lambert_edge(p, n, polygon.previous, x);
    }
    out.previous = x;
    out.count += 1u;
    return out;
}

// The edge a → b (heights `ha`, `hb` over the tangent plane) of the polygon being clipped: `a`
// if above the plane, then the crossing if the edge crosses it.
fn clip_edge(
    polygon: Polygon,
    p: vec3<f32>,
    n: vec3<f32>,
    a: vec3<f32>,
    b: vec3<f32>,
    ha: f32,
    hb: f32,
) -> Polygon {
    var out = polygon;
    if ha > 0.0 {
        out = add_vertex(out, p, n, a);
    }
    if (ha > 0.0) != (hb > 0.0) {
        out = add_vertex(out, p, n, mix(a, b, ha / (ha - hb)));
    }
    return out;
}

// The outward unit normal of the face across box axis `i` (half-extent vector `a`), with `b` and
// `c` the other two. The face spans `b` and `c`, so its normal is b × c, turned to `a`'s side: a
// box moved by a skinned mesh's joints is sheared, `a` then leans off the normal, and a receiver
// on the face judged by `a` came out in front of a face that passes through it, which Lambert's
// formula then counts as a whole hemisphere (black pixels on the Fox's chest). A flat box has a
// zero `a`; a face with no area, a zero normal (nothing stands in front of it).
fn face_normal(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let g = cross(b, c);
    let length_g = length(g);
    if length_g <= 0.0 {
        return vec3<f32>(0.0);
    }
    return g * (select(1.0, -1.0, dot(g, a) < 0.0) / length_g);
}

// The cap of the sphere (`centre`, `radius`) whose rays from `p` meet it within `reach`.
fn sphere_occlusion_within(
    p: vec3<f32>,
    n: vec3<f32>,
    centre: vec3<f32>,
    radius: f32,
    reach: f32,
) -> f32 {
    let to_centre = centre - p;
    let d = length(to_centre);
    var cos_gamma = 0.0;
    if d > radius {
        cos_gamma = sqrt(1.0 - (radius / d) * (radius / d));
        if reach > 0.0 {
            if reach <= d - radius {
                return 0.0;
            }
            if reach * reach < d * d - radius * radius {
                cos_gamma = (reach * reach + d * d - radius * radius) / (2.0 * d * reach);
            }
        }
    }
    return cap_occlusion(cos_gamma, dot(n, to_centre) / max(d, 1e-12));
}

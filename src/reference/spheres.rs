//! Far-field occlusion of sphere occluders' proxies on the CPU, exactly as
//! `shaders/proxy_occlusion.wgsl` and `spheres/splat.wgsl` evaluate it: boxes by Lambert's formula
//! over the faces they turn towards the receiver, spheres by the cap within reach, each clipped to
//! a distance; proxies multiply their visibilities.

use std::f32::consts::TAU;

use bevy::math::{Mat3, Vec2, Vec3};

use super::nd_buffer::{NdBuffer, ViewMatrices};
use crate::geometry::cap::{cap_occlusion, share_beyond};
use crate::geometry::union::occluder_union;
use crate::spheres::join::proxy_joins;
use crate::spheres::{OccluderSphere, OccluderSpheres, ProxyReach, ProxyShape, far_field_reach};

/// √π / 2: half the side of the square with the area of the unit disk.
const SQUARE_OF_DISK: f32 = 0.886_226_9;

/// Lambert's formula over a convex polygon seen from `p` with normal `n`, all corners on or above
/// the tangent plane.
fn polygon_occlusion(p: Vec3, n: Vec3, corners: &[Vec3]) -> f32 {
    let mut sum = 0.0;
    for i in 0..corners.len() {
        let a = (corners[i] - p).normalize();
        let b = (corners[(i + 1) % corners.len()] - p).normalize();
        let g = a.cross(b);
        let length = g.length();
        if length > 1e-12 {
            sum += length.atan2(a.dot(b)) * n.dot(g) / length;
        }
    }
    (sum.abs() / TAU).min(1.0)
}

/// The occlusion of the rectangle `centre` ± `u` ± `v` on a face with outward unit normal `f`
/// within `reach` (≤ 0: no limit), and the centre of the part that counted.
pub fn face_occlusion(
    p: Vec3,
    n: Vec3,
    centre: Vec3,
    f: Vec3,
    (u, v): (Vec3, Vec3),
    reach: f32,
) -> (f32, Vec3) {
    let (hu, hv) = (u.length(), v.length());
    if hu <= 0.0 || hv <= 0.0 {
        return (0.0, centre);
    }
    let (eu, ev) = (u / hu, v / hv);
    let (mut lo, mut hi) = (Vec2::new(-hu, -hv), Vec2::new(hu, hv));
    if reach > 0.0 {
        let height = f.dot(p - centre);
        if height >= reach {
            return (0.0, centre);
        }
        let half = (reach * reach - height * height).sqrt() * SQUARE_OF_DISK;
        let foot = p - f * height - centre;
        let q = Vec2::new(foot.dot(eu), foot.dot(ev));
        lo = lo.max(q - half);
        hi = hi.min(q + half);
        if lo.x >= hi.x || lo.y >= hi.y {
            return (0.0, centre);
        }
    }
    let part = centre + eu * (0.5 * (lo.x + hi.x)) + ev * (0.5 * (lo.y + hi.y));
    let rect = [
        centre + eu * lo.x + ev * lo.y,
        centre + eu * hi.x + ev * lo.y,
        centre + eu * hi.x + ev * hi.y,
        centre + eu * lo.x + ev * hi.y,
    ];
    let mut clipped = Vec::with_capacity(5);
    for i in 0..4 {
        let (a, b) = (rect[i], rect[(i + 1) % 4]);
        let (ha, hb) = (n.dot(a - p), n.dot(b - p));
        if ha > 0.0 {
            clipped.push(a);
        }
        if (ha > 0.0) != (hb > 0.0) {
            clipped.push(a.lerp(b, ha / (ha - hb)));
        }
    }
    let occlusion = if clipped.len() >= 3 {
        polygon_occlusion(p, n, &clipped)
    } else {
        0.0
    };
    (occlusion, part)
}

/// The outward unit normal of the face across half-extent `a`, spanned by `b` and `c`
/// (`face_normal` in `proxy_occlusion.wgsl`, which says why it is b × c and not `a`).
fn face_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let g = b.cross(c);
    let sign = if g.dot(a) < 0.0 { -1.0 } else { 1.0 };
    g.normalize_or_zero() * sign
}

/// The cap of the sphere (`centre`, `radius`) whose rays from `p` meet it within `reach` (≤ 0: no
/// limit).
pub fn sphere_occlusion_within(p: Vec3, n: Vec3, centre: Vec3, radius: f32, reach: f32) -> f32 {
    let to_centre = centre - p;
    let d = to_centre.length();
    let mut cos_gamma = 0.0;
    if d > radius {
        cos_gamma = (1.0 - (radius / d) * (radius / d)).sqrt();
        if reach > 0.0 {
            if reach <= d - radius {
                return 0.0;
            }
            if reach * reach < d * d - radius * radius {
                cos_gamma = (reach * reach + d * d - radius * radius) / (2.0 * d * reach);
            }
        }
    }
    cap_occlusion(cos_gamma, n.dot(to_centre) / d.max(1e-12))
}

/// One proxy's occlusion of the receiver (`p`, `n`) within `reach` (≤ 0: no limit): the share of
/// its ambient light the proxy blocks, all of it counted.
pub fn proxy_occlusion(proxy: &OccluderSphere, p: Vec3, n: Vec3, reach: f32) -> f32 {
    proxy_channels(proxy, false, p, n, reach, 0.0, &HeldByNd::NOTHING)[1]
}

/// How far from its centre a proxy's occlusion reaches under `reach` with camera radius `radius`,
/// and the distance its rays count hits within (0: no limit).
fn influence(proxy: &OccluderSphere, reach: ProxyReach, radius: f32) -> (f32, f32) {
    match reach {
        ProxyReach::CameraRadius => (proxy.radius + radius, radius),
        ProxyReach::Epsilon(epsilon) => (far_field_reach(proxy.radius, epsilon), 0.0),
    }
}

/// What a camera brings to the proxies: its radius, and under `FarFieldBlend::CountOnce` the near
/// field's reach with the ND-buffer whose held geometry within it the near field counts (and
/// whether its back layer counts).
#[derive(Clone, Copy, Debug)]
pub struct ProxyCamera {
    /// The camera's radius R, metres.
    pub radius: f32,
    /// The near field's reach under CountOnce, metres; 0 where the far field counts everything.
    pub near_radius: f32,
    /// The back-face layer is drawn.
    pub use_back: bool,
}

/// The far field of sphere occluders at every pixel of the front layer of `nd`, row-major, in
/// compose's two channels after the union of [`occluder_union`]: the near field's share the
/// ND-buffer misses, and the rest (see `splat.wgsl`).
pub fn far_field_channels(
    nd: &NdBuffer,
    view: &ViewMatrices,
    occluders: &[OccluderSpheres],
    camera: &ProxyCamera,
) -> Vec<[f32; 2]> {
    let held = HeldByNd {
        point: &|x, tolerance| nd.holds(view, camera.use_back, x, tolerance),
        face: &|x, f| view.seen_face(x, f),
    };
    let joins = proxy_joins(occluders);
    nd.per_receiver(view, |receiver| {
        let (p, n) = (receiver.world_position, receiver.texel.normal);
        let (mut open, mut articulated_open, mut largest) = ([1.0f32; 2], 1.0f32, 0.0f32);
        for (occluder, join) in occluders.iter().zip(&joins) {
            let by_union = join.joins_at(p);
            for proxy in &occluder.spheres {
                let (extent, reach) = influence(proxy, occluder.reach, camera.radius);
                if p.distance(proxy.center) > extent {
                    continue;
                }
                let [a, b] =
                    proxy_channels(proxy, by_union, p, n, reach, camera.near_radius, &held);
                open[0] *= 1.0 - a;
                open[1] *= 1.0 - b;
                if by_union {
                    let both = 1.0 - (1.0 - a) * (1.0 - b);
                    articulated_open *= 1.0 - both;
                    largest = largest.max(both);
                }
            }
        }
        occluder_union([1.0 - open[0], 1.0 - open[1]], articulated_open, largest)
    })
}

/// The far field of sphere occluders alone, as compose writes it with the near field off:
/// 1 − (1 − near share)(1 − rest) of [`far_field_channels`].
pub fn far_field_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    occluders: &[OccluderSpheres],
    camera: &ProxyCamera,
) -> Vec<f32> {
    far_field_channels(nd, view, occluders, camera)
        .into_iter()
        .map(|[a, b]| 1.0 - (1.0 - a) * (1.0 - b))
        .collect()
}

/// What the ND-buffer holds, as [`proxy_channels`] asks it under count-once.
pub struct HeldByNd<'a> {
    /// How far the ND-buffer holds the geometry at world point `x` with a depth tolerance (m),
    /// 0–1 ([`NdBuffer::holds`]).
    pub point: &'a dyn Fn(Vec3, f32) -> f32,
    /// How fully the camera sees a box face at `x` with outward unit normal `f`, 0–1
    /// ([`ViewMatrices::seen_face`]).
    pub face: &'a dyn Fn(Vec3, Vec3) -> f32,
}

impl HeldByNd<'static> {
    /// Nothing held: the far field counts every part of a proxy.
    pub const NOTHING: Self = Self {
        point: &|_, _| 0.0,
        face: &|_, _| 0.0,
    };
}

/// One proxy's occlusion in the two channels `splat.wgsl` writes: the part within `near` (> 0)
/// the ND-buffer does not hold (by `held`; for the boxes that join the others `by_union` at the
/// receiver, nothing of a face from a receiver within 0.1 `near` of its plane), and the share of
/// the rest; with `near` ≤ 0, (0, all).
pub fn proxy_channels(
    proxy: &OccluderSphere,
    by_union: bool,
    p: Vec3,
    n: Vec3,
    reach: f32,
    near: f32,
    held: &HeldByNd,
) -> [f32; 2] {
    let tolerance = 0.1 * near;
    let centre = proxy.center;
    let clamp = |[a, b]: [f32; 2]| [a.clamp(0.0, 1.0), b.clamp(0.0, 1.0)];
    match proxy.shape {
        ProxyShape::Spheres => {
            let radius = proxy.axes.x_axis.length();
            let all = sphere_occlusion_within(p, n, centre, radius, reach);
            if near > 0.0 {
                let inner = sphere_occlusion_within(p, n, centre, radius, near);
                clamp([
                    inner * (1.0 - (held.point)(centre, radius + tolerance)),
                    share_beyond(all, inner),
                ])
            } else {
                clamp([0.0, all])
            }
        }
        ProxyShape::Boxes => {
            let axes: [Vec3; 3] = [proxy.axes.x_axis, proxy.axes.y_axis, proxy.axes.z_axis];
            let mut occlusion = [0.0f32; 2];
            let outside = Vec3::from_array(axes.map(|axis| {
                let half = axis.length();
                let along = if half > 0.0 {
                    (p - centre).dot(axis) / half
                } else {
                    0.0
                };
                (along.abs() - half).max(0.0)
            }));
            if reach > 0.0 && outside.length() >= reach {
                return occlusion;
            }
            let one_part = near > 0.0 && reach > 0.0 && reach <= near;
            let margin = 1e-4 + 1e-3 * proxy.radius;
            for i in 0..3 {
                let (a, b, c) = (axes[i], axes[(i + 1) % 3], axes[(i + 2) % 3]);
                let normal = face_normal(a, b, c);
                for side in [-1.0f32, 1.0] {
                    let f = normal * side;
                    let face_centre = centre + a * side;
                    if f.dot(p - face_centre) <= margin {
                        continue;
                    }
                    if near <= 0.0 {
                        occlusion[1] += face_occlusion(p, n, face_centre, f, (b, c), reach).0;
                        continue;
                    }
                    let inner_reach = if reach > 0.0 { near.min(reach) } else { near };
                    let (inner, at) = face_occlusion(p, n, face_centre, f, (b, c), inner_reach);
                    // One of several boxes filling one object: a receiver that near its face
                    // lies on the object's surface (`splat.wgsl`).
                    if inner > 0.0 && (!by_union || f.dot(p - face_centre) > tolerance) {
                        occlusion[0] +=
                            inner * (1.0 - (held.point)(at, tolerance) * (held.face)(at, f));
                    }
                    if !one_part {
                        let all = face_occlusion(p, n, face_centre, f, (b, c), reach).0;
                        occlusion[1] += share_beyond(all, inner);
                    }
                }
            }
            clamp(occlusion)
        }
    }
}

/// A box proxy from its centre and half-extent vectors (columns).
pub fn box_proxy(center: Vec3, axes: Mat3) -> OccluderSphere {
    OccluderSphere {
        center,
        radius: (axes.x_axis.length_squared()
            + axes.y_axis.length_squared()
            + axes.z_axis.length_squared())
        .sqrt(),
        axes,
        shape: ProxyShape::Boxes,
    }
}

#[cfg(test)]
mod tests {
    use crate::reference::near_field::sphere_occlusion;
    use crate::spheres::far_field_reach;
    use bevy::math::Affine3A;
    use bevy::prelude::*;

    use super::*;
    use crate::geometry::bvh::Bvh;
    use crate::geometry::triangles::TriangleScene;
    use crate::reference::ground_truth::point_occlusion;

    /// Cosine-weighted share of rays from `p` that hit `bvh` within `reach`.
    fn traced(bvh: &Bvh, p: Vec3, n: Vec3, reach: f32) -> f32 {
        point_occlusion(bvh, p + n * 1e-4, n, reach, 4096)
    }

    #[test]
    fn a_box_blocks_what_a_ray_tracer_finds() {
        let half = Vec3::new(0.5, 0.3, 0.8);
        let turn = Quat::from_euler(EulerRot::XYZ, 0.4, -0.3, 0.9);
        let placed = Affine3A::from_rotation_translation(turn, Vec3::new(0.2, 0.6, -0.1));
        let mut scene = TriangleScene::default();
        scene.add_mesh(&Cuboid::from_size(half * 2.0).into(), placed);
        let bvh = Bvh::new(scene.triangles);
        let proxy = box_proxy(
            placed.translation.into(),
            Mat3::from_quat(turn) * Mat3::from_diagonal(half),
        );
        let mut worst: f32 = 0.0;
        for (k, reach) in [(0, 0.0), (1, 0.75), (2, 2.0)] {
            for i in 0..40 {
                // Receivers on a shell around the box, facing roughly towards it.
                let a = i as f32 * 2.399;
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / 40.0;
                let dir = Vec3::new(
                    (1.0 - z * z).sqrt() * a.cos(),
                    z,
                    (1.0 - z * z).sqrt() * a.sin(),
                );
                let p = Vec3::from(placed.translation) + dir * (1.2 + 0.3 * k as f32);
                let n = (-dir + Vec3::new(0.3, -0.2, 0.1) * (i % 3) as f32).normalize();
                let limit = if reach > 0.0 { reach } else { f32::INFINITY };
                let truth = traced(&bvh, p, n, limit);
                let ours = proxy_occlusion(&proxy, p, n, reach);
                worst = worst.max((truth - ours).abs());
                // Without a reach the formula is exact; within one, the clipped square stands for
                // the disk of the same area.
                let bound = if reach > 0.0 { 0.03 } else { 0.006 };
                assert!(
                    (truth - ours).abs() < bound,
                    "reach {reach}, receiver {p} facing {n}: traced {truth}, box {ours}"
                );
            }
        }
        println!("largest difference {worst}");
    }

    /// A skinned mesh's joints shear its boxes: each face is then a parallelogram whose normal
    /// is not its box axis.
    #[test]
    fn a_sheared_box_blocks_what_a_ray_tracer_finds_and_nothing_behind_its_faces() {
        let centre = Vec3::new(0.1, 0.5, -0.2);
        let axes = Mat3::from_cols(
            Vec3::new(0.3, 0.06, 0.02),
            Vec3::new(0.0, 0.4, 0.05),
            Vec3::new(-0.03, 0.0, 0.2),
        );
        let proxy = box_proxy(centre, axes);
        let mut scene = TriangleScene::default();
        scene.add_mesh(
            &Cuboid::new(1.0, 1.0, 1.0).into(),
            Affine3A::from_mat3_translation(axes * 2.0, centre),
        );
        let bvh = Bvh::new(scene.triangles);
        let columns = [axes.x_axis, axes.y_axis, axes.z_axis];
        let mut worst_behind: f32 = 0.0;
        let mut worst: f32 = 0.0;
        for i in 0..3 {
            let (a, b, c) = (columns[i], columns[(i + 1) % 3], columns[(i + 2) % 3]);
            let normal = b.cross(c).normalize() * b.cross(c).dot(a).signum();
            for side in [-1.0f32, 1.0] {
                let f = normal * side;
                for (s, t) in [(0.6, 0.3), (-0.5, 0.7), (0.1, -0.8), (0.9, 0.9)] {
                    let on_face = centre + a * side + b * s + c * t;
                    // Just off or just inside the face, facing out (a little tilted), as a
                    // mesh's surface lies about its loosely fitted box: the box lies behind.
                    let tilt = (f + b.normalize() * 0.05).normalize();
                    for off in [2e-4, -2e-4] {
                        let behind = proxy_occlusion(&proxy, on_face + f * off, tilt, 0.75);
                        worst_behind = worst_behind.max(behind);
                    }
                    // Off the face, facing back at it.
                    let p = on_face + f * 0.1;
                    let truth = traced(&bvh, p, -tilt, 0.75);
                    let ours = proxy_occlusion(&proxy, p, -tilt, 0.75);
                    worst = worst.max((truth - ours).abs());
                }
            }
        }
        println!("behind its faces {worst_behind}, largest difference in front {worst}");
        assert!(worst_behind < 1e-3, "{worst_behind}");
        assert!(worst < 0.005, "{worst}");
    }

    #[test]
    fn a_flat_box_never_darkens_its_own_plane() {
        let floor = box_proxy(
            Vec3::ZERO,
            Mat3::from_cols(Vec3::X * 10.0, Vec3::ZERO, Vec3::Z * 10.0),
        );
        for p in [Vec3::new(0.3, 1e-5, -2.0), Vec3::new(4.0, 0.0, 1.0)] {
            let a = proxy_occlusion(&floor, p, Vec3::Y, 0.75);
            assert!(a < 1e-4, "{a}");
        }
        // A wall of a box standing on it sees the floor below its horizon: half its light
        // within reach, less the part farther than the reach.
        let a = proxy_occlusion(&floor, Vec3::new(0.0, 0.05, 0.0), Vec3::X, 2.0);
        assert!((0.4..0.5).contains(&a), "{a}");
    }

    #[test]
    fn spheres_block_their_cap_within_reach() {
        let proxy = OccluderSphere {
            center: Vec3::new(0.0, 2.0, 0.0),
            radius: 0.5,
            axes: Mat3::from_diagonal(Vec3::splat(0.5)),
            shape: ProxyShape::Spheres,
        };
        let full = proxy_occlusion(&proxy, Vec3::ZERO, Vec3::Y, 0.0);
        assert!((full - 0.0625).abs() < 1e-4, "sin²α = 1/16: {full}");
        // Nothing lies within 1.4 m; all of it within 2 m.
        assert_eq!(proxy_occlusion(&proxy, Vec3::ZERO, Vec3::Y, 1.4), 0.0);
        let within = proxy_occlusion(&proxy, Vec3::ZERO, Vec3::Y, 1.8);
        assert!(within > 0.0 && within < full);
        assert_eq!(proxy_occlusion(&proxy, Vec3::ZERO, Vec3::Y, 2.0), full);
    }

    /// Eq. 5: a sphere blocks exactly ε of a receiver that faces it at d_far.
    #[test]
    fn occlusion_at_reach_is_epsilon() {
        for epsilon in [0.005, 0.02, 0.1] {
            let reach = far_field_reach(0.3, epsilon);
            // Facing the sphere, at exactly d_far.
            let a = sphere_occlusion(Vec3::new(0.0, reach, 0.0), 0.3, Vec3::ZERO, Vec3::Y);
            assert!((a - epsilon).abs() < 1e-4, "ε {epsilon}: {a}");
            let beyond =
                sphere_occlusion(Vec3::new(0.0, reach * 1.1, 0.0), 0.3, Vec3::ZERO, Vec3::Y);
            assert!(beyond < epsilon);
        }
        assert!((far_field_reach(1.0, 0.01) - 10.01).abs() < 0.01);
    }
}

//! The ray-marched reference on the CPU, step for step as `ray_march/march.wgsl` runs it.

use bevy::math::{IVec2, Vec3, Vec4, Vec4Swizzles};

use super::nd_buffer::{NdBuffer, ViewMatrices};
use super::sampling::{HASH_TO_UNIT, pcg_hash, tangent_frame};

/// Parameters of one evaluation, as the GPU uniform carries them.
#[derive(Clone, Copy, Debug)]
pub struct RayMarchInputs {
    /// R, metres.
    pub radius: f32,
    /// Multiplier on the occlusion.
    pub intensity: f32,
    /// Azimuths per pixel.
    pub directions: u32,
    /// Elevations per azimuth.
    pub elevations: u32,
    /// Steps per ray.
    pub steps: u32,
    /// How far behind the back-face layer a step still counts as blocked, metres
    /// ([`RayMarchParams::thickness`](crate::RayMarchParams::thickness) × R).
    pub thickness: f32,
}

/// The pixel of a `width`×`height` viewport view-space `x` projects to, and its NDC depth;
/// `None` behind the camera.
fn project(view: &ViewMatrices, x: Vec3, width: u32, height: u32) -> Option<(IVec2, f32)> {
    let clip = view.clip_from_view * x.extend(1.0);
    if clip.w <= 0.0 {
        return None;
    }
    let ndc = clip.xyz() / clip.w;
    let q = IVec2::new(
        ((ndc.x + 1.0) * 0.5 * width as f32).floor() as i32,
        ((1.0 - ndc.y) * 0.5 * height as f32).floor() as i32,
    );
    Some((q, ndc.z))
}

/// How far apart, as a share of their distance from the camera, the two layers may lie and
/// still hold the same polygon, a two-sided sheet: `TWO_SIDED_GAP` in `march.wgsl`, which says
/// why.
const TWO_SIDED_GAP: f32 = 1e-4;

/// 1 blocked (inside the solid the layers bound, less than `thickness` behind the back-face
/// layer or R behind a two-sided sheet, or behind a sheet thinner than `step` that the previous
/// step, at `previous`, lay in front of), 0 free behind the front layer, 2 free in front of it
/// (or where it holds nothing), −1 left the screen.
fn blocked(
    nd: &NdBuffer,
    view: &ViewMatrices,
    x: Vec3,
    previous: Vec3,
    step: f32,
    inputs: &RayMarchInputs,
) -> i32 {
    let (w, h) = (nd.width, nd.height);
    let Some((q, ndc_z)) = project(view, x, w, h) else {
        return -1;
    };
    let (Some(front), Some(back)) = (nd.texel(false, q.x, q.y), nd.texel(true, q.x, q.y)) else {
        return -1;
    };
    // Stored reverse-Z depths, compared as the shader compares them (a larger depth is nearer).
    if front.depth <= 0.0 || ndc_z >= front.depth {
        return 2;
    }
    let front_z = view.view_position(q.x, q.y, w, h, front.depth).z;
    if back.depth > 0.0 {
        if ndc_z > back.depth {
            return 1;
        }
        let back_z = view.view_position(q.x, q.y, w, h, back.depth).z;
        let two_sided = (front_z - back_z).abs() < TWO_SIDED_GAP * -front_z;
        let thickness = if two_sided {
            inputs.radius
        } else {
            inputs.thickness
        };
        if back_z - x.z < thickness {
            return 1;
        }
        let crossed = front_z - back_z < step && previous.z >= front_z;
        return i32::from(crossed);
    }
    i32::from(front_z - x.z < inputs.radius)
}

/// How far, in view-space z, a ray's crossing of a sheet's plane may lie outside the sheet the
/// layers hold there, as a share of a step: `SHEET_TOLERANCE` in `march.wgsl`.
const SHEET_TOLERANCE: f32 = 0.05;

/// Whether a ray now at view-space `x`, in front of the surface the pixel it projects to shows,
/// came through that surface from behind since its previous step at `previous`, `step` metres
/// back: `came_through_from_behind` in `march.wgsl`, which says why.
fn came_through_from_behind(
    nd: &NdBuffer,
    view: &ViewMatrices,
    x: Vec3,
    previous: Vec3,
    step: f32,
) -> bool {
    let (w, h) = (nd.width, nd.height);
    let Some((q, _)) = project(view, x, w, h) else {
        return false;
    };
    let (Some(front), Some(back)) = (nd.texel(false, q.x, q.y), nd.texel(true, q.x, q.y)) else {
        return false;
    };
    if front.depth <= 0.0 || back.depth <= 0.0 {
        return false;
    }
    let orthographic = view.clip_from_view.w_axis.w == 1.0;
    // The two faces where the line of sight through `x` meets them.
    let along_sight = |depth: f32| {
        let z = view.view_position(q.x, q.y, w, h, depth).z;
        let scale = if orthographic { 1.0 } else { z / x.z };
        (x.truncate() * scale).extend(z)
    };
    let (f, b) = (along_sight(front.depth), along_sight(back.depth));
    let up = facing_the_eye(
        view,
        (view.view_from_world * front.normal.extend(0.0)).xyz(),
        f,
    );
    let before = (previous - b).dot(up);
    let after = (x - b).dot(up);
    if !((f - b).dot(up) < step && before < 0.0 && (x - f).dot(up) > 0.0) {
        return false;
    }
    let crossing = previous.lerp(x, before / (before - after));
    let Some((at, _)) = project(view, crossing, w, h) else {
        return false;
    };
    let Some(front_there) = nd.texel(false, at.x, at.y).filter(|t| t.depth > 0.0) else {
        return false;
    };
    // The sheet there, as deep along the line of sight as at `q`.
    let front_z = view.view_position(at.x, at.y, w, h, front_there.depth).z;
    let back_z = front_z - (f.z - b.z);
    let tolerance = SHEET_TOLERANCE * step;
    crossing.z <= front_z + tolerance && crossing.z >= back_z - tolerance
}

/// The view-space normal `m` of the surface at view-space `p`, turned to the side the camera
/// sees: `facing_the_eye` in `march.wgsl`.
fn facing_the_eye(view: &ViewMatrices, m: Vec3, p: Vec3) -> Vec3 {
    let to_eye = if view.clip_from_view.w_axis.w == 1.0 {
        Vec3::Z
    } else {
        -p
    };
    if m.dot(to_eye) < 0.0 { -m } else { m }
}

/// Occlusion (0 = open) of every pixel, row-major.
pub fn ray_march_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    inputs: &RayMarchInputs,
) -> Vec<f32> {
    nd.per_pixel(|x, y| pixel_occlusion(nd, view, inputs, x, y))
}

/// The share of the way from the last step on screen to the edge crossing that `edge_crossing`
/// returns: `INSIDE_THE_EDGE` in `march.wgsl`.
const INSIDE_THE_EDGE: f32 = 0.999;

/// How far along the ray from view-space `origin` along `dir`, between `on_screen` (a step on
/// screen) and `left_at` (the next, off it), its image leaves the screen, a little short of
/// that: `edge_crossing` in `march.wgsl`, which says why.
fn edge_crossing(
    view: &ViewMatrices,
    origin: Vec3,
    dir: Vec3,
    on_screen: f32,
    left_at: f32,
) -> f32 {
    let clip = view.clip_from_view * origin.extend(1.0);
    let clip_dir = view.clip_from_view * dir.extend(0.0);
    let start = Vec4::splat(clip.w) + Vec4::new(-clip.x, clip.x, -clip.y, clip.y);
    let rate =
        Vec4::splat(clip_dir.w) + Vec4::new(-clip_dir.x, clip_dir.x, -clip_dir.y, clip_dir.y);
    let t = (0..4)
        .filter(|&i| rate[i] < 0.0)
        .map(|i| -start[i] / rate[i])
        .fold(left_at, f32::min)
        .clamp(on_screen, left_at);
    on_screen + (t - on_screen) * INSIDE_THE_EDGE
}

/// Whether the ray from view-space `origin` along unit `dir`, whose image reached the screen's
/// edge at distance `edge` (`edge_crossing`), meets the tangent plane of the surface at the
/// screen's edge there, off screen and within `radius`: `beyond_the_edge` in `march.wgsl`, which
/// says why.
fn beyond_the_edge(
    nd: &NdBuffer,
    view: &ViewMatrices,
    origin: Vec3,
    dir: Vec3,
    edge: f32,
    radius: f32,
) -> bool {
    let (w, h) = (nd.width, nd.height);
    let exit = view.clip_from_view * (origin + dir * edge).extend(1.0);
    if exit.w <= 0.0 {
        return false;
    }
    let ndc = exit.xyz() / exit.w;
    let pixel = IVec2::new(
        (((ndc.x + 1.0) * 0.5 * w as f32).floor() as i32).clamp(0, w as i32 - 1),
        (((1.0 - ndc.y) * 0.5 * h as f32).floor() as i32).clamp(0, h as i32 - 1),
    );
    let Some(texel) = nd.texel(false, pixel.x, pixel.y) else {
        return false;
    };
    if texel.depth <= 0.0 || texel.normal == Vec3::ZERO {
        return false;
    }
    let e = view.view_position(pixel.x, pixel.y, w, h, texel.depth);
    let m = (view.view_from_world * texel.normal.extend(0.0))
        .xyz()
        .normalize();
    let up = facing_the_eye(view, m, e);
    let start = (origin + dir * edge - e).dot(up);
    let end = (origin + dir * radius - e).dot(up);
    if !(start > 0.0 && end < 0.0) {
        return false;
    }
    let t = edge + (radius - edge) * start / (start - end);
    let meet = view.clip_from_view * (origin + dir * t).extend(1.0);
    if meet.w <= 0.0 {
        return true;
    }
    let (u, v) = ((meet.x / meet.w + 1.0) * 0.5, (1.0 - meet.y / meet.w) * 0.5);
    !(0.0..1.0).contains(&u) || !(0.0..1.0).contains(&v)
}

/// How far above the surface at view-space `p` with normal `n` rays start, metres, where a pixel
/// is `footprint` wide: `start_height` in `march.wgsl`, which says why. Twice the least
/// height at which a step cannot read as behind the depth at the centre of the pixel it projects
/// to, (footprint / 2) sin θ, θ between the normal and the direction to the eye.
fn start_height(view: &ViewMatrices, p: Vec3, n: Vec3, footprint: f32) -> f32 {
    let orthographic = view.clip_from_view.w_axis.w == 1.0;
    let to_eye = if orthographic {
        Vec3::Z
    } else {
        -p.normalize()
    };
    let cos_view = n.dot(to_eye).abs().min(1.0);
    footprint * (1.0 - cos_view * cos_view).sqrt()
}

/// Where step `s` of `steps` samples a ray, metres along it, and how far it lies from the step
/// before: `offset` of a `step` into its stride (0.5, the accumulated march's frame 0), the last
/// at `radius` itself.
fn step_at(s: u32, steps: u32, offset: f32, step: f32, radius: f32) -> (f32, f32) {
    if s + 1 == steps {
        (radius, radius - (s as f32 - 1.0 + offset) * step)
    } else {
        ((s as f32 + offset) * step, step)
    }
}

/// Occlusion of one pixel.
pub fn pixel_occlusion(
    nd: &NdBuffer,
    view: &ViewMatrices,
    inputs: &RayMarchInputs,
    x: i32,
    y: i32,
) -> f32 {
    let Some(receiver) = nd.receiver(view, x, y) else {
        return 0.0;
    };
    let (p, n) = (receiver.view_position, receiver.view_normal);
    let frame = tangent_frame(n);
    let (t1, t2) = (frame.x_axis, frame.y_axis);
    let origin = p + n * start_height(view, p, n, view.pixel_world_size(-p.z, nd.height));
    let step = inputs.radius / inputs.steps as f32;
    let hash = pcg_hash(x as u32 ^ pcg_hash(y as u32 ^ 0x2c1b_3c6d));
    let rotation = hash as f32 * HASH_TO_UNIT;
    let jitter = pcg_hash(hash) as f32 * HASH_TO_UNIT;
    let mut hits = 0u32;
    for i in 0..inputs.directions {
        let phi = (i as f32 + rotation) * std::f32::consts::TAU / inputs.directions as f32;
        for j in 0..inputs.elevations {
            let u = (j as f32 + jitter) / inputs.elevations as f32;
            let (sin_theta, cos_theta) = (u.sqrt(), (1.0 - u).sqrt());
            let dir = t1 * (sin_theta * phi.cos()) + t2 * (sin_theta * phi.sin()) + n * cos_theta;
            let mut on_screen = 0.0;
            // The first step in front of the front layer after the start or a hidden step, and
            // its stride (`came_through_from_behind`).
            let mut sheet = None;
            let mut left_at = None;
            let mut hit = false;
            let mut was_hidden = true;
            for s in 0..inputs.steps {
                let (t, stride) = step_at(s, inputs.steps, 0.5, step, inputs.radius);
                let previous = origin + dir * (t - stride).max(0.0);
                let state = blocked(nd, view, origin + dir * t, previous, stride, inputs);
                if state == 2 && was_hidden && sheet.is_none() {
                    sheet = Some((t, stride));
                }
                was_hidden = state == 0;
                if state == 1 || state == -1 {
                    hit = state == 1;
                    left_at = (state == -1).then_some(t);
                    break;
                }
                on_screen = t;
            }
            // As the shader does, once per ray after its loop.
            hit =
                hit || sheet.is_some_and(|(t, stride)| {
                    let previous = origin + dir * (t - stride).max(0.0);
                    came_through_from_behind(nd, view, origin + dir * t, previous, stride)
                }) || left_at.is_some_and(|t| {
                    // The ray at the screen's edge is judged as a step.
                    let edge = edge_crossing(view, origin, dir, on_screen, t.max(on_screen));
                    let at_edge = origin + dir * edge;
                    let last = origin + dir * on_screen;
                    blocked(nd, view, at_edge, last, edge - on_screen, inputs) == 1
                        || beyond_the_edge(nd, view, origin, dir, edge, inputs.radius)
                });
            hits += u32::from(hit);
        }
    }
    let total = (inputs.directions * inputs.elevations) as f32;
    (inputs.intensity * hits as f32 / total).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use bevy::math::{Mat4, Vec3, Vec4Swizzles};

    use super::{ViewMatrices, edge_crossing, step_at};

    #[test]
    fn the_steps_reach_the_radius_in_order_whatever_the_offset() {
        let (steps, radius) = (6, 0.75);
        let step = radius / steps as f32;
        for offset in [0.0, 0.25, 0.5, 0.999] {
            let mut previous = 0.0;
            for s in 0..steps {
                let (t, stride) = step_at(s, steps, offset, step, radius);
                assert!(
                    t > previous || (s == 0 && t == 0.0),
                    "step {s} at {t} after {previous}"
                );
                if s > 0 {
                    assert!(
                        (t - stride - previous).abs() < 1e-6,
                        "stride {stride} at step {s}"
                    );
                }
                assert!(t <= radius);
                previous = t;
            }
            assert_eq!(previous, radius, "offset {offset}: the last step lies at R");
        }
    }

    /// Whether view-space `p` projects inside the screen, and how far from its nearest edge in
    /// normalized device coordinates.
    fn inside_by(view: &ViewMatrices, p: Vec3) -> (bool, f32) {
        let clip = view.clip_from_view * p.extend(1.0);
        let ndc = clip.xy() / clip.w;
        let inside = clip.w > 0.0 && ndc.abs().max_element() <= 1.0;
        (inside, 1.0 - ndc.abs().max_element())
    }

    #[test]
    fn the_edge_crossing_lies_just_inside_the_screen_even_past_the_camera_plane() {
        let view = ViewMatrices::new(
            Mat4::IDENTITY,
            Mat4::perspective_infinite_reverse_rh(0.8, 4.0 / 3.0, 0.05),
        );
        let origin = Vec3::new(0.2, -0.3, -2.0);
        // Off the side of the screen ahead of the camera, then towards the camera and past its
        // plane, where the step off screen has no image at all.
        for (dir, left_at) in [
            (Vec3::new(1.0, 0.0, 0.0), 3.0),
            (Vec3::new(0.0, -0.6, 0.8).normalize(), 4.0),
        ] {
            let (on_screen, _) = inside_by(&view, origin);
            assert!(on_screen);
            let t = edge_crossing(&view, origin, dir, 0.0, left_at);
            let (inside, margin) = inside_by(&view, origin + dir * t);
            assert!(inside && t > 0.0 && t < left_at, "{dir}: crossing at {t}");
            assert!(margin < 0.01, "{dir}: {margin} from the edge at {t}");
            let (past, _) = inside_by(&view, origin + dir * (t * 1.01 + 0.01));
            assert!(!past, "{dir}: still on screen just after {t}");
        }
    }
}

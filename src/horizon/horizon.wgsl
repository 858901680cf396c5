// Horizon-based ambient occlusion, Bavoil & Sainz 2008: per image-space direction, the rise of the
// horizon above a starting elevation, attenuated by W0 · (1 − (r/R)²). Modes (`HorizonMode`):
// 0 low (no normals: from straight down, minus one W0 per direction), 1 normal (from the tangent
// plane), 2 high (from the higher of the tangent plane and the surface one pixel away, with
// per-direction jitter).
// `reference::horizon` is the CPU twin; keep the two in step.

#import bevy_dynamic_ao::image_space_bindings::{
    view, settings, front_depth, front_normal, back_depth, back_normal, receiver, Receiver,
    store_occlusion, view_position, view_position_at,
}
#import bevy_dynamic_ao::nd_buffer::pixel_world_size
#import bevy_dynamic_ao::sampling::{pcg_hash, HASH_TO_UNIT, frame_offset, pixel_pattern}
#import bevy_dynamic_ao::math::TAU

const HALF_PI: f32 = 1.57079632679489662;

// The tangent-plane vector that one pixel along image direction `dir` covers: the view ray
// through that point meets the plane through `p` with normal `n`. Stepping in the image moves
// along this vector, not along (dir.x, −dir.y, 0), once perspective is taken into account, so
// a flat surface gets no occlusion from itself.
fn tangent_along(pixel: vec2<i32>, size: vec2<f32>, dir: vec2<f32>, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let uv = (vec2<f32>(pixel) + 0.5 + dir) / size;
    let a = view_position_at(uv, 1.0);
    let b = view_position_at(uv, 0.5);
    let denominator = dot(n, b - a);
    if abs(denominator) < 1e-12 {
        let along = vec3<f32>(dir.x, -dir.y, 0.0);
        return along - n * dot(n, along);
    }
    return a + (b - a) * (dot(n, p - a) / denominator) - p;
}

@compute @workgroup_size(8, 8, 1)
fn horizon(@builtin(global_invocation_id) invocation: vec3<u32>) {
    let r = receiver(invocation);
    var value = 0.0;
    if r.shade {
        value = horizon_occlusion(r);
    }
    store_occlusion(r, value);
}

// Horizon-based occlusion at receiver `r`, which has a surface.
fn horizon_occlusion(r: Receiver) -> f32 {
    let pixel = r.pixel;
    let size = r.size;
    let dims = vec2<i32>(size);
    let p = r.view_position;
    let n = r.view_normal;
    let radius = settings.image_space_radius;
    let radius_px = radius / pixel_world_size(view, -p.z, size.y);
    // Fewer steps where the radius covers fewer pixels: never two steps in one pixel.
    let steps = clamp(u32(radius_px), 1u, settings.horizon_steps);
    let step_px = radius_px / f32(steps);
    let pattern = pixel_pattern(pixel, 0x68bc21ebu, settings.frame_index);
    let hash = pattern.hash;
    let rotation = pattern.rotation;
    let pixel_jitter = pattern.jitter;
    let frame = frame_offset(settings.frame_index);
    let directions = settings.horizon_directions;
    let mode = settings.horizon_mode;

    var sum = 0.0;
    for (var i = 0u; i < directions; i++) {
        let angle = (f32(i) + rotation) * TAU / f32(directions);
        let dir = vec2<f32>(cos(angle), sin(angle));
        // The elevation of the tangent plane along this image direction.
        let tangent = tangent_along(pixel, size, dir, p, n);
        let sin_tangent = clamp(tangent.z / max(length(tangent), 1e-6), -1.0, 1.0);
        var sin_horizon = sin(min(asin(sin_tangent) + settings.horizon_angle_bias, HALF_PI));
        var jitter = pixel_jitter;
        if mode == 0u {
            sin_horizon = -1.0;
        } else if mode == 2u {
            jitter = fract(f32(pcg_hash(hash ^ ((i + 1u) * 0x9e3779b9u))) * HASH_TO_UNIT + frame.y);
            let q = pixel + vec2<i32>(floor(dir + 0.5));
            if all(q >= vec2<i32>(0)) && all(q < dims) && any(q != pixel) {
                let dq = textureLoad(front_depth, q, 0);
                if dq > 0.0 {
                    let v = view_position(q, size, dq) - p;
                    let r = length(v);
                    if r > 0.0 && r < radius {
                        sin_horizon = max(sin_horizon, v.z / r);
                    }
                }
            }
        }
        var ao = 0.0;
        for (var k = 0u; k < steps; k++) {
            let offset = dir * ((f32(k) + jitter) * step_px + 1.0);
            let q = pixel + vec2<i32>(floor(offset + 0.5));
            if all(q == pixel) || any(q < vec2<i32>(0)) || any(q >= dims) {
                continue;
            }
            let dq = textureLoad(front_depth, q, 0);
            if dq <= 0.0 {
                continue;
            }
            let v = view_position(q, size, dq) - p;
            let r = length(v);
            if r >= radius || r <= 0.0 {
                continue;
            }
            let sin_elevation = v.z / r;
            if sin_elevation > sin_horizon {
                let x = r / radius;
                ao += settings.horizon_attenuation * (1.0 - x * x) * (sin_elevation - sin_horizon);
                sin_horizon = sin_elevation;
            }
        }
        if mode == 0u {
            // The lower half of the sphere, below the unknown tangent plane.
            ao -= settings.horizon_attenuation;
        }
        sum += ao;
    }
    return settings.horizon_contrast * settings.intensity * sum / f32(directions);
}

// Near-field ambient occlusion in image space: Shanmugam & Arikan 2007, §4, eq. 2–4.
// `reference::near_field` evaluates the same steps on the CPU; keep the two in step.

#import bevy_dynamic_ao::image_space_bindings::{
    view, settings, front_depth, front_normal, back_depth, back_normal, receiver, Receiver,
    store_occlusion,
}
#import bevy_dynamic_ao::nd_buffer::{decode_normal, world_position, view_depth, pixel_world_size}
#import bevy_dynamic_ao::math::{PI, TAU}
#import bevy_dynamic_ao::sampling::{pixel_rotation, disk_sample, frame_offset}
#import bevy_dynamic_ao::sphere_occlusion::sphere_occlusion


// A_ψ of the sphere standing for the surface sample seen at pixel `q` (depth and encoded normal
// already read), as seen from receiver `p` with normal `n`.
fn occluder(
    q: vec2<i32>,
    depth: f32,
    encoded_normal: vec3<f32>,
    size: vec2<f32>,
    p: vec3<f32>,
    n: vec3<f32>,
    sphere_scale: f32,
) -> f32 {
    if depth <= 0.0 {
        return 0.0;
    }
    let position = world_position(view, q, size, depth);
    // Eq. 4 takes only occluders closer than r_far.
    let d = distance(position, p);
    if d >= settings.image_space_radius {
        return 0.0;
    }
    // A surface point below the receiver's tangent plane cannot occlude it. The push-back along
    // −n does this for a flat surface; this test also covers the far side of a thin solid,
    // whose back-layer spheres would otherwise poke through the receiver's own surface.
    if dot(n, position - p) <= 0.0 {
        return 0.0;
    }
    // The sphere never reaches past half the way to the receiver, so a sample close to a crease
    // cannot swallow the receiver whole (A_ψ = 1) and black the crease out.
    let radius = min(pixel_world_size(view, view_depth(view, position), size.y) * sphere_scale, 0.5 * d);
    let center = position - decode_normal(encoded_normal) * radius;
    return sphere_occlusion(center, radius, p, n);
}

@compute @workgroup_size(8, 8, 1)
fn near_field(@builtin(global_invocation_id) invocation: vec3<u32>) {
    let r = receiver(invocation);
    var value = 0.0;
    if r.shade {
        value = near_field_occlusion(r);
    }
    store_occlusion(r, value);
}

// The near field's occlusion at receiver `r`, which has a surface.
fn near_field_occlusion(r: Receiver) -> f32 {
    let pixel = r.pixel;
    let size = r.size;
    let n = r.normal;
    let p = world_position(view, pixel, size, r.depth);

    // r_far projected at the receiver, pixels; the sample count follows its area (fig. 4).
    let radius_px = settings.image_space_radius / pixel_world_size(view, view_depth(view, p), size.y);
    let area = PI * radius_px * radius_px;
    let count = clamp(u32(ceil(min(area, 4096.0))), settings.near_field_min_samples, settings.near_field_max_samples);
    // Each sample stands for area / count pixels; a sphere of that cross-section has a radius
    // of this many pixel sizes. Under temporal accumulation over N frames, a frame's samples are
    // a 1/N share of the pattern the history averages: each stands for area / (count · N)
    // pixels and counts N times, so that the average estimates the full budget, not N
    // estimates of a small one.
    let frames = settings.temporal_frames;
    let sphere_scale = radius_px / sqrt(f32(count) * frames);
    let frame = frame_offset(settings.frame_index);
    let rotation = pixel_rotation(vec2<u32>(pixel)) + frame.x * TAU;
    let ring = fract(0.5 + frame.y);

    // Open fraction left by the occluders so far: 1 − Π(1 − A_ψ).
    var open = 1.0;
    for (var i = 0u; i < count; i++) {
        let offset = disk_sample(i, count, radius_px, rotation, ring);
        let q = pixel + vec2<i32>(floor(offset + 0.5));
        if all(q == pixel) || any(q < vec2<i32>(0)) || any(q >= vec2<i32>(size)) {
            continue;
        }
        var sample_open = 1.0 - occluder(q, textureLoad(front_depth, q, 0),
            textureLoad(front_normal, q, 0).xyz, size, p, n, sphere_scale);
        if settings.near_field_back_layer != 0u {
            sample_open *= 1.0 - occluder(q, textureLoad(back_depth, q, 0),
                textureLoad(back_normal, q, 0).xyz, size, p, n, sphere_scale);
        }
        if frames > 1.0 {
            sample_open = pow(sample_open, frames);
        }
        open *= sample_open;
    }
    return (1.0 - open) * settings.intensity;
}

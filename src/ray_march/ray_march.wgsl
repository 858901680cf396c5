// Ray-marched ambient occlusion through both ND-buffer layers (Bavoil & Sainz 2008,
// "Ray-Marched Ambient Occlusion"). `reference::ray_march` is the CPU twin.

#import bevy_dynamic_ao::image_space_bindings::{
    view, settings, front_depth, front_normal, back_depth, back_normal, occlusion, receiver,
    view_position,
}
#import bevy_dynamic_ao::sampling::pixel_pattern
#import bevy_dynamic_ao::math::{TAU, tangent_frame}

// Whether the view-space point `x` lies inside the geometry the two layers bound.
fn blocked(x: vec3<f32>, size: vec2<f32>, dims: vec2<i32>, radius: f32) -> i32 {
    let clip = view.clip_from_view * vec4<f32>(x, 1.0);
    if clip.w <= 0.0 {
        return -1;
    }
    let ndc = clip.xy / clip.w;
    let q = vec2<i32>(floor(vec2<f32>((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5) * size));
    if any(q < vec2<i32>(0)) || any(q >= dims) {
        // The ray left the screen: nothing more is known along it.
        return -1;
    }
    let front = textureLoad(front_depth, q, 0);
    if front <= 0.0 {
        return 0;
    }
    let front_z = view_position(q, size, front).z;
    // A small tolerance keeps the receiver's own surface from blocking it.
    if x.z > front_z - 0.01 * radius {
        return 0;
    }
    let back = textureLoad(back_depth, q, 0);
    if back > 0.0 {
        return select(0, 1, x.z > view_position(q, size, back).z);
    }
    return select(0, 1, front_z - x.z < radius);
}

@compute @workgroup_size(8, 8, 1)
fn ray_march(@builtin(global_invocation_id) invocation: vec3<u32>) {
    let r = receiver(invocation);
    if !r.shade {
        return;
    }
    let pixel = r.pixel;
    let size = r.size;
    let dims = vec2<i32>(size);
    let p = r.view_position;
    let n = r.view_normal;
    let frame = tangent_frame(n);
    let t1 = frame[0];
    let t2 = frame[1];

    let radius = settings.image_space_radius;
    let pattern = pixel_pattern(pixel, 0x2c1b3c6du, settings.frame_index);
    let rotation = pattern.rotation;
    let jitter = pattern.jitter;
    let directions = settings.ray_march_directions;
    let elevations = settings.ray_march_elevations;
    var hits = 0u;
    for (var i = 0u; i < directions; i++) {
        let phi = (f32(i) + rotation) * TAU / f32(directions);
        for (var j = 0u; j < elevations; j++) {
            // Cosine-weighted: sin²θ uniform in [0, 1).
            let u = (f32(j) + jitter) / f32(elevations);
            let sin_theta = sqrt(u);
            let cos_theta = sqrt(1.0 - u);
            let dir = t1 * (sin_theta * cos(phi)) + t2 * (sin_theta * sin(phi)) + n * cos_theta;
            for (var s = 0u; s < settings.ray_march_steps; s++) {
                let t = (f32(s) + 0.5) / f32(settings.ray_march_steps) * radius;
                let state = blocked(p + dir * t, size, dims, radius);
                if state != 0 {
                    hits += u32(state == 1);
                    break;
                }
            }
        }
    }
    let value = settings.intensity * f32(hits) / f32(directions * elevations);
    textureStore(occlusion, r.out_pixel, vec4<f32>(clamp(value, 0.0, 1.0)));
}

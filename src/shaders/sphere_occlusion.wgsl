// Occlusion of a receiver by one sphere, Shanmugam & Arikan 2007, eq. 2–3:
//   A_ψ(C, r, P, n) = S_Ω(P, C, r) · max(n·PC^, 0),  S_Ω = 2π(1 − cos(asin(r / |PC|)))
// divided here by π, the cosine-weighted measure of the hemisphere, so that the result is the
// fraction of the receiver's ambient light the sphere blocks (what ground truth measures), and
// 1 inside the sphere (§6). `reference::near_field::sphere_occlusion` is the CPU twin.

#define_import_path bevy_dynamic_ao::sphere_occlusion

fn sphere_occlusion(center: vec3<f32>, radius: f32, receiver: vec3<f32>, normal: vec3<f32>) -> f32 {
    let to_center = center - receiver;
    let distance = length(to_center);
    if distance <= radius {
        return 1.0;
    }
    let sin_theta = radius / distance;
    let cap = 2.0 * (1.0 - sqrt(1.0 - sin_theta * sin_theta));
    return min(cap * max(dot(normal, to_center / distance), 0.0), 1.0);
}

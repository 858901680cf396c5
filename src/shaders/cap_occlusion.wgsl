// The share of a receiver's ambient light that a cone of directions blocks: the cosine-weighted
// measure of a spherical cap of angular radius σ whose axis lies at angle θ from the receiver's
// normal, clipped by the receiver's tangent plane, divided by π (the cosine-weighted measure of
// the hemisphere). This is what ray-traced ground truth measures for an occluder that fills the
// cap. Closed form: π sin²σ cos θ while the cap lies wholly above the horizon; across the horizon
// the clipped integral of Snyder (1996, "Area light sources for real-time graphics"); a cap wider
// than a hemisphere is the whole sphere less the opposite cap. Malmer et al.'s T_clip (2005,
// §3.3.1) is this function; sphere occluders use it for the cap of the sphere that lies within
// reach. `geometry::cap` is the CPU twin (the field baker uses it too).

#define_import_path bevy_dynamic_ao::cap_occlusion

#import bevy_dynamic_ao::math::PI

// σ ≤ π/2, given by its cosine; `cos_theta` is the cosine of the axis' angle from the normal.
fn narrow_cap_occlusion(cos_sigma: f32, cos_theta: f32) -> f32 {
    let sin2_sigma = max(1.0 - cos_sigma * cos_sigma, 0.0);
    if cos_theta >= sqrt(sin2_sigma) {
        // Wholly above the horizon.
        return sin2_sigma * cos_theta;
    }
    if cos_theta <= -sqrt(sin2_sigma) || sin2_sigma <= 0.0 {
        return 0.0;
    }
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    // cot σ; y is where the horizon cuts the cap's boundary.
    let x = max(cos_sigma, 0.0) / sqrt(sin2_sigma);
    let y = clamp(-x * cos_theta / max(sin_theta, 1e-7), -1.0, 1.0);
    let s = sin_theta * sqrt(max(1.0 - y * y, 0.0));
    let integral = (cos_theta * acos(y) - x * s) * sin2_sigma + atan2(s, x);
    return clamp(integral / PI, 0.0, 1.0);
}

// Any σ in [0, π], given by its cosine.
fn cap_occlusion(cos_sigma: f32, cos_theta: f32) -> f32 {
    if cos_sigma >= 0.0 {
        return narrow_cap_occlusion(cos_sigma, cos_theta);
    }
    return 1.0 - narrow_cap_occlusion(-cos_sigma, -cos_theta);
}

// Of two occlusions of one occluder, `inner` the part within the near field's reach and `all`
// the whole: the share of the directions `inner` leaves open that the rest covers, so that the
// two join back into `all` as independent occluders, 1 − (1 − inner)(1 − share).
fn share_beyond(all: f32, inner: f32) -> f32 {
    return clamp((all - inner) / max(1.0 - inner, 1e-4), 0.0, 1.0);
}

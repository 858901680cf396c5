// Constants and small functions several passes share; each is written once, here.

#define_import_path bevy_dynamic_ao::math

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717958648;

// Wendland's compactly supported kernel (Reinbothe et al. 2009, eq. 3): 1 at t = 0, falling
// smoothly to 0 at t = h and 0 beyond.
fn wendland(t: f32, h: f32) -> f32 {
    if t > h {
        return 0.0;
    }
    let s = 1.0 - t / h;
    return s * s * s * s * (4.0 * t / h + 1.0);
}

// An orthonormal frame (tangent, bitangent, n) around unit `n` without a branch on a reference
// axis (Duff et al. 2017), `reference::sampling::tangent_frame` is the CPU twin.
fn tangent_frame(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, bt, n);
}

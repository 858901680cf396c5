// Sample patterns. Integer hashing keeps them bit-identical to `reference::sampling` on the CPU.

#define_import_path bevy_dynamic_ao::sampling

const GOLDEN_ANGLE: f32 = 2.39996322972865332;
// 1 / 2³²: maps a 32-bit hash into [0, 1).
const HASH_TO_UNIT: f32 = 2.3283064365386963e-10;
// 2π / 2³²: maps a 32-bit hash to an angle.
const HASH_TO_ANGLE: f32 = 1.4629180792671596e-9;

// PCG hash (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering").
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Per-pixel rotation of the sample pattern, radians in [0, 2π).
fn pixel_rotation(pixel: vec2<u32>) -> f32 {
    return f32(pcg_hash(pixel.x ^ pcg_hash(pixel.y))) * HASH_TO_ANGLE;
}

// Sample `i` of `count` on a Vogel spiral filling a disk of `radius` pixels, rotated by
// `rotation`: evenly spread for any count, so the count can follow the projected radius.
fn disk_sample(i: u32, count: u32, radius: f32, rotation: f32) -> vec2<f32> {
    let r = radius * sqrt((f32(i) + 0.5) / f32(count));
    let angle = f32(i) * GOLDEN_ANGLE + rotation;
    return vec2<f32>(cos(angle), sin(angle)) * r;
}

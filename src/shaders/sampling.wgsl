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

// Offsets of frame `frame` in [0, 1)², along the plastic-number sequence (Roberts' R2): low
// discrepancy over consecutive frames, so under temporal accumulation each frame samples between
// the previous ones. Frame 0 (every frame without accumulation) gives (0, 0).
fn frame_offset(frame: u32) -> vec2<f32> {
    return fract(f32(frame & 1023u) * vec2<f32>(0.75487766624669276, 0.56984029099805327));
}

// A third offset of frame `frame` in [0, 1), along the golden-ratio sequence; 0 on frame 0.
fn frame_step(frame: u32) -> f32 {
    return fract(f32(frame & 1023u) * 0.61803398874989485);
}

// A third offset in [0, 1) for a pixel whose pattern hashed to `hash`: 0.5 on frame 0 (every
// frame without accumulation, where the CPU twins expect the middle), else moved every frame
// by `frame_step`, so accumulated frames fill the interval.
fn frame_jitter(hash: u32, frame: u32) -> f32 {
    if frame == 0u {
        return 0.5;
    }
    return fract(f32(pcg_hash(hash ^ 0x9e3779b9u)) * HASH_TO_UNIT + frame_step(frame));
}

// A pixel's random pattern: its `hash` (salted per technique), and a rotation and a jitter in
// [0, 1) drawn from it, both moved by frame `frame`'s offsets.
struct PixelPattern {
    hash: u32,
    rotation: f32,
    jitter: f32,
}

fn pixel_pattern(pixel: vec2<i32>, salt: u32, frame: u32) -> PixelPattern {
    let hash = pcg_hash(u32(pixel.x) ^ pcg_hash(u32(pixel.y) ^ salt));
    let offset = frame_offset(frame);
    return PixelPattern(
        hash,
        fract(f32(hash) * HASH_TO_UNIT + offset.x),
        fract(f32(pcg_hash(hash)) * HASH_TO_UNIT + offset.y),
    );
}

// Sample `i` of `count` on a Vogel spiral filling a disk of `radius` pixels, rotated by
// `rotation` with each ring shifted by `ring` (0.5: the spiral's own rings): evenly spread for
// any count, so the count can follow the projected radius.
fn disk_sample(i: u32, count: u32, radius: f32, rotation: f32, ring: f32) -> vec2<f32> {
    let r = radius * sqrt((f32(i) + ring) / f32(count));
    let angle = f32(i) * GOLDEN_ANGLE + rotation;
    return vec2<f32>(cos(angle), sin(angle)) * r;
}

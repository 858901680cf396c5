//! The integer hash behind every pseudo-random pattern of the crate, bit-identical to
//! `pcg_hash` in `shaders/sampling.wgsl`.

/// 1 / 2³²: maps a 32-bit hash into [0, 1).
pub const HASH_TO_UNIT: f32 = 2.328_306_4e-10;

/// PCG hash (Jarzynski & Olano 2020).
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

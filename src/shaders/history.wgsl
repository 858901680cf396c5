// A texel of a temporal history (`temporal::TemporalHistory`, Rgba32Uint), which the temporal
// pass writes and the upsampling reads: the accumulated value (f32 bits, or two 16-bit unorm
// channels for the voxel term), the linear depth and frame count it was accumulated at (f32 bits)
// and its surface's normal (4 × 8-bit snorm). A background texel has depth and frames 0.

#define_import_path bevy_dynamic_ao::history

struct HistoryTexel {
    // The value as stored; its reader knows how many channels it holds.
    value: u32,
    // Linear depth, metres; 0 on the background.
    depth: f32,
    frames: f32,
    normal: vec3<f32>,
}

fn pack_history(texel: HistoryTexel) -> vec4<u32> {
    return vec4<u32>(
        texel.value,
        bitcast<u32>(texel.depth),
        bitcast<u32>(texel.frames),
        pack4x8snorm(vec4<f32>(texel.normal, 0.0)),
    );
}

fn unpack_history(packed: vec4<u32>) -> HistoryTexel {
    return HistoryTexel(
        packed.x,
        bitcast<f32>(packed.y),
        bitcast<f32>(packed.z),
        unpack4x8snorm(packed.w).xyz,
    );
}

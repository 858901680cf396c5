// Voxel grids and the rays traced through them (Reinbothe, Boubekeur & Alexa 2009, §5–6).
// `reference::voxels` is the CPU twin; the integer hashing keeps the rays bit-identical.

#define_import_path bevy_dynamic_ao::voxel_grid

#import bevy_dynamic_ao::sampling::pcg_hash
#import bevy_dynamic_ao::math::TAU

// `voxels::grid_data::GpuVolume` on the Rust side.
struct VoxelVolume {
    // Rows of the world → grid affine map; cell (x, y, z) spans [x, x + 1]³.
    grid_from_world: array<vec4<f32>, 3>,
    // First 32-bit word of the grid in the grid buffer.
    offset: u32,
    // Cells per axis; 0 marks an unused slot.
    resolution: u32,
    rays: u32,
    // Evenly spaced tests per ray (the paper's march); 0: every cell the ray crosses.
    steps: u32,
    // cos of the half-angle of the cone the rays fill.
    cos_spread: f32,
    // Metres; 0: the camera's radius.
    d_max: f32,
    // Start offset of the rays along the normal, metres.
    bias: f32,
    // World-space size of the cells the jitter is constant over, metres.
    noise_cell: f32,
    // World-space size of one cell along each grid axis, metres.
    cell: vec3<f32>,
    // Bit 0: the occupied voxels are drawn; bit 1: hits count without falloff.
    flags: u32,
    // The volume's RenderLayers as bits (`seen_by_view`).
    layers: vec2<u32>,
    // Rays per pixel on views that accumulate the voxel term (at most `rays`).
    accumulated_rays: u32,
    // First word of the volume's brick bits, from `VoxelParams::brick_offset`.
    brick_offset: u32,
}

// Counts of this frame's buffers, which may be longer; `voxels::render::VoxelParams`.
struct VoxelParams {
    triangles: u32,
    volumes: u32,
    // Where the interior bits start: the grid buffer holds every volume's surface bits, then
    // every volume's interior bits in the same layout.
    solid_offset: u32,
    // Where the brick bits start, after the interior bits: one bit per brick of BRICK_CELLS³
    // cells, set where any of its cells is occupied, bricks ordered as cells are.
    brick_offset: u32,
}

// `voxels::component::BRICK_CELLS`.
const BRICK_CELLS: u32 = 8u;

const GOLDEN_RATIO_FRACTION: f32 = 0.618033988749895;

fn to_grid(volume: VoxelVolume, p: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(p, 1.0);
    return vec3<f32>(
        dot(volume.grid_from_world[0], h),
        dot(volume.grid_from_world[1], h),
        dot(volume.grid_from_world[2], h),
    );
}

// A world-space direction in grid units (the linear part of the map).
fn to_grid_direction(volume: VoxelVolume, d: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        dot(volume.grid_from_world[0].xyz, d),
        dot(volume.grid_from_world[1].xyz, d),
        dot(volume.grid_from_world[2].xyz, d),
    );
}

// A hash of the world-space noise cell holding `p`: the same surface point gets the same rays
// wherever the camera is (the object-space jitter of §6).
fn cell_hash(p: vec3<f32>, cell: f32) -> u32 {
    let c = vec3<i32>(floor(p / cell));
    return pcg_hash(bitcast<u32>(c.x) ^ pcg_hash(bitcast<u32>(c.y) ^ pcg_hash(bitcast<u32>(c.z))));
}

// A uniform number in [0, 1) from a hash, exact in f32.
fn unit_float(h: u32) -> f32 {
    return f32(h >> 8u) / 16777216.0;
}

// Ray `i` of `count`: a regular spiral over the cone of half-angle acos(cos_spread) around the
// z axis, uniform in solid angle, shifted by the jitter (j1, j2) ∈ [0, 1)².
fn ray_direction(i: u32, count: u32, cos_spread: f32, j1: f32, j2: f32) -> vec3<f32> {
    let cos_theta = 1.0 - (f32(i) + j1) / f32(count) * (1.0 - cos_spread);
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let phi = TAU * fract(f32(i) * GOLDEN_RATIO_FRACTION + j2);
    return vec3<f32>(cos(phi) * sin_theta, sin(phi) * sin_theta, cos_theta);
}

// Bricks per axis of a grid.
fn bricks_per_axis(volume: VoxelVolume) -> u32 {
    return (volume.resolution + BRICK_CELLS - 1u) / BRICK_CELLS;
}

// Linear index of cell `c` in its grid, or −1 outside the grid.
fn cell_index(volume: VoxelVolume, c: vec3<i32>) -> i32 {
    let n = i32(volume.resolution);
    if any(c < vec3<i32>(0)) || any(c >= vec3<i32>(n)) {
        return -1;
    }
    return c.x + n * (c.y + n * c.z);
}

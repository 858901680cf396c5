// Per-frame voxelization (Reinbothe, Boubekeur & Alexa 2009, §5): every triangle sets the bits of
// the cells it touches. One workgroup per triangle; its lanes share the triangle's columns along
// the axis its normal is closest to, and each cell the triangle's plane crosses in a column is
// kept when the separating-axis test (Akenine-Möller 2001) finds triangle and cell overlapping.
// The bit grid is cleared before the pass; `reference::voxels::voxelize` is the CPU twin.
// `mark_bricks` then builds the coarse level the rays skip empty space with.

#import bevy_dynamic_ao::voxel_grid::{
    BRICK_CELLS, VoxelParams, VoxelVolume, bricks_per_axis, cell_index,
}

struct GridTriangle {
    // Grid space; a.w holds the volume index as bits, b.w is 1 for a triangle of a closed mesh.
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> triangles: array<GridTriangle>;
@group(0) @binding(1) var<storage, read> volumes: array<VoxelVolume>;
@group(0) @binding(2) var<storage, read_write> grid: array<atomic<u32>>;
@group(0) @binding(3) var<uniform> params: VoxelParams;

const LANES: u32 = 64u;

// Whether the triangle (v0, v1, v2), relative to a cell's centre, overlaps the cell
// [−½, ½]³: no separating axis among the 3 cell normals, the triangle normal and the 9
// edge × axis products. Touching counts as overlapping.
fn triangle_overlaps_cell(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> bool {
    let edges = array<vec3<f32>, 3>(v1 - v0, v2 - v1, v0 - v2);
    for (var e = 0u; e < 3u; e++) {
        let edge = edges[e];
        for (var k = 0u; k < 3u; k++) {
            var unit = vec3<f32>(0.0);
            unit[k] = 1.0;
            let axis = cross(unit, edge);
            let p0 = dot(axis, v0);
            let p1 = dot(axis, v1);
            let p2 = dot(axis, v2);
            let r = 0.5 * (abs(axis.x) + abs(axis.y) + abs(axis.z));
            if min(p0, min(p1, p2)) > r || max(p0, max(p1, p2)) < -r {
                return false;
            }
        }
    }
    let lo = min(v0, min(v1, v2));
    let hi = max(v0, max(v1, v2));
    if any(lo > vec3<f32>(0.5)) || any(hi < vec3<f32>(-0.5)) {
        return false;
    }
    let normal = cross(edges[0], edges[1]);
    let r = 0.5 * (abs(normal.x) + abs(normal.y) + abs(normal.z));
    return abs(dot(normal, v0)) <= r;
}

// The 2D edge function of (a, b) at p, computed from the lexicographically smaller end, so the
// two triangles that share an edge get exactly opposite values.
fn edge_value(a: vec2<f32>, b: vec2<f32>, p: vec2<f32>) -> f32 {
    if a.x < b.x || (a.x == b.x && a.y < b.y) {
        return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    }
    return -((a.x - b.x) * (p.y - b.y) - (a.y - b.y) * (p.x - b.x));
}

// Whether a point with edge value e on edge a → b of a counter-clockwise triangle belongs to it:
// inside, or on an edge it owns (the top-left rule), so shared edges count once.
fn owns(e: f32, a: vec2<f32>, b: vec2<f32>) -> bool {
    let d = b - a;
    return e > 0.0 || (e == 0.0 && (d.y > 0.0 || (d.y == 0.0 && d.x < 0.0)));
}

// Interior of closed meshes (parity along z): in every column whose centre it covers, the
// triangle flips the interior bit of the lowest cell whose centre lies above it, and
// `fill_interior` then carries each flip up its column, so that cells above an odd number of
// surfaces end up set. Flipping every cell above the surface here instead cost one atomic per
// cell per triangle: a wall across the grid's columns rewrote most of the grid, 16 ms at 256³
// on a GPU.
fn fill_closed(volume: VoxelVolume, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, lane: u32) {
    let area = edge_value(a.xy, b.xy, c.xy);
    if area == 0.0 {
        return;
    }
    var p0 = a;
    var p1 = b;
    if area < 0.0 {
        p0 = b;
        p1 = a;
    }
    let p2 = c;
    let n = i32(volume.resolution);
    if min(a.z, min(b.z, c.z)) >= f32(n) {
        return;
    }
    let lo = max(vec2<i32>(floor(min(a.xy, min(b.xy, c.xy)))), vec2<i32>(0));
    let hi = min(vec2<i32>(floor(max(a.xy, max(b.xy, c.xy)))), vec2<i32>(n - 1));
    if any(lo > hi) {
        return;
    }
    let width = u32(hi.x - lo.x + 1);
    let columns = width * u32(hi.y - lo.y + 1);
    for (var column = lane; column < columns; column += LANES) {
        let x = lo.x + i32(column % width);
        let y = lo.y + i32(column / width);
        let q = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
        let e0 = edge_value(p1.xy, p2.xy, q);
        let e1 = edge_value(p2.xy, p0.xy, q);
        let e2 = edge_value(p0.xy, p1.xy, q);
        if !(owns(e0, p1.xy, p2.xy) && owns(e1, p2.xy, p0.xy) && owns(e2, p0.xy, p1.xy)) {
            continue;
        }
        let z = (e0 * p0.z + e1 * p1.z + e2 * p2.z) / abs(area);
        let k = max(i32(floor(z - 0.5)) + 1, 0);
        if k < n {
            let i = u32(x + n * (y + n * k));
            atomicXor(&grid[params.solid_offset + volume.offset + i / 32u], 1u << (i % 32u));
        }
    }
}

// The running XOR up each column of the flips `fill_closed` left: afterwards a cell's interior
// bit is the parity of the closed surfaces below its centre. Invocation `id.x` of row `id.y`
// (a volume) takes one word of a z layer where layers fill whole words (resolution a multiple
// of 8), the 32 columns of its bits at once; otherwise one column (x, y), whose bits only it
// touches while its neighbours flip theirs in the same words.
@compute @workgroup_size(64, 1, 1)
fn fill_interior(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.y >= params.volumes {
        return;
    }
    let volume = volumes[id.y];
    let n = volume.resolution;
    let base = params.solid_offset + volume.offset;
    let columns = n * n;
    if columns % 32u == 0u {
        let words = columns / 32u;
        if id.x >= words {
            return;
        }
        var parity = 0u;
        for (var k = 0u; k < n; k++) {
            let w = base + id.x + words * k;
            parity ^= atomicLoad(&grid[w]);
            atomicStore(&grid[w], parity);
        }
        return;
    }
    let column = id.x;
    if column >= columns {
        return;
    }
    var parity = 0u;
    for (var k = 0u; k < n; k++) {
        let i = column + n * n * k;
        let flipped = (atomicLoad(&grid[base + i / 32u]) >> (i % 32u)) & 1u;
        parity ^= flipped;
        if parity != flipped {
            atomicXor(&grid[base + i / 32u], 1u << (i % 32u));
        }
    }
}

// Whether any of bits `first` ..= `last`, which lie in at most two words, is set in the grid
// whose bits start at word `base`.
fn any_bit(base: u32, first: u32, last: u32) -> bool {
    let low = ~0u << (first % 32u);
    let high = ~0u >> (31u - last % 32u);
    let w0 = first / 32u;
    let w1 = last / 32u;
    if w0 == w1 {
        return (atomicLoad(&grid[base + w0]) & low & high) != 0u;
    }
    return (atomicLoad(&grid[base + w0]) & low) != 0u || (atomicLoad(&grid[base + w1]) & high) != 0u;
}

// The coarse occupancy level, after `fill_interior`: a brick's bit is set where any of its cells
// holds a surface or an interior bit. Invocation `id.x` of row `id.y` (a volume) takes, where
// rows of cells fill whole words (resolution a multiple of 32), the BRICK_CELLS² words of a
// word's width of bricks (32 / BRICK_CELLS of them, whose bits lie in one word of brick bits:
// a quarter of the reads of a brick at a time); otherwise one brick, reading its rows a word or
// two at a time.
@compute @workgroup_size(64, 1, 1)
fn mark_bricks(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.y >= params.volumes {
        return;
    }
    let volume = volumes[id.y];
    let n = volume.resolution;
    let bricks = bricks_per_axis(volume);
    let brick_base = params.brick_offset + volume.brick_offset;
    if n % 32u == 0u {
        let words = n / 32u;
        if id.x >= words * bricks * bricks {
            return;
        }
        let word = id.x % words;
        let by = (id.x / words) % bricks;
        let bz = id.x / (words * bricks);
        var bits = 0u;
        for (var z = bz * BRICK_CELLS; z < (bz + 1u) * BRICK_CELLS; z++) {
            for (var y = by * BRICK_CELLS; y < (by + 1u) * BRICK_CELLS; y++) {
                let w = word + words * (y + n * z);
                bits |= atomicLoad(&grid[volume.offset + w]);
                bits |= atomicLoad(&grid[params.solid_offset + volume.offset + w]);
            }
        }
        var mask = 0u;
        for (var k = 0u; k < 32u / BRICK_CELLS; k++) {
            let run = (bits >> (k * BRICK_CELLS)) & ((1u << BRICK_CELLS) - 1u);
            mask |= select(0u, 1u << k, run != 0u);
        }
        // The word's bricks are consecutive in one word of brick bits: `bricks` is a multiple of
        // 32 / BRICK_CELLS.
        let first = word * (32u / BRICK_CELLS) + bricks * (by + bricks * bz);
        if mask != 0u {
            atomicOr(&grid[brick_base + first / 32u], mask << (first % 32u));
        }
        return;
    }
    if id.x >= bricks * bricks * bricks {
        return;
    }
    let lo = vec3<u32>(id.x % bricks, (id.x / bricks) % bricks, id.x / (bricks * bricks)) * BRICK_CELLS;
    let hi = min(lo + BRICK_CELLS, vec3<u32>(n));
    for (var z = lo.z; z < hi.z; z++) {
        for (var y = lo.y; y < hi.y; y++) {
            let first = lo.x + n * (y + n * z);
            let last = first + hi.x - lo.x - 1u;
            if any_bit(volume.offset, first, last)
                || any_bit(params.solid_offset + volume.offset, first, last) {
                atomicOr(&grid[brick_base + id.x / 32u], 1u << (id.x % 32u));
                return;
            }
        }
    }
}

@compute @workgroup_size(64, 1, 1)
fn voxelize(
    @builtin(workgroup_id) workgroup: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let index = workgroup.x + workgroup.y * workgroups.x;
    if index >= params.triangles {
        return;
    }
    let t = triangles[index];
    let volume = volumes[bitcast<u32>(t.a.w)];
    let a = t.a.xyz;
    let b = t.b.xyz;
    let c = t.c.xyz;
    if t.b.w != 0.0 {
        fill_closed(volume, a, b, c, lane);
    }
    let last = vec3<i32>(i32(volume.resolution) - 1);
    let lo = clamp(vec3<i32>(floor(min(a, min(b, c)))), vec3<i32>(0), last);
    let hi = clamp(vec3<i32>(floor(max(a, max(b, c)))), vec3<i32>(0), last);

    // Columns run along the dominant axis d of the normal; (u, v) span the other two.
    let normal = cross(b - a, c - a);
    let m = abs(normal);
    var d = 2u;
    if m.x >= m.y && m.x >= m.z {
        d = 0u;
    } else if m.y >= m.z {
        d = 1u;
    }
    let u = (d + 1u) % 3u;
    let v = (d + 2u) % 3u;
    let width = u32(hi[u] - lo[u] + 1);
    let columns = width * u32(hi[v] - lo[v] + 1);
    let plane = dot(normal, a);
    for (var column = lane; column < columns; column += LANES) {
        let cu = lo[u] + i32(column % width);
        let cv = lo[v] + i32(column / width);
        // The span of the triangle's plane over the column's square bounds the cells to test.
        var first = lo[d];
        var end = hi[d];
        if m[d] > 0.0 {
            var z_min = 1e30;
            var z_max = -1e30;
            for (var k = 0u; k < 4u; k++) {
                let pu = f32(cu) + f32(k & 1u);
                let pv = f32(cv) + f32(k >> 1u);
                let z = (plane - normal[u] * pu - normal[v] * pv) / normal[d];
                z_min = min(z_min, z);
                z_max = max(z_max, z);
            }
            first = max(first, i32(floor(z_min - 1e-3)));
            end = min(end, i32(floor(z_max + 1e-3)));
        }
        for (var cd = first; cd <= end; cd++) {
            var cell = vec3<i32>(0);
            cell[d] = cd;
            cell[u] = cu;
            cell[v] = cv;
            let centre = vec3<f32>(cell) + 0.5;
            if triangle_overlaps_cell(a - centre, b - centre, c - centre) {
                let i = cell_index(volume, cell);
                if i >= 0 {
                    atomicOr(&grid[volume.offset + u32(i) / 32u], 1u << (u32(i) % 32u));
                }
            }
        }
    }
}

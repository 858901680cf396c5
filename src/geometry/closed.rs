//! Whether a triangle soup encloses a volume.

use bevy::math::Vec3;
use bevy::platform::collections::HashMap;

/// Whether a triangle soup encloses a volume: every edge, with vertices at the same position
/// welded (meshes split vertices along hard edges and seams), belongs to exactly two triangles.
pub fn is_closed(triangles: impl IntoIterator<Item = [Vec3; 3]>) -> bool {
    let mut welded: HashMap<[u32; 3], u32> = HashMap::default();
    let mut id = |p: Vec3| {
        let next = welded.len() as u32;
        *welded.entry(p.to_array().map(f32::to_bits)).or_insert(next)
    };
    let mut edges: HashMap<(u32, u32), u32> = HashMap::default();
    for triangle in triangles {
        let ids = triangle.map(&mut id);
        for k in 0..3 {
            let (a, b) = (ids[k], ids[(k + 1) % 3]);
            if a == b {
                return false;
            }
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    !edges.is_empty() && edges.values().all(|&count| count == 2)
}

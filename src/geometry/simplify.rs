//! Fewer triangles for the same surface, by vertex clustering (Rossignac & Borrel 1993): the
//! vertices that fall in one cell of a uniform grid become one, the cell's first vertex, and the
//! triangles that collapse are dropped. Each vertex kept is one of the mesh's own, so the coarse
//! surface lies within a cell of the fine one everywhere the fine one has vertices.

use bevy::math::Vec3;
use bevy::platform::collections::HashMap;

/// A mesh with fewer triangles, over a vertex list of its own.
#[derive(Clone, Debug, PartialEq)]
pub struct Simplified {
    /// The vertices kept, mesh space, metres: a subset of the input's.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`, wound as the input's.
    pub triangles: Vec<[u32; 3]>,
    /// The grid's cell size, metres: no vertex moved farther than its diagonal.
    pub cell: f32,
}

/// How many times [`simplify`] widens its cells looking for a mesh small enough.
const TRIES: usize = 8;
/// How much wider each try's cells are than the last's.
const WIDEN: f32 = 1.3;

/// `triangles` over `positions` (mesh space) with at most `max_triangles` of them, clustered on
/// the finest grid that gets there among cells of twice the mean edge length widened by 30% per
/// try: on a surface of even triangles that is about a quarter of them. `None` when the mesh
/// already has no more than `max_triangles`, has no finite edge, or when eight tries do not get
/// there.
pub fn simplify(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    max_triangles: usize,
) -> Option<Simplified> {
    if triangles.len() <= max_triangles {
        return None;
    }
    let (mut sum, mut edges) = (0.0f64, 0usize);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let (Some(a), Some(b)) = (positions.get(a), positions.get(b)) else {
                continue;
            };
            let length = a.distance(*b);
            if length.is_finite() {
                sum += f64::from(length);
                edges += 1;
            }
        }
    }
    if edges == 0 || sum <= 0.0 {
        return None;
    }
    let mut cell = 2.0 * (sum / edges as f64) as f32;
    for _ in 0..TRIES {
        let simplified = cluster(positions, triangles, cell);
        if simplified.triangles.len() <= max_triangles && !simplified.triangles.is_empty() {
            return Some(simplified);
        }
        cell *= WIDEN;
    }
    None
}

/// `triangles` clustered on a grid of `cell` metres. Triangles with a vertex out of range or not
/// finite are dropped, as are those that collapse and all but one of those that end up on the
/// same three vertices in the same turn.
pub fn cluster(positions: &[Vec3], triangles: &[[u32; 3]], cell: f32) -> Simplified {
    let mut cells: HashMap<[i32; 3], u32> = HashMap::default();
    let mut kept = Vec::new();
    // The vertex each input vertex became, filled as triangles reach it.
    let mut became = vec![u32::MAX; positions.len()];
    let mut out = Vec::with_capacity(triangles.len() / 3);
    let mut seen = bevy::platform::collections::HashSet::<[u32; 3]>::default();
    'triangles: for t in triangles {
        let mut corners = [0u32; 3];
        for (corner, &i) in corners.iter_mut().zip(t) {
            let Some(p) = positions.get(i as usize).filter(|p| p.is_finite()) else {
                continue 'triangles;
            };
            if became[i as usize] == u32::MAX {
                let key = (*p / cell).floor().as_ivec3().to_array();
                became[i as usize] = *cells.entry(key).or_insert_with(|| {
                    kept.push(*p);
                    (kept.len() - 1) as u32
                });
            }
            *corner = became[i as usize];
        }
        let [a, b, c] = corners;
        if a == b || b == c || a == c {
            continue;
        }
        // The same triangle in the same turn, whichever corner it starts at.
        let first = (0..3).min_by_key(|&k| corners[k]).unwrap_or(0);
        let key = [0, 1, 2].map(|k| corners[(first + k) % 3]);
        if seen.insert(key) {
            out.push(corners);
        }
    }
    Simplified {
        positions: kept,
        triangles: out,
        cell,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat grid of `n` × `n` quads of 1 cm, two triangles each, wound towards +z.
    fn grid(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                positions.push(Vec3::new(x as f32, y as f32, 0.0) * 0.01);
            }
        }
        let at = |x: u32, y: u32| y * (n + 1) + x;
        let mut triangles = Vec::new();
        for y in 0..n {
            for x in 0..n {
                triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
            }
        }
        (positions, triangles)
    }

    fn normal(positions: &[Vec3], t: [u32; 3]) -> Vec3 {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        (b - a).cross(c - a)
    }

    #[test]
    fn a_grid_keeps_a_quarter_of_its_triangles_or_fewer_facing_as_before() {
        let (positions, triangles) = grid(64);
        let simplified = simplify(&positions, &triangles, triangles.len() / 4).unwrap();
        assert!(simplified.triangles.len() <= triangles.len() / 4);
        // Not emptied: a grid of cells twice the edge keeps about a quarter.
        assert!(
            simplified.triangles.len() > triangles.len() / 8,
            "{}",
            simplified.triangles.len()
        );
        for t in &simplified.triangles {
            assert!(normal(&simplified.positions, *t).z > 0.0);
        }
        // Every vertex kept is one of the input's.
        for p in &simplified.positions {
            assert!(positions.contains(p));
        }
    }

    #[test]
    fn the_coarse_grid_covers_the_fine_one_but_a_cell_at_its_rim() {
        let (positions, triangles) = grid(64);
        let simplified = simplify(&positions, &triangles, triangles.len() / 4).unwrap();
        let area: f32 = simplified
            .triangles
            .iter()
            .map(|t| normal(&simplified.positions, *t).length() / 2.0)
            .sum();
        let full = 0.64f32 * 0.64;
        let rim = 4.0 * 0.64 * simplified.cell;
        assert!(
            area <= full + 1e-4 && area >= full - rim,
            "{area} of {full}"
        );
    }

    #[test]
    fn small_or_broken_meshes_are_left_alone() {
        let (positions, triangles) = grid(4);
        assert_eq!(simplify(&positions, &triangles, 32), None);
        // Indices past the vertices, and a vertex at NaN: nothing to measure.
        let broken = vec![[0, 1, 99]; 64];
        assert_eq!(simplify(&positions[..2], &broken, 8), None);
        let mut nan = positions.clone();
        nan[0] = Vec3::NAN;
        let kept = cluster(&nan, &triangles, 0.02);
        assert!(kept.positions.iter().all(|p| p.is_finite()));
    }
}

//! Baking an ambient occlusion field on the CPU (Malmer et al. 2005, §3.2–3.4): rays from every
//! grid point against the object's triangles (the [`reference`](crate::reference) BVH), in
//! parallel over slices of the grid, with the same directions everywhere so the result does not
//! depend on the number of threads.

use std::sync::atomic::{AtomicUsize, Ordering};

use bevy::math::{UVec3, Vec3};

use super::format::{AoFieldData, MAX_RESOLUTION};
use crate::reference::bvh::Bvh;
use crate::reference::scene::Triangle;

/// How to bake a field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeSettings {
    /// Grid cells per axis. Range 2 to 256. Default 32.
    pub resolution: u32,
    /// ε of eq. 4: occlusion below this is neglected, which sets the grid's extent. Range
    /// (0, 1). Default 0.1, the paper's value (about three times the object's half size).
    pub epsilon: f32,
    /// Rays per grid point over the whole sphere. Default 256.
    pub rays: u32,
    /// Rescale values so the largest one on the grid's boundary becomes 0 (§3.4.1): no visible
    /// edge where the field ends. Default `true`.
    pub rescale_border: bool,
    /// Replace fully occluded cells (inside the object) by the mean of their open neighbours
    /// (§3.4.2), so interpolation at the surface reads sensible values. Default `true`.
    pub fill_interior: bool,
}

impl Default for BakeSettings {
    fn default() -> Self {
        Self {
            resolution: 32,
            epsilon: 0.1,
            rays: 256,
            rescale_border: true,
            fill_interior: true,
        }
    }
}

/// Why a field could not be baked.
#[derive(Clone, Debug, PartialEq)]
pub enum BakeError {
    /// The object has no usable triangle.
    NoTriangles,
    /// A setting is out of range; the message says which.
    BadSettings(String),
}

impl std::fmt::Display for BakeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoTriangles => write!(f, "the object has no usable triangle to bake"),
            Self::BadSettings(why) => write!(f, "bad bake settings: {why}"),
        }
    }
}

impl std::error::Error for BakeError {}

/// The grid box of eq. 4 around an object's bounding box `[min, max]`: along each axis i, with
/// half size r_i and A_i the bounding box's area seen along that axis,
/// e_i = r_i + sqrt(A_i / (4π ε)). Returns the centre and the half extents e_i.
pub fn grid_box(min: Vec3, max: Vec3, epsilon: f32) -> (Vec3, Vec3) {
    let r = (max - min) * 0.5;
    let area = Vec3::new(4.0 * r.y * r.z, 4.0 * r.x * r.z, 4.0 * r.x * r.y);
    let e = r + (area / (4.0 * std::f32::consts::PI * epsilon)).map(f32::sqrt);
    ((min + max) * 0.5, e)
}

/// `count` directions spread evenly over the unit sphere (a Fibonacci lattice).
fn sphere_directions(count: u32) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..count)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f32 + 1.0) / count as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// Bakes the field of `triangles` (mesh space). `progress(done, total)` is called as slices of
/// the grid finish, from the baking threads.
pub fn bake(
    triangles: Vec<Triangle>,
    settings: &BakeSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<AoFieldData, BakeError> {
    if !(2..=MAX_RESOLUTION).contains(&settings.resolution) {
        return Err(BakeError::BadSettings(format!(
            "resolution {} is outside 2..={MAX_RESOLUTION}",
            settings.resolution
        )));
    }
    if !(settings.epsilon > 0.0 && settings.epsilon < 1.0) {
        return Err(BakeError::BadSettings(format!(
            "epsilon {} is outside (0, 1)",
            settings.epsilon
        )));
    }
    if settings.rays == 0 {
        return Err(BakeError::BadSettings("rays must be at least 1".into()));
    }
    let triangles: Vec<Triangle> = triangles
        .into_iter()
        .filter(|t| {
            t.vertices.iter().all(|v| v.is_finite())
                && t.face_normal().length_squared() > f32::MIN_POSITIVE
        })
        .collect();
    if triangles.is_empty() {
        return Err(BakeError::NoTriangles);
    }
    let (min, max) = triangles
        .iter()
        .flat_map(|t| t.vertices)
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let (center, half_extent) = grid_box(min, max, settings.epsilon);
    let resolution = UVec3::splat(settings.resolution);
    let bvh = Bvh::new(triangles);
    let directions = sphere_directions(settings.rays);
    let cell_size = 2.0 * half_extent / resolution.as_vec3();
    let origin = center - half_extent;

    let n = settings.resolution as usize;
    let mut cells = vec![[0.0f32; 4]; n * n * n];
    let done = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    let slice = n * n;
    std::thread::scope(|scope| {
        // Interleaved slices keep the threads busy when the object fills only part of the grid.
        let mut chunks: Vec<Vec<(usize, &mut [[f32; 4]])>> =
            (0..threads).map(|_| Vec::new()).collect();
        for (z, chunk) in cells.chunks_mut(slice).enumerate() {
            chunks[z % threads].push((z, chunk));
        }
        for work in chunks {
            let (bvh, directions, done) = (&bvh, &directions, &done);
            scope.spawn(move || {
                for (z, chunk) in work {
                    for y in 0..n {
                        for x in 0..n {
                            let p = origin
                                + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * cell_size;
                            chunk[y * n + x] = sample(bvh, directions, p);
                        }
                    }
                    progress(done.fetch_add(1, Ordering::Relaxed) + 1, n);
                }
            });
        }
    });

    let mut field = AoFieldData {
        resolution,
        center,
        half_extent,
        cells,
    };
    if settings.fill_interior {
        fill_interior(&mut field);
    }
    if settings.rescale_border {
        rescale_border(&mut field);
    }
    Ok(field)
}

/// Occlusion (eq. 2: the blocked fraction of all directions) and average occluded direction at
/// `p`.
fn sample(bvh: &Bvh, directions: &[Vec3], p: Vec3) -> [f32; 4] {
    let mut blocked = 0u32;
    let mut sum = Vec3::ZERO;
    for &d in directions {
        if bvh.any_hit(p, d, 0.0, f32::INFINITY) {
            blocked += 1;
            sum += d;
        }
    }
    let a = blocked as f32 / directions.len() as f32;
    let d = sum.normalize_or_zero();
    [a, d.x, d.y, d.z]
}

/// §3.4.2: cells inside the object (every ray blocked) take the mean of their neighbours that
/// see out, so a surface point between an inside and an outside cell interpolates sensibly.
/// One pass, as in the paper: cells deeper inside keep 1, and no surface point reads them.
pub fn fill_interior(field: &mut AoFieldData) {
    let r = field.resolution.as_ivec3();
    let original = field.cells.clone();
    for z in 0..r.z {
        for y in 0..r.y {
            for x in 0..r.x {
                let i = field.index(x as u32, y as u32, z as u32);
                if original[i][0] < 1.0 {
                    continue;
                }
                let (mut sum, mut dir, mut count) = (0.0, Vec3::ZERO, 0);
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let (nx, ny, nz) = (x + dx, y + dy, z + dz);
                            if nx < 0 || ny < 0 || nz < 0 || nx >= r.x || ny >= r.y || nz >= r.z {
                                continue;
                            }
                            let c = original[field.index(nx as u32, ny as u32, nz as u32)];
                            if c[0] < 1.0 {
                                sum += c[0];
                                dir += Vec3::new(c[1], c[2], c[3]);
                                count += 1;
                            }
                        }
                    }
                }
                if count > 0 {
                    let d = dir.normalize_or_zero();
                    field.cells[i] = [sum / count as f32, d.x, d.y, d.z];
                }
            }
        }
    }
}

/// Values at or below this are rescaled by §3.4.1; larger ones are kept.
const RESCALE_LIMIT: f32 = 0.3;

/// §3.4.1: with V_M the largest occlusion on the grid's boundary, every value V ≤ 0.3 becomes
/// 0.3 (V − V_M) / (0.3 − V_M) (and at least 0), so the field fades to 0 at its boundary and
/// joins the open space outside without a step. V_M is capped just below 0.3, where the formula
/// would break down (a grid far too small for its object).
pub fn rescale_border(field: &mut AoFieldData) {
    let r = field.resolution;
    let mut boundary_max = 0.0f32;
    for z in 0..r.z {
        for y in 0..r.y {
            for x in 0..r.x {
                let on_boundary =
                    x == 0 || y == 0 || z == 0 || x == r.x - 1 || y == r.y - 1 || z == r.z - 1;
                if on_boundary {
                    boundary_max = boundary_max.max(field.cells[field.index(x, y, z)][0]);
                }
            }
        }
    }
    let vm = boundary_max.min(RESCALE_LIMIT - 0.01);
    for cell in &mut field.cells {
        if cell[0] <= RESCALE_LIMIT {
            cell[0] = (RESCALE_LIMIT * (cell[0] - vm) / (RESCALE_LIMIT - vm)).max(0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use bevy::math::Affine3A;
    use bevy::prelude::*;

    use super::*;
    use crate::reference::scene::TriangleScene;

    fn cube() -> Vec<Triangle> {
        let mut scene = TriangleScene::default();
        scene.add_mesh(&Cuboid::new(1.0, 1.0, 1.0).into(), Affine3A::IDENTITY);
        scene.triangles
    }

    /// Blocked fraction of all directions at `p`, by testing every triangle for each of many
    /// pseudo-random directions: no BVH, no shared direction set.
    fn brute_force(triangles: &[Triangle], p: Vec3, rays: u32) -> f32 {
        let mut blocked = 0;
        let mut state = 12345u32;
        let mut next = || {
            state = crate::reference::sampling::pcg_hash(state);
            state as f32 / u32::MAX as f32
        };
        for _ in 0..rays {
            let z = 2.0 * next() - 1.0;
            let phi = std::f32::consts::TAU * next();
            let r = (1.0 - z * z).sqrt();
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let hit = triangles.iter().any(|t| {
                let [a, b, c] = t.vertices;
                let (e1, e2) = (b - a, c - a);
                let h = d.cross(e2);
                let det = e1.dot(h);
                if det.abs() < 1e-9 {
                    return false;
                }
                let s = p - a;
                let u = s.dot(h) / det;
                let q = s.cross(e1);
                let v = d.dot(q) / det;
                u >= 0.0 && v >= 0.0 && u + v <= 1.0 && e2.dot(q) / det > 0.0
            });
            blocked += u32::from(hit);
        }
        blocked as f32 / rays as f32
    }

    #[test]
    fn extent_follows_equation_4() {
        let (center, e) = grid_box(Vec3::splat(-0.5), Vec3::splat(0.5), 0.1);
        assert_eq!(center, Vec3::ZERO);
        // r = 0.5, A = 1: e = 0.5 + sqrt(1 / 0.4π) ≈ 1.392, about 3 r as the paper says.
        assert!(
            (e.x - 1.392).abs() < 1e-3 && e.x == e.y && e.y == e.z,
            "{e}"
        );
        // An elongated box gets a grid that is relatively thinner along its long axis.
        let (_, e) = grid_box(
            Vec3::new(-1.0, -0.25, -0.25),
            Vec3::new(1.0, 0.25, 0.25),
            0.1,
        );
        assert!((e.x - (1.0 + (0.25f32 / (0.4 * std::f32::consts::PI)).sqrt())).abs() < 1e-4);
        assert!(e.x / 1.0 < e.y / 0.25);
    }

    #[test]
    fn baked_values_match_a_brute_force_ray_cast() {
        let settings = BakeSettings {
            resolution: 8,
            rays: 1024,
            rescale_border: false,
            fill_interior: false,
            ..default()
        };
        let triangles = cube();
        let field = bake(triangles.clone(), &settings, &|_, _| {}).unwrap();
        let cell = 2.0 * field.half_extent / 8.0;
        let mut compared = 0;
        for (x, y, z) in [
            (0, 0, 0),
            (1, 3, 4),
            (2, 4, 4),
            (3, 7, 2),
            (5, 5, 1),
            (7, 4, 4),
        ] {
            let p = field.center - field.half_extent
                + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * cell;
            let expected = brute_force(&triangles, p, 4096);
            let got = field.cells[field.index(x, y, z)][0];
            // 1024 lattice rays against 4096 random ones: both within about 0.01 of the truth.
            assert!(
                (got - expected).abs() < 0.03,
                "cell ({x},{y},{z}) at {p}: baked {got}, brute force {expected}"
            );
            compared += 1;
        }
        assert_eq!(compared, 6);
        // Beside the cube on +x, the occluded directions point back at it.
        let c = field.cells[field.index(7, 4, 4)];
        assert!(c[1] < -0.9, "{c:?}");
    }

    #[test]
    fn border_rescale_leaves_no_step_at_the_boundary() {
        let settings = BakeSettings {
            resolution: 12,
            rays: 256,
            ..default()
        };
        let field = bake(cube(), &settings, &|_, _| {}).unwrap();
        let r = field.resolution;
        let mut boundary_max = 0.0f32;
        let mut inner_max = 0.0f32;
        for z in 0..r.z {
            for y in 0..r.y {
                for x in 0..r.x {
                    let a = field.cells[field.index(x, y, z)][0];
                    let edge = [x, y, z].iter().any(|&c| c == 0 || c == r.x - 1);
                    if edge {
                        boundary_max = boundary_max.max(a);
                    } else {
                        inner_max = inner_max.max(a);
                    }
                }
            }
        }
        // Outside the grid there is no occlusion, so the boundary must be 0 to meet it.
        assert_eq!(boundary_max, 0.0);
        assert!(
            inner_max > 0.3,
            "the contact occlusion must survive the rescale"
        );
        // Without the rescale the boundary holds the occlusion eq. 4 neglects, up to about ε.
        let raw = bake(
            cube(),
            &BakeSettings {
                rescale_border: false,
                ..settings
            },
            &|_, _| {},
        )
        .unwrap();
        let raw_max = raw.cells.iter().map(|c| c[0]).fold(0.0f32, f32::max);
        assert!(raw_max > 0.0);
    }

    #[test]
    fn interior_cells_take_their_open_neighbours_values() {
        let settings = BakeSettings {
            resolution: 8,
            rays: 128,
            rescale_border: false,
            ..default()
        };
        let filled = bake(cube(), &settings, &|_, _| {}).unwrap();
        let raw = bake(
            cube(),
            &BakeSettings {
                fill_interior: false,
                ..settings
            },
            &|_, _| {},
        )
        .unwrap();
        let inside: Vec<usize> = (0..raw.cells.len())
            .filter(|&i| raw.cells[i][0] >= 1.0)
            .collect();
        assert!(!inside.is_empty(), "the cube should hold interior cells");
        assert!(inside.iter().any(|&i| filled.cells[i][0] < 1.0));
    }

    #[test]
    fn bad_input_is_refused() {
        assert_eq!(
            bake(Vec::new(), &BakeSettings::default(), &|_, _| {}),
            Err(BakeError::NoTriangles)
        );
        for settings in [
            BakeSettings {
                resolution: 1,
                ..default()
            },
            BakeSettings {
                epsilon: 0.0,
                ..default()
            },
            BakeSettings {
                rays: 0,
                ..default()
            },
        ] {
            assert!(matches!(
                bake(cube(), &settings, &|_, _| {}),
                Err(BakeError::BadSettings(_))
            ));
        }
    }

    #[test]
    fn baking_is_deterministic() {
        let settings = BakeSettings {
            resolution: 6,
            rays: 64,
            ..default()
        };
        assert_eq!(
            bake(cube(), &settings, &|_, _| {}),
            bake(cube(), &settings, &|_, _| {})
        );
    }
}

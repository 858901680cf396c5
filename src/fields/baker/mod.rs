//! Baking an ambient occlusion field on the CPU (Malmer et al. 2005, §3.2–3.4): rays from every
//! grid point against the object's triangles (the [`reference`](crate::reference) BVH), in
//! parallel over slices of the grid, with the same directions everywhere so the result does not
//! depend on the number of threads.
//!
//! Every grid point stores the occlusion and average occluded direction twice: for hits within
//! the reach (the camera's radius R) and within the near field's reach, so that the far field can
//! leave to the near field what it counts (see `FarFieldBlend::CountOnce`). It also stores its
//! signed distance to the object, so that the lookup never blends values from inside the object
//! or from the far side of a thin one into a point on its surface, and leaves the object's own
//! surface to the near field. The near field reaches only its own distance there, so grid points
//! next to the surface also store what lies beyond it: rays over the cosine-weighted hemisphere
//! of the nearest surface point, the share that meets the object between the near reach and R.

use std::sync::atomic::{AtomicUsize, Ordering};

use bevy::math::{UVec3, Vec3};
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

use super::format::{AoFieldData, MAX_RESOLUTION};
use crate::geometry::bvh::Bvh;
use crate::geometry::triangles::Triangle;
use crate::settings::{DEFAULT_NEAR_FIELD_RADIUS, DEFAULT_RADIUS};

mod axes;
mod own_surface;
mod paper;
mod sample;

use axes::AxisHemispheres;
use own_surface::{OwnSurface, cosine_hemisphere};
pub use paper::{fill_interior, rescale_border};
use sample::{Cell, SampleDistances, sample};

/// How far a field's occlusion reaches, which also sets its grid's extent.
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Clone, Debug, PartialEq)]
pub enum FieldReach {
    /// The radius of the cameras that show the field ([`DynamicAo::radius`](crate::DynamicAo::radius),
    /// the largest among them) and their near-field radius: the field is baked again, in the
    /// background, when they change. Baked outside an app (`ao_bake`), the crate's defaults.
    CameraRadius,
    /// Hits within `reach` metres, with the near field's share within `near` metres.
    Distance {
        /// R, metres, > 0.
        reach: f32,
        /// The near field's reach, metres, in (0, reach].
        near: f32,
    },
    /// Hits at any distance, the paper's; the grid's extent follows eq. 4 with this ε ∈ (0, 1)
    /// (0.1 in the paper: about three times the object's half size), and occlusion beyond it
    /// is dropped.
    Unlimited {
        /// ε of eq. 4.
        epsilon: f32,
    },
}

/// How to bake a field.
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub struct BakeSettings {
    /// Grid cells along the longest side of the grid box; the other sides get cells of about
    /// the same size, within a budget of `resolution`³ cells, but a thin side (a floor's height)
    /// gets at least [`THIN_AXIS_CELLS`] × `resolution` ([`grid_resolution`]). Range 2 to 256.
    /// Default: [`BakeSettings::DEFAULT_RESOLUTION`] (32).
    pub resolution: u32,
    /// How far occlusion counts. Default: [`FieldReach::CameraRadius`].
    pub reach: FieldReach,
    /// Rays per grid point over the whole sphere. Range 1 to [`BakeSettings::MAX_RAYS`].
    /// Default: [`BakeSettings::DEFAULT_RAYS`] (256).
    pub rays: u32,
    /// Rescale values so the largest one on the grid's boundary becomes 0 (§3.4.1): no visible
    /// edge where an unlimited field ends. It lowers every value up to 0.3. Default: `false`: a
    /// field with a finite reach is 0 at its boundary already.
    pub rescale_border: bool,
    /// Replace fully occluded cells (inside the object) by the mean of their open neighbours
    /// (§3.4.2). Default: `false`: the lookup skips cells inside the object.
    pub fill_interior: bool,
    /// Also store, per grid point, how far the cone model misses the traced occlusion of the
    /// six axis hemispheres (what a receiver facing ±x, ±y or ±z sees), which the lookup adds
    /// back by the receiver's normal. The paper's cone alone overestimates what a large flat
    /// occluder casts (the floor beside a wall: 0.465 where the truth has 0.424 at R = 2 m).
    /// Default: `true`; `false` in [`BakeSettings::paper`].
    pub axis_correction: bool,
}

impl Default for BakeSettings {
    fn default() -> Self {
        Self {
            resolution: Self::DEFAULT_RESOLUTION,
            reach: FieldReach::CameraRadius,
            rays: Self::DEFAULT_RAYS,
            rescale_border: false,
            fill_interior: false,
            axis_correction: true,
        }
    }
}

impl BakeSettings {
    /// Default grid cells along the longest side.
    pub const DEFAULT_RESOLUTION: u32 = 32;
    /// Default rays per grid point.
    pub const DEFAULT_RAYS: u32 = 256;
    /// Most rays per grid point: past a few thousand the field's noise is below what 8-bit
    /// lighting shows, and the bake's time grows with the rays.
    pub const MAX_RAYS: u32 = 16_384;

    #[cfg(test)]
    fn without_fixes(self) -> Self {
        Self {
            rescale_border: false,
            fill_interior: false,
            ..self
        }
    }

    /// The paper's settings: hits at any distance, the grid extent of eq. 4 with ε = 0.1, the
    /// border rescale and the interior fill, and the cone without axis corrections.
    pub fn paper() -> Self {
        Self {
            reach: FieldReach::Unlimited { epsilon: 0.1 },
            rescale_border: true,
            fill_interior: true,
            axis_correction: false,
            ..Self::default()
        }
    }

    /// These settings with [`FieldReach::CameraRadius`] made concrete for a camera of this radius
    /// and near-field reach (metres).
    pub fn for_camera(self, radius: f32, near: f32) -> Self {
        match self.reach {
            FieldReach::CameraRadius => Self {
                reach: FieldReach::Distance {
                    reach: radius,
                    near: near.min(radius),
                },
                ..self
            },
            _ => self,
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

/// The least share of `resolution` a thin axis of the grid gets in cells. With cubic cells a 20 m
/// floor's field at R = 0.75 m had 4 cells of 36 cm across its height, and a box standing on the
/// floor read stripes of the floor's field up its sides (AnimatedMorphCube on a floor joined to
/// the default: 0.0156 RMSE against 0.0104 without fields); 3/8 (12 cells of 13 cm) read 0.0096,
/// and 1/2 darkened where a counter meets its floor (BENCHMARKS.md, "A floor's field across its
/// height").
pub const THIN_AXIS_CELLS: f32 = 0.375;

/// Cells per axis for a grid box of `half_extent`: about cubic cells, `2 × resolution` along the
/// longest side at most, `resolution`³ in all at most, and at least 2 per axis. An axis that
/// cubic cells would cross in fewer than [`THIN_AXIS_CELLS`] × `resolution` cells (a floor's
/// height, a wall's thickness) gets that many, and the other axes share what is left of the
/// budget: across a thin object the field changes over R on either side of it, along it only near
/// its edges.
pub fn grid_resolution(half_extent: Vec3, resolution: u32) -> UVec3 {
    let budget = (resolution as f32).powi(3);
    let e = half_extent.max(Vec3::splat(1e-6 * half_extent.max_element().max(1e-6)));
    let k = (budget / (e.x * e.y * e.z)).cbrt();
    let longest = resolution as f32 / e.max_element();
    let mut cells = e * k.min(longest * 2.0);
    let least = ((resolution as f32 * THIN_AXIS_CELLS) as u32).max(2) as f32;
    let thin = cells.cmplt(Vec3::splat(least));
    if thin.any() && !thin.all() {
        let raised = Vec3::select(thin, Vec3::splat(least), Vec3::ONE);
        let rest = Vec3::select(thin, Vec3::ONE, e);
        let others = 3 - thin.bitmask().count_ones() as i32;
        let left = budget / (raised.x * raised.y * raised.z);
        let k_rest = (left / (rest.x * rest.y * rest.z)).powf(1.0 / others as f32);
        cells = Vec3::select(thin, raised, cells.min(e * k_rest));
    }
    cells.round().as_uvec3().clamp(
        UVec3::splat(2),
        UVec3::splat(MAX_RESOLUTION.min(resolution * 4).max(2)),
    )
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

/// Whether a triangle takes part in a bake: finite and not degenerate.
fn usable(t: &Triangle) -> bool {
    t.vertices.iter().all(|v| v.is_finite()) && t.face_normal().length_squared() > f32::MIN_POSITIVE
}

/// The grid a bake of these triangles with these settings makes: what a cached field must match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BakeGrid {
    /// Centre of the grid box, mesh space, metres.
    pub center: Vec3,
    /// Half extents of the grid box, metres.
    pub half_extent: Vec3,
    /// Hits count within this, metres (∞: at any distance).
    pub reach: f32,
    /// Near hits count within this, metres (∞: at any distance).
    pub near: f32,
    /// Cells per axis.
    pub resolution: UVec3,
}

impl BakeGrid {
    /// The grid for the usable triangles among `triangles`, with `settings` resolved for a
    /// camera; `None` without any usable triangle.
    pub fn plan(triangles: &[Triangle], settings: &BakeSettings) -> Option<Self> {
        let (min, max) = triangles
            .iter()
            .filter(|t| usable(t))
            .flat_map(|t| t.vertices)
            .fold(None, |bounds: Option<(Vec3, Vec3)>, v| {
                Some(bounds.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
            })?;
        let (center, half_extent, reach, near) = match settings.reach {
            FieldReach::Distance { reach, near } => (
                (min + max) * 0.5,
                // Beyond the object's bounds grown by the reach no ray meets it: the field is 0.
                (max - min) * 0.5 + Vec3::splat(reach),
                reach,
                near.min(reach),
            ),
            FieldReach::Unlimited { epsilon } => {
                let (center, e) = grid_box(min, max, epsilon);
                (center, e, f32::INFINITY, f32::INFINITY)
            }
            FieldReach::CameraRadius => {
                let resolved = settings.for_camera(DEFAULT_RADIUS, DEFAULT_NEAR_FIELD_RADIUS);
                return Self::plan(triangles, &resolved);
            }
        };
        Some(Self {
            center,
            half_extent,
            reach,
            near,
            resolution: grid_resolution(half_extent, settings.resolution),
        })
    }

    /// Whether `field` is what a bake on this grid writes (a cached file is trusted only then).
    pub fn matches(&self, field: &AoFieldData) -> bool {
        let finite = |d: f32| if d.is_finite() { d } else { 0.0 };
        let close =
            |a: Vec3, b: Vec3| (a - b).abs().max_element() <= 1e-5 * b.abs().max_element().max(1.0);
        field.resolution == self.resolution
            && close(field.center, self.center)
            && close(field.half_extent, self.half_extent)
            && field.reach == finite(self.reach)
            && field.near_reach == finite(self.near)
    }
}

/// Bakes the field of `triangles` (mesh space). [`FieldReach::CameraRadius`] bakes for the
/// crate's default radius; the plugin resolves it with [`BakeSettings::for_camera`] first.
/// `progress(done, total)` is called as slices of the grid finish, from the baking threads.
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
    let settings = settings.for_camera(DEFAULT_RADIUS, DEFAULT_NEAR_FIELD_RADIUS);
    match settings.reach {
        FieldReach::Unlimited { epsilon } if !(epsilon > 0.0 && epsilon < 1.0) => {
            return Err(BakeError::BadSettings(format!(
                "epsilon {epsilon} is outside (0, 1)"
            )));
        }
        FieldReach::Distance { reach, near }
            if !(reach.is_finite() && reach > 0.0 && near.is_finite() && near > 0.0) =>
        {
            return Err(BakeError::BadSettings(format!(
                "reach {reach} m and near reach {near} m must be positive distances"
            )));
        }
        _ => {}
    }
    if !(1..=BakeSettings::MAX_RAYS).contains(&settings.rays) {
        return Err(BakeError::BadSettings(format!(
            "rays {} is outside 1..={}",
            settings.rays,
            BakeSettings::MAX_RAYS
        )));
    }
    let triangles: Vec<Triangle> = triangles.into_iter().filter(usable).collect();
    let Some(BakeGrid {
        center,
        half_extent,
        reach,
        near,
        resolution,
    }) = BakeGrid::plan(&triangles, &settings)
    else {
        return Err(BakeError::NoTriangles);
    };
    let bvh = Bvh::new(triangles);
    let directions = sphere_directions(settings.rays);
    let hemisphere = cosine_hemisphere(settings.rays);
    let axes = AxisHemispheres::new(&directions, settings.axis_correction);
    let cell_size = 2.0 * half_extent / resolution.as_vec3();
    let own = OwnSurface {
        hemisphere: &hemisphere,
        // A receiver on the surface interpolates grid points up to a cell's diagonal from it.
        within: 2.0 * cell_size.max_element(),
        // Nothing to add where the near field reaches as far as the field.
        skip: !(near.is_finite() && near < reach),
    };
    let origin = center - half_extent;
    let distances = SampleDistances {
        reach,
        near,
        miss: 2.0 * half_extent.length(),
    };

    let (nx, ny, nz) = (
        resolution.x as usize,
        resolution.y as usize,
        resolution.z as usize,
    );
    let mut cells = vec![Cell::default(); nx * ny * nz];
    let done = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    let slice = nx * ny;
    std::thread::scope(|scope| {
        // Interleaved slices keep the threads busy when the object fills only part of the grid.
        let mut chunks: Vec<Vec<(usize, &mut [Cell])>> = (0..threads).map(|_| Vec::new()).collect();
        for (z, chunk) in cells.chunks_mut(slice).enumerate() {
            chunks[z % threads].push((z, chunk));
        }
        for work in chunks {
            let (bvh, directions, done, own, axes, distances) =
                (&bvh, &directions, &done, &own, &axes, &distances);
            scope.spawn(move || {
                for (z, chunk) in work {
                    for y in 0..ny {
                        for x in 0..nx {
                            let p = origin
                                + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * cell_size;
                            chunk[y * nx + x] = sample(bvh, directions, own, axes, p, distances);
                        }
                    }
                    progress(done.fetch_add(1, Ordering::Relaxed) + 1, nz);
                }
            });
        }
    });

    let finite = |d: f32| if d.is_finite() { d } else { 0.0 };
    let mut field = AoFieldData {
        resolution,
        center,
        half_extent,
        reach: finite(reach),
        near_reach: finite(near),
        cells: cells.iter().map(|c| c.far).collect(),
        near_cells: cells.iter().map(|c| c.near).collect(),
        distances: cells
            .iter()
            .map(|c| {
                let o = c.near_offset;
                [c.signed_distance, o.x, o.y, o.z]
            })
            .collect(),
        own_surface: cells.iter().map(|c| c.own_surface).collect(),
        axes: cells.iter().map(|c| c.axes).collect(),
    };
    if settings.fill_interior {
        fill_interior(&mut field);
    }
    if settings.rescale_border {
        rescale_border(&mut field);
    }
    Ok(field)
}

#[cfg(test)]
mod tests;

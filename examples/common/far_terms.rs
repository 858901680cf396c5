//! The far-field terms as `ao_capture` sets them up on a whole scene, shared with the tests and
//! benchmarks so that all of them judge the same setup a user would make: every mesh an
//! occluder.
#![allow(dead_code)]

use bevy::prelude::*;
use bevy_dynamic_ao::geometry::bvh::Bvh;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::nd_buffer::{NdTexel, ViewMatrices};

/// A far-field term: alone it is the whole occlusion, after `+` it joins an image-space
/// technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FarTerm {
    /// A `SphereOccluder` on every mesh.
    Spheres,
    /// An AO field baked for every mesh.
    Fields,
    /// One voxel volume over what occludes the surfaces the camera sees (`occluder_bounds`).
    Voxels,
}

impl FarTerm {
    pub const ALL: [Self; 3] = [Self::Spheres, Self::Fields, Self::Voxels];

    pub fn name(self) -> &'static str {
        match self {
            Self::Spheres => "spheres",
            Self::Fields => "fields",
            Self::Voxels => "voxels",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|term| term.name() == name)
    }

    /// Switches this term on in `ao` and every other far-field term off.
    pub fn select(term: Option<Self>, ao: &mut DynamicAo) {
        ao.spheres = term == Some(Self::Spheres);
        ao.fields = term == Some(Self::Fields);
        ao.voxels = term == Some(Self::Voxels);
    }

    /// Gives every mesh in `meshes` this term's occluder component; for voxels, spawns one volume
    /// over the world-space box `[lo, hi]` grown by `margin` metres and returns it. Every setting
    /// is the plugin's default: the volume reaches as far as the camera's radius.
    pub fn attach(
        self,
        commands: &mut Commands,
        meshes: &[Entity],
        (lo, hi): (Vec3, Vec3),
        margin: f32,
    ) -> Option<Entity> {
        match self {
            Self::Spheres => {
                for &mesh in meshes {
                    commands.entity(mesh).insert(SphereOccluder::default());
                }
                None
            }
            Self::Fields => {
                for &mesh in meshes {
                    commands.entity(mesh).insert(AoField::default());
                }
                None
            }
            Self::Voxels => Some(
                commands
                    .spawn((
                        Transform::from_translation((lo + hi) / 2.0),
                        VoxelAoVolume {
                            half_extents: (hi - lo) / 2.0 + margin,
                            ..default()
                        },
                    ))
                    .id(),
            ),
        }
    }
}

/// How far a volume over [`occluder_bounds`] reaches past them, as a share of the radius: the
/// bounds' rim passes through the outermost hits, whose triangles reach a little farther.
pub const VOXEL_MARGIN: f32 = 0.05;

/// Hemisphere rays each sampled surface traces in [`occluder_bounds`].
const PLACEMENT_RAYS: u32 = 16;
/// Most surfaces [`occluder_bounds`] samples: the front layer is thinned to about this many.
const PLACEMENT_SURFACES: u32 = 20_000;

/// The world-space bounds of what occludes the surfaces a camera sees within `radius`: from
/// surfaces of the front layer of its ND-buffer (`texels`, row-major, `width` × `height`, thinned
/// to about 20,000), 16 cosine-weighted rays each are traced against `bvh`, and the bounds hold
/// every point they hit. A voxel volume needs cells only there: a ray from any surface the
/// camera sees ends at an occluder inside them or at none, and an open floor far from anything,
/// which occludes nothing the camera sees, takes no cells, so they are as fine as the
/// occlusion allows. `None` where no ray hits anything.
pub fn occluder_bounds(
    bvh: &Bvh,
    texels: &[NdTexel],
    width: u32,
    height: u32,
    view: &ViewMatrices,
    radius: f32,
) -> Option<(Vec3, Vec3)> {
    let stride = ((width * height) as f32 / PLACEMENT_SURFACES as f32)
        .sqrt()
        .ceil()
        .max(1.0) as u32;
    let eye = view.view_from_world.inverse().w_axis.truncate();
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for y in (0..height).step_by(stride as usize) {
        for x in (0..width).step_by(stride as usize) {
            let t = texels[(y * width + x) as usize];
            if t.depth <= 0.0 || t.normal == Vec3::ZERO {
                continue;
            }
            let p = view.world_position(x as i32, y as i32, width, height, t.depth);
            if !p.is_finite() {
                continue;
            }
            // Off the surface by more than the depth buffer's error at that distance, so that
            // no ray hits the surface it leaves.
            let start = p + t.normal * (1e-3 * p.distance(eye) + 1e-4);
            let (t1, t2) = t.normal.any_orthonormal_pair();
            for i in 0..PLACEMENT_RAYS {
                let u = (i as f32 + 0.5) / PLACEMENT_RAYS as f32;
                let phi = std::f32::consts::TAU * (i as f32 * 0.618_034).fract();
                let r = u.sqrt();
                let d = t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + t.normal * (1.0 - u).sqrt();
                if let Some(hit) = bvh.closest_hit(start, d, 0.0, radius) {
                    let q = start + d * hit.t;
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
        }
    }
    lo.is_finite().then_some((lo, hi))
}

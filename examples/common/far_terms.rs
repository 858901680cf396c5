//! The far-field terms as `ao_capture` sets them up on a whole scene, shared with the tests and
//! benchmarks so that all of them judge the same setup a user would make: every mesh an
//! occluder.
#![allow(dead_code)]

use bevy::prelude::*;
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
    /// One voxel volume around the whole scene, grown by the radius.
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
    /// over the world-space box `[lo, hi]` grown by `radius` (so occluders at its rim still reach
    /// the surfaces inside) and returns it. Every setting is the plugin's default: the volume
    /// reaches as far as the camera's radius.
    pub fn attach(
        self,
        commands: &mut Commands,
        meshes: &[Entity],
        (lo, hi): (Vec3, Vec3),
        radius: f32,
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
                            half_extents: (hi - lo) / 2.0 + radius,
                            ..default()
                        },
                    ))
                    .id(),
            ),
        }
    }
}

/// The world-space bounds of the surfaces a camera sees: the front layer of its ND-buffer
/// (`texels`, row-major, `width` × `height`) unprojected. `None` where it sees nothing.
pub fn visible_bounds(
    texels: &[NdTexel],
    width: u32,
    height: u32,
    view: &ViewMatrices,
) -> Option<(Vec3, Vec3)> {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for (i, t) in texels.iter().enumerate() {
        if t.depth <= 0.0 {
            continue;
        }
        let (x, y) = ((i as u32 % width) as i32, (i as u32 / width) as i32);
        let p = view.world_position(x, y, width, height, t.depth);
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    lo.is_finite().then_some((lo, hi))
}

/// Where one voxel volume over a scene serves a camera best: the scene's bounds, cut down to the
/// surfaces the camera sees grown by `radius` (only occluders that close can reach them), so its
/// cells are as fine as the view allows.
pub fn voxel_region(
    scene: (Vec3, Vec3),
    visible: Option<(Vec3, Vec3)>,
    radius: f32,
) -> (Vec3, Vec3) {
    let Some((lo, hi)) = visible else {
        return scene;
    };
    let (lo, hi) = (
        scene.0.max(lo - Vec3::splat(radius)),
        scene.1.min(hi + Vec3::splat(radius)),
    );
    if lo.cmple(hi).all() { (lo, hi) } else { scene }
}

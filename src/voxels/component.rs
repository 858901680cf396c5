//! The volume component users add, and what the plugin reports back about each volume's grid.

use bevy::ecs::prelude::*;
use bevy::math::{Affine3A, Vec3};
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// A region whose geometry is voxelized every frame and casts ambient occlusion through its voxels
/// (Reinbothe, Boubekeur & Alexa 2009).
///
/// The region is a box of `half_extents` around the entity, in the entity's own space: it moves,
/// turns and scales with the entity's `GlobalTransform`, so a volume on (or below) a character
/// follows the character. Every frame, every visible mesh that reaches into the box (static,
/// skinned or morphed) is rasterized into a grid of `resolution`³ occupancy bits. Every visible
/// surface inside the box, or within reach of it, then traces `rays` rays through the grid, so
/// occluders behind other surfaces or off-screen still darken it.
///
/// By default it measures what ray-traced ground truth measures: a ray is blocked when it meets
/// an occupied cell closer than the camera's [`radius`](crate::DynamicAo::radius), found by
/// walking every cell the ray crosses. The paper's own choices are options: a fixed number of
/// evenly spaced tests per ray ([`VoxelMarch::Steps`]), Wendland's distance falloff
/// ([`VoxelFalloff::Wendland`]) and a reach of its own (`d_max`).
///
/// Defaults follow the paper's table 1 where they do not change what is measured (256³ voxels,
/// 32 rays; 8 a frame where the camera accumulates). Several volumes may exist; where they
/// overlap, a surface takes the darkest of their answers.
///
/// `RenderLayers`: a camera samples the volume when it shares a layer with the volume's entity,
/// and a mesh is voxelized into the volume only when it is on every layer of the volume (without
/// the component, both are on layer 0). So no camera is darkened by a mesh it does not draw. A
/// mesh on other layers than the volume's casts through a volume of its own layers: in a split
/// screen whose players see layer 0 plus a layer each, one volume on layer 0 for the shared
/// scene and one on each player's layer.
///
/// ```no_run
/// # use bevy::prelude::*;
/// # use bevy_dynamic_ao::prelude::*;
/// fn spawn(mut commands: Commands) {
///     // A 4 m × 2 m × 4 m region around the entity, voxelized at 128³.
///     commands.spawn((
///         Transform::from_xyz(0.0, 1.0, 0.0),
///         VoxelAoVolume {
///             half_extents: Vec3::new(2.0, 1.0, 2.0),
///             resolution: 128,
///             ..default()
///         },
///     ));
/// }
/// ```
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Default, Clone, Debug)]
#[require(bevy::transform::components::Transform)]
pub struct VoxelAoVolume {
    /// Half the size of the box along the entity's local axes, metres (before the entity's
    /// scale). Every component must be finite and positive.
    /// Default: [`VoxelAoVolume::DEFAULT_HALF_EXTENTS`] (2 m).
    pub half_extents: Vec3,
    /// Voxels along each axis of the box (the grid has `resolution`³ cells). Useful range 64 to
    /// 256; clamped into [`Self::MIN_RESOLUTION`]..=[`Self::MAX_RESOLUTION`].
    /// Default: [`VoxelAoVolume::DEFAULT_RESOLUTION`] (256).
    pub resolution: u32,
    /// Rays per pixel of the AO map. Clamped into 1..=[`Self::MAX_RAYS`].
    /// Default: [`VoxelAoVolume::DEFAULT_RAYS`] (32).
    pub rays: u32,
    /// Rays per pixel each frame on a camera that accumulates the voxel term
    /// ([`AoTemporal`](crate::AoTemporal) on, as by default): the history averages the frames'
    /// turned patterns, so fewer rays a frame converge to what `rays` rays give. At most `rays`;
    /// clamped into 1..=[`Self::MAX_RAYS`].
    /// Default: [`VoxelAoVolume::DEFAULT_ACCUMULATED_RAYS`] (8).
    pub accumulated_rays: u32,
    /// How a ray looks for occupied cells. Default: [`VoxelMarch::Cells`], every cell it
    /// crosses.
    pub march: VoxelMarch,
    /// Opening of the cone the rays fill, as a fraction of the hemisphere: 1 = the whole
    /// hemisphere (eq. 1), 0.5 = within 45° of the normal. Smaller is sharper and darker where
    /// the occluder faces the surface. Range (0, 1].
    /// Default: [`VoxelAoVolume::DEFAULT_SPREAD`] (1).
    pub spread: f32,
    /// Longest distance an occluder counts from, metres. `None`: the radius of the camera that
    /// renders the volume ([`DynamicAo::radius`](crate::DynamicAo::radius)), so every camera
    /// measures within its own radius. `Some(d)` sets the paper's d_max for this volume
    /// instead. Default: `None`.
    pub d_max: Option<f32>,
    /// How an occluder's weight falls off with its distance. Default: [`VoxelFalloff::None`],
    /// every hit within reach counts, as ground truth counts it.
    pub falloff: VoxelFalloff,
}

/// How a ray through a voxel grid looks for the first occupied cell.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub enum VoxelMarch {
    /// Every cell the ray crosses, in order (a 3D digital differential analyser): no occluder
    /// is stepped over, however thin (a floor is one cell thick). Its cost grows with the reach
    /// in cells; where the reach spans at least four bricks of 8³ cells, a brick with no
    /// occupied cell is crossed in one step, which finds the same hits for a fraction of the
    /// cost (most of a ray's reach is air).
    #[default]
    Cells,
    /// This many occupancy tests, evenly spaced up to the reach and jittered per pixel, as the
    /// paper's §6 does (8 in its table 1): a fixed cost, but a thin occluder between two tests
    /// is missed (a one-cell floor is found by about one ray in (reach / cell) / steps).
    /// Clamped into 1..=[`VoxelAoVolume::MAX_STEPS`].
    Steps(u32),
}

/// How the occlusion of a ray that hits an occupied cell at distance t falls off with t.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub enum VoxelFalloff {
    /// Every hit within reach counts fully: the obscurance of eq. 1 cut at the reach, the
    /// quantity ray-traced ground truth measures.
    #[default]
    None,
    /// Wendland's kernel of eq. 3 with the reach as support, as the paper publishes it: 1 at the
    /// surface, 0.19 at half the reach, 0 at the reach. Softer, contact-weighted shadows that
    /// find less than ground truth (next to a box just outside the view, 0.022 of the 0.126 a ray
    /// tracer finds within 0.75 m).
    Wendland,
}

impl VoxelAoVolume {
    /// Smallest grid resolution.
    pub const MIN_RESOLUTION: u32 = 8;
    /// Largest grid resolution: 512³ bits are 16 MiB.
    pub const MAX_RESOLUTION: u32 = 512;
    /// Most rays per pixel.
    pub const MAX_RAYS: u32 = 256;
    /// Most steps per ray of [`VoxelMarch::Steps`].
    pub const MAX_STEPS: u32 = 64;
    /// How far, in cells, a ray of [`VoxelMarch::Cells`] travels through occupied cells before
    /// it counts as blocked (`HIT_DEPTH` in `voxel_ao.wgsl`). Conservative voxelization grows
    /// every occluder by up to a cell on each side, and a ray that only grazes that rim is not
    /// blocked by the mesh; a ray across the thinnest occluder, a plane one cell thick, travels
    /// at least one cell. 0.9 lowered the voxel term's error on every scene of `cargo bench
    /// --bench far_field` it was tried on (characters, rooms, a box and a wall off-screen;
    /// characters on a floor by about a tenth); 1.5 let rays slip through floors and walls.
    pub const HIT_DEPTH: f32 = 0.9;
    /// Default half extents, metres.
    pub const DEFAULT_HALF_EXTENTS: Vec3 = Vec3::splat(2.0);
    /// Default resolution (table 1).
    pub const DEFAULT_RESOLUTION: u32 = 256;
    /// Default rays per pixel (table 1).
    pub const DEFAULT_RAYS: u32 = 32;
    /// Default rays per pixel each frame under accumulation: a quarter of table 1's, which
    /// converge to the same error at a quarter of the cost (BENCHMARKS.md, "Fewer voxel rays a
    /// frame under accumulation").
    pub const DEFAULT_ACCUMULATED_RAYS: u32 = 8;
    /// Steps per ray of the paper's table 1, for [`VoxelMarch::Steps`].
    pub const PAPER_STEPS: u32 = 8;
    /// Default spread: the whole hemisphere.
    pub const DEFAULT_SPREAD: f32 = 1.0;

    /// A volume of these half extents with the default sampling settings.
    pub fn new(half_extents: Vec3) -> Self {
        Self {
            half_extents,
            ..Self::default()
        }
    }

    /// Checks the settings: an unusable region is an error (the volume is skipped), out-of-range
    /// sampling settings are clamped or replaced by their defaults and listed in the second value.
    pub fn sanitized(&self) -> Result<(Self, Vec<String>), VoxelVolumeError> {
        let h = self.half_extents;
        if !h.is_finite() {
            return Err(VoxelVolumeError::NonFiniteExtents(h));
        }
        if h.min_element() <= 0.0 {
            return Err(VoxelVolumeError::EmptyExtents(h));
        }
        let mut fixes = Vec::new();
        let mut clamp = |name: &str, value: u32, min: u32, max: u32| {
            let clamped = value.clamp(min, max);
            if clamped != value {
                fixes.push(format!(
                    "{name} {value} is outside {min}..={max}; using {clamped}"
                ));
            }
            clamped
        };
        let resolution = clamp(
            "resolution",
            self.resolution,
            Self::MIN_RESOLUTION,
            Self::MAX_RESOLUTION,
        );
        let rays = clamp("rays", self.rays, 1, Self::MAX_RAYS);
        // More a frame than without accumulation is no fault: `rays` caps it.
        let accumulated_rays =
            clamp("accumulated_rays", self.accumulated_rays, 1, Self::MAX_RAYS).min(rays);
        let march = match self.march {
            VoxelMarch::Cells => VoxelMarch::Cells,
            VoxelMarch::Steps(steps) => {
                VoxelMarch::Steps(clamp("steps", steps, 1, Self::MAX_STEPS))
            }
        };
        let spread = if self.spread.is_finite() && self.spread > 0.0 && self.spread <= 1.0 {
            self.spread
        } else {
            fixes.push(format!(
                "spread {} is outside (0, 1]; using {}",
                self.spread,
                Self::DEFAULT_SPREAD
            ));
            Self::DEFAULT_SPREAD
        };
        let d_max = match self.d_max {
            Some(d) if !(d.is_finite() && d > 0.0) => {
                fixes.push(format!(
                    "d_max {d} is not a positive distance; using the camera's radius"
                ));
                None
            }
            d => d,
        };
        Ok((
            Self {
                half_extents: h,
                resolution,
                rays,
                accumulated_rays,
                march,
                spread,
                d_max,
                falloff: self.falloff,
            },
            fixes,
        ))
    }
}

impl Default for VoxelAoVolume {
    fn default() -> Self {
        Self {
            half_extents: Self::DEFAULT_HALF_EXTENTS,
            resolution: Self::DEFAULT_RESOLUTION,
            rays: Self::DEFAULT_RAYS,
            accumulated_rays: Self::DEFAULT_ACCUMULATED_RAYS,
            march: VoxelMarch::Cells,
            spread: Self::DEFAULT_SPREAD,
            d_max: None,
            falloff: VoxelFalloff::None,
        }
    }
}

/// Why a [`VoxelAoVolume`] casts nothing.
#[derive(Clone, Debug, PartialEq)]
pub enum VoxelVolumeError {
    /// A half extent is NaN or infinite.
    NonFiniteExtents(Vec3),
    /// A half extent is zero or negative (an empty or inverted box).
    EmptyExtents(Vec3),
    /// The entity's transform is not finite, or squashes the box flat.
    BadTransform,
}

impl std::fmt::Display for VoxelVolumeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NonFiniteExtents(h) => write!(f, "its half extents {h} are not finite"),
            Self::EmptyExtents(h) => write!(
                f,
                "its half extents {h} are not all positive (a zero-size or inverted box)"
            ),
            Self::BadTransform => write!(
                f,
                "its GlobalTransform is not finite or has a zero scale, so the box has no volume"
            ),
        }
    }
}

impl std::error::Error for VoxelVolumeError {}

/// Where the plugin put a [`VoxelAoVolume`]'s grid this frame; added to every volume in use.
///
/// Cell (x, y, z) is bit `i % 32` of word `offset + i / 32` of the grid buffer, with
/// `i = x + resolution · (y + resolution · z)`, when a triangle touches it, and the same bit of
/// word `solid_offset + i / 32` when it lies inside a closed mesh. Read the buffer with
/// [`VoxelGridReadback`].
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct VoxelGridInfo {
    /// World space to grid space, where cell (x, y, z) spans [x, x + 1] × [y, y + 1] × [z, z + 1].
    pub grid_from_world: Affine3A,
    /// Cells along each axis.
    pub resolution: u32,
    /// First 32-bit word of this grid's surface bits in the grid buffer.
    pub offset: u32,
    /// First 32-bit word of this grid's interior bits in the grid buffer.
    pub solid_offset: u32,
    /// Triangles rasterized into the grid this frame.
    pub triangles: u32,
    /// How the volume's rays are traced this frame.
    pub rays: VoxelRays,
}

impl VoxelGridInfo {
    /// 32-bit words the grid takes.
    pub fn words(&self) -> u32 {
        grid_words(self.resolution)
    }

    /// 32-bit words a grid of `resolution`³ cells takes.
    pub fn words_for(resolution: u32) -> u32 {
        grid_words(resolution)
    }
}

/// How a volume's rays are traced, in world units: derived from a sanitized [`VoxelAoVolume`] and
/// its grid's placement, identically for the GPU pass and the CPU twin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelRays {
    /// Rays per pixel.
    pub rays: u32,
    /// Rays per pixel each frame on a camera that accumulates the voxel term; at most `rays`.
    pub accumulated_rays: u32,
    /// How each ray looks for occupied cells.
    pub march: VoxelMarch,
    /// Cosine of the half-angle of the cone the rays fill.
    pub cos_spread: f32,
    /// Longest distance an occluder counts from, metres; `None`: the camera's radius.
    pub d_max: Option<f32>,
    /// How far rays start off the surface along its normal, metres: one cell diagonal, so a ray
    /// never tests the cells its own surface occupies.
    pub bias: f32,
    /// Size of the world-space cubes the ray jitter is constant over, metres.
    pub noise_cell: f32,
    /// World-space size of one cell along each grid axis, metres.
    pub cell: Vec3,
    /// How a hit's weight falls off with its distance.
    pub falloff: VoxelFalloff,
}

impl VoxelRays {
    /// The rays of `volume` (sanitized) whose grid cells map to world space by `grid_from_world`.
    pub fn new(volume: &VoxelAoVolume, grid_from_world: Affine3A) -> Self {
        let world_from_grid = grid_from_world.inverse().matrix3;
        let cell = Vec3::new(
            world_from_grid.x_axis.length(),
            world_from_grid.y_axis.length(),
            world_from_grid.z_axis.length(),
        );
        Self {
            rays: volume.rays,
            accumulated_rays: volume.accumulated_rays,
            march: volume.march,
            cos_spread: (volume.spread * std::f32::consts::FRAC_PI_2).cos().max(0.0),
            d_max: volume.d_max,
            bias: cell.length(),
            noise_cell: 0.25 * cell.min_element(),
            cell,
            falloff: volume.falloff,
        }
    }

    /// The reach of a ray seen by a camera of this `radius`, metres.
    pub fn reach(&self, radius: f32) -> f32 {
        self.d_max.unwrap_or(radius)
    }
}

/// 32-bit words of a grid of `resolution`³ bits.
pub(crate) fn grid_words(resolution: u32) -> u32 {
    (resolution * resolution * resolution).div_ceil(32)
}

/// Cells along each axis of a brick of the coarse occupancy level (`BRICK_CELLS` in
/// `voxel_grid.wgsl`): a brick's bit is set where any of its cells is occupied, and a ray
/// crosses a brick whose bit is clear in one step instead of cell by cell.
pub(crate) const BRICK_CELLS: u32 = 8;

/// 32-bit words of the coarse occupancy bits of a grid of `resolution`³ cells.
pub(crate) fn brick_words(resolution: u32) -> u32 {
    grid_words(resolution.div_ceil(BRICK_CELLS))
}

/// Asks the plugin to copy the voxel grids of every volume into this storage buffer each frame,
/// after they are built; read it with Bevy's `Readback::buffer`. The buffer must hold at least
/// as many 32-bit words as the grids take (twice the sum of [`VoxelGridInfo::words`]: surface
/// and interior bits); a smaller one is skipped with a warning. For tests and tools.
#[derive(Resource, Clone, Debug)]
pub struct VoxelGridReadback(pub bevy::asset::Handle<bevy::render::storage::ShaderBuffer>);

/// Keeps this mesh out of every voxel grid: it casts no voxel occlusion (use it for meshes that
/// should not occlude, such as markers or effects, or that other occluders already cover).
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[reflect(Component, Default, Clone, Debug)]
pub struct NotVoxelOccluder;

/// Draws the occupied voxels of this [`VoxelAoVolume`] over every camera that has
/// [`DynamicAo`](crate::DynamicAo): a debug view of what the grid holds this frame.
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[reflect(Component, Default, Clone, Debug)]
pub struct ShowOccupiedVoxels;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shaders_bricks_are_as_wide_as_the_buffers() {
        let wgsl = include_str!("voxel_grid.wgsl");
        assert!(wgsl.contains(&format!("const BRICK_CELLS: u32 = {BRICK_CELLS}u;")));
        // A partial brick at the far end still has its bit.
        assert_eq!(brick_words(256), 32 * 32 * 32 / 32);
        assert_eq!(brick_words(9), 1);
    }

    #[test]
    fn the_rays_a_frame_under_accumulation_are_at_most_the_volumes_rays() {
        let (volume, fixes) = VoxelAoVolume::default().sanitized().unwrap();
        assert_eq!((volume.rays, volume.accumulated_rays), (32, 8));
        assert!(fixes.is_empty());
        let few = VoxelAoVolume {
            rays: 4,
            ..VoxelAoVolume::default()
        };
        let (volume, fixes) = few.sanitized().unwrap();
        assert_eq!(volume.accumulated_rays, 4);
        assert!(fixes.is_empty(), "capping at `rays` is no fault: {fixes:?}");
        let none = VoxelAoVolume {
            accumulated_rays: 0,
            ..VoxelAoVolume::default()
        };
        let (volume, fixes) = none.sanitized().unwrap();
        assert_eq!(volume.accumulated_rays, 1);
        assert_eq!(fixes, ["accumulated_rays 0 is outside 1..=256; using 1"]);
    }
}

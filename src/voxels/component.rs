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
/// surface inside the box, or within `d_max` of it, then traces `rays` rays of `steps` steps each
/// through the grid, so occluders behind other surfaces or off-screen still darken it.
///
/// Defaults follow the paper's table 1 (256³ voxels, 32 rays, 8 steps). Several volumes may
/// exist; where they overlap, a surface takes the darkest of their answers.
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
    /// scale). Every component must be finite and positive. Default 2 m.
    pub half_extents: Vec3,
    /// Voxels along each axis of the box (the grid has `resolution`³ cells). Useful range 64 to
    /// 256; clamped into [`Self::MIN_RESOLUTION`]..=[`Self::MAX_RESOLUTION`]. Default 256.
    pub resolution: u32,
    /// Rays per pixel of the AO map. Clamped into 1..=[`Self::MAX_RAYS`]. Default 32.
    pub rays: u32,
    /// Occupancy tests per ray, evenly spaced up to `d_max`. Clamped into
    /// 1..=[`Self::MAX_STEPS`]. Default 8.
    pub steps: u32,
    /// Opening of the cone the rays fill, as a fraction of the hemisphere: 1 = the whole
    /// hemisphere (eq. 1), 0.5 = within 45° of the normal. Smaller is sharper and darker where
    /// the occluder faces the surface. Range (0, 1]. Default 1.
    pub spread: f32,
    /// Longest distance an occluder counts from, metres; its weight falls off with the Wendland
    /// kernel (eq. 3) and is 0 beyond. Default 1 m.
    pub d_max: f32,
    /// How an occluder's weight falls off with its distance. Default:
    /// [`VoxelFalloff::Wendland`], as the paper publishes it.
    pub falloff: VoxelFalloff,
}

/// How the occlusion of a ray that hits an occupied cell at distance t falls off with t.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub enum VoxelFalloff {
    /// Wendland's kernel of eq. 3 with support d_max: 1 at the surface, 0.19 at d_max / 2,
    /// 0 at d_max. Soft, contact-weighted shadows.
    #[default]
    Wendland,
    /// Every hit within d_max counts fully: the obscurance of eq. 1 cut at d_max, the
    /// definition ray-traced ground truth uses. Darker and wider.
    None,
}

impl VoxelAoVolume {
    /// Smallest grid resolution.
    pub const MIN_RESOLUTION: u32 = 8;
    /// Largest grid resolution: 512³ bits are 16 MiB.
    pub const MAX_RESOLUTION: u32 = 512;
    /// Most rays per pixel.
    pub const MAX_RAYS: u32 = 256;
    /// Most steps per ray.
    pub const MAX_STEPS: u32 = 64;
    /// Default half extents, metres.
    pub const DEFAULT_HALF_EXTENTS: Vec3 = Vec3::splat(2.0);
    /// Default resolution (table 1).
    pub const DEFAULT_RESOLUTION: u32 = 256;
    /// Default rays per pixel (table 1).
    pub const DEFAULT_RAYS: u32 = 32;
    /// Default steps per ray (table 1).
    pub const DEFAULT_STEPS: u32 = 8;
    /// Default spread: the whole hemisphere.
    pub const DEFAULT_SPREAD: f32 = 1.0;
    /// Default d_max, metres.
    pub const DEFAULT_D_MAX: f32 = 1.0;

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
        let steps = clamp("steps", self.steps, 1, Self::MAX_STEPS);
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
        let d_max = if self.d_max.is_finite() && self.d_max > 0.0 {
            self.d_max
        } else {
            fixes.push(format!(
                "d_max {} is not a positive distance; using {} m",
                self.d_max,
                Self::DEFAULT_D_MAX
            ));
            Self::DEFAULT_D_MAX
        };
        Ok((
            Self {
                half_extents: h,
                resolution,
                rays,
                steps,
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
            steps: Self::DEFAULT_STEPS,
            spread: Self::DEFAULT_SPREAD,
            d_max: Self::DEFAULT_D_MAX,
            falloff: VoxelFalloff::Wendland,
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
    /// Occupancy tests per ray.
    pub steps: u32,
    /// Cosine of the half-angle of the cone the rays fill.
    pub cos_spread: f32,
    /// Longest distance an occluder counts from, metres.
    pub d_max: f32,
    /// How far rays start off the surface along its normal, metres: one cell diagonal, so a ray
    /// never tests the cells its own surface occupies.
    pub bias: f32,
    /// Size of the world-space cubes the ray jitter is constant over, metres.
    pub noise_cell: f32,
    /// d_max + bias in cells along each grid axis: surfaces farther outside the grid are skipped.
    pub reach: Vec3,
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
        let bias = cell.length();
        Self {
            rays: volume.rays,
            steps: volume.steps,
            cos_spread: (volume.spread * std::f32::consts::FRAC_PI_2).cos().max(0.0),
            d_max: volume.d_max,
            bias,
            noise_cell: 0.25 * cell.min_element(),
            reach: (volume.d_max + bias) / cell,
            falloff: volume.falloff,
        }
    }
}

/// 32-bit words of a grid of `resolution`³ bits.
pub(crate) fn grid_words(resolution: u32) -> u32 {
    (resolution * resolution * resolution).div_ceil(32)
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

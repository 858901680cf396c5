//! The `.aofield` file: one baked ambient occlusion field, versioned and checksummed.
//!
//! Layout, little-endian:
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `AOFIELD\0` |
//! | 4 | version (u32, currently 4) |
//! | 12 | grid resolution x, y, z (u32 each, 2 to [`MAX_RESOLUTION`]) |
//! | 12 | grid box centre, mesh space (f32 × 3, metres) |
//! | 12 | grid box half extents e_i (f32 × 3, metres, > 0) |
//! | 8 | the distances the occlusion counts within: reach, then near reach (f32 × 2, metres, 0 = unlimited) |
//! | 112 per cell | occlusion a ∈ [0, 1] within reach and the average occluded direction (f32 × 4); the same within the near reach (f32 × 4); the signed distance to the surface and the mean offset from the cell's centre to the points where rays meet the object within the near reach (f32 × 4, metres); the share of the object's own surface's hemisphere blocked beyond the near reach, at the surface point nearest the cell, and that surface's unit normal on the cell's side (f32 × 4, zero away from the surface and inside the object); the cone's error on the six axis hemispheres +x, −x, +y, −y, +z, −z within reach, then within the near reach (f32 × 12, each in [−1, 1]); cells x fastest, then y, then z |
//! | 8 | FNV-1a 64-bit hash of every byte before it |

use bevy::asset::Asset;
use bevy::math::{UVec3, Vec3};
use bevy::reflect::TypePath;

/// First bytes of every `.aofield` file.
pub const MAGIC: &[u8; 8] = b"AOFIELD\0";
/// The version this crate writes and reads (version 1 held occlusion at unlimited distance only;
/// version 2 nothing for the object's own surface; version 3 no axis corrections).
pub const VERSION: u32 = 4;
/// Largest grid resolution per axis.
pub const MAX_RESOLUTION: u32 = 256;
const HEADER_BYTES: usize = 8 + 4 + 12 + 12 + 12 + 8;
/// Floats per cell, in the file and on the GPU, in the order [`AoFieldData::cell_values`] gives.
pub(crate) const CELL_FLOATS: usize = 28;
const CHECKSUM_BYTES: usize = 8;

/// A baked ambient occlusion field (Malmer et al. 2005): per grid cell, the fraction of the
/// sphere of directions the object blocks and the average occluded direction, on a regular grid
/// over a box around the object, in the object's own (mesh) space; counted within two distances
/// (the camera's radius and the near field's), with the signed distance to the object's surface.
#[derive(Asset, TypePath, Clone, Debug, PartialEq)]
pub struct AoFieldData {
    /// Cells per axis.
    pub resolution: UVec3,
    /// Centre of the grid box, mesh space, metres.
    pub center: Vec3,
    /// Half extents of the grid box, metres (e_i of eq. 4, or the object's bounds grown by
    /// `reach`).
    pub half_extent: Vec3,
    /// Rays count hits closer than this, metres; 0: at any distance (the paper's).
    pub reach: f32,
    /// `near_cells` count hits closer than this, metres; 0: at any distance.
    pub near_reach: f32,
    /// Per cell, x fastest: occlusion a ∈ [0, 1] (eq. 2, hits within `reach`) and the average
    /// occluded direction (unit, or zero where nothing is occluded).
    pub cells: Vec<[f32; 4]>,
    /// The same for hits within `near_reach`.
    pub near_cells: Vec<[f32; 4]>,
    /// Per cell: the signed distance from the cell's centre to the object's surface (negative
    /// inside a closed object or behind a one-sided one), then the mean offset from the cell's
    /// centre to the points where rays meet the object within `near_reach` (zero without any),
    /// metres.
    pub distances: Vec<[f32; 4]>,
    /// Per cell outside the object within two cells of its surface: the share of the
    /// cosine-weighted hemisphere of the object's surface point nearest the cell that the object
    /// blocks between `near_reach` and `reach`, among the directions open within `near_reach`
    /// (what the near field, which shades the object's own surface within `near_reach`, leaves
    /// out), then that point's unit normal on the cell's side. Zero elsewhere and in fields
    /// without a near reach.
    pub own_surface: Vec<[f32; 4]>,
    /// Per cell: what the cone model (`cells`, `near_cells` shaded as a cap clipped by the
    /// receiver's tangent plane) gets wrong on the six axis hemispheres, true occlusion minus the
    /// cone's, for receivers facing +x, −x, +y, −y, +z and −z (mesh space): within `reach`, then
    /// within `near_reach`. The lookup adds them weighted by the squared components of the
    /// receiver's normal, so an axis-facing receiver (a floor under a model standing upright)
    /// reads the traced occlusion. Zero where the bake left the cone as the paper has it.
    pub axes: Vec<[f32; 12]>,
}

/// Why bytes are not a valid `.aofield` file.
#[derive(Debug, Clone, PartialEq)]
pub enum AoFieldError {
    /// Fewer bytes than the header and checksum need.
    TooShort(usize),
    /// The file does not start with `AOFIELD\0`.
    BadMagic,
    /// A version this crate cannot read.
    UnsupportedVersion(u32),
    /// A resolution outside 2..=[`MAX_RESOLUTION`].
    BadResolution(UVec3),
    /// A centre or half extent that is not finite, or a half extent that is not positive.
    BadBox,
    /// The file is shorter or longer than its resolution says.
    WrongLength {
        /// Bytes the header promises.
        expected: usize,
        /// Bytes found.
        found: usize,
    },
    /// The stored checksum does not match the content: the file is corrupt.
    ChecksumMismatch,
    /// A cell holds a non-finite value or an occlusion outside [0, 1].
    BadCell(usize),
    /// Reading the file failed.
    Io(String),
}

impl std::fmt::Display for AoFieldError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TooShort(n) => write!(f, "not an AO field: only {n} bytes"),
            Self::BadMagic => write!(f, "not an AO field: the file does not start with AOFIELD"),
            Self::UnsupportedVersion(v) => write!(
                f,
                "AO field version {v} is not supported (this build reads version {VERSION}); \
                 bake it again"
            ),
            Self::BadResolution(r) => write!(
                f,
                "AO field resolution {r} is outside 2..={MAX_RESOLUTION} per axis"
            ),
            Self::BadBox => write!(f, "AO field box is not finite or has no extent"),
            Self::WrongLength { expected, found } => write!(
                f,
                "AO field is truncated or padded: {found} bytes where its header promises \
                 {expected}"
            ),
            Self::ChecksumMismatch => write!(f, "AO field is corrupt: its checksum does not match"),
            Self::BadCell(i) => write!(f, "AO field cell {i} holds an invalid value"),
            Self::Io(e) => write!(f, "AO field could not be read: {e}"),
        }
    }
}

impl std::error::Error for AoFieldError {}

impl From<std::io::Error> for AoFieldError {
    fn from(error: std::io::Error) -> Self {
        Self::Io(error.to_string())
    }
}

/// FNV-1a, 64 bits: small, dependency-free and good enough to catch corruption.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |hash, b| {
        (hash ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

impl AoFieldData {
    /// Bytes of the `.aofield` file of a field with `resolution` cells per axis.
    pub fn file_size(resolution: UVec3) -> usize {
        let cells = resolution.x as usize * resolution.y as usize * resolution.z as usize;
        HEADER_BYTES + cells * CELL_FLOATS * 4 + CHECKSUM_BYTES
    }

    /// Number of cells the resolution calls for.
    pub fn cell_count(&self) -> usize {
        (self.resolution.x * self.resolution.y * self.resolution.z) as usize
    }

    /// How far from the object's surface the fade of its own surface ends (half the smallest
    /// cell side), mesh units: closer, a receiver is taken to lie on the object itself.
    pub fn own_surface_fade(&self) -> f32 {
        (self.half_extent / self.resolution.as_vec3()).min_element()
    }

    /// Index of cell (x, y, z).
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        ((z * self.resolution.y + y) * self.resolution.x + x) as usize
    }

    /// Every cell's values in the order the file and the GPU buffer hold them: far occlusion and
    /// direction, near occlusion and direction, distances, own surface, axis corrections.
    pub fn cell_values(&self) -> impl Iterator<Item = [f32; CELL_FLOATS]> + '_ {
        (0..self.cells.len()).map(|i| {
            let mut values = [0.0; CELL_FLOATS];
            let parts: [&[f32]; 5] = [
                &self.cells[i],
                &self.near_cells[i],
                &self.distances[i],
                &self.own_surface[i],
                &self.axes[i],
            ];
            let mut at = 0;
            for part in parts {
                values[at..at + part.len()].copy_from_slice(part);
                at += part.len();
            }
            values
        })
    }

    /// The file bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes =
            Vec::with_capacity(HEADER_BYTES + 4 * CELL_FLOATS * self.cells.len() + CHECKSUM_BYTES);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&VERSION.to_le_bytes());
        for v in self.resolution.to_array() {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for v in self
            .center
            .to_array()
            .into_iter()
            .chain(self.half_extent.to_array())
            .chain([self.reach, self.near_reach])
        {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for values in self.cell_values() {
            for v in values {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        let checksum = fnv1a(&bytes);
        bytes.extend_from_slice(&checksum.to_le_bytes());
        bytes
    }

    /// Reads file bytes, checking everything the header promises.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, AoFieldError> {
        if bytes.len() < HEADER_BYTES + CHECKSUM_BYTES {
            return Err(AoFieldError::TooShort(bytes.len()));
        }
        if &bytes[..8] != MAGIC {
            return Err(AoFieldError::BadMagic);
        }
        let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let f32_at = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let version = u32_at(8);
        if version != VERSION {
            return Err(AoFieldError::UnsupportedVersion(version));
        }
        let resolution = UVec3::new(u32_at(12), u32_at(16), u32_at(20));
        if resolution.min_element() < 2 || resolution.max_element() > MAX_RESOLUTION {
            return Err(AoFieldError::BadResolution(resolution));
        }
        let center = Vec3::new(f32_at(24), f32_at(28), f32_at(32));
        let half_extent = Vec3::new(f32_at(36), f32_at(40), f32_at(44));
        let (reach, near_reach) = (f32_at(48), f32_at(52));
        let valid_box =
            center.is_finite() && half_extent.is_finite() && half_extent.min_element() > 0.0;
        let valid_reach =
            reach.is_finite() && reach >= 0.0 && near_reach.is_finite() && near_reach >= 0.0;
        if !(valid_box && valid_reach) {
            return Err(AoFieldError::BadBox);
        }
        let cells = (resolution.x * resolution.y * resolution.z) as usize;
        let expected = HEADER_BYTES + 4 * CELL_FLOATS * cells + CHECKSUM_BYTES;
        if bytes.len() != expected {
            return Err(AoFieldError::WrongLength {
                expected,
                found: bytes.len(),
            });
        }
        let body = &bytes[..expected - CHECKSUM_BYTES];
        let stored = u64::from_le_bytes(bytes[expected - CHECKSUM_BYTES..].try_into().unwrap());
        if fnv1a(body) != stored {
            return Err(AoFieldError::ChecksumMismatch);
        }
        let (mut far, mut near, mut distances, mut own, mut axes) = (
            Vec::with_capacity(cells),
            Vec::with_capacity(cells),
            Vec::with_capacity(cells),
            Vec::with_capacity(cells),
            Vec::with_capacity(cells),
        );
        for i in 0..cells {
            let at = HEADER_BYTES + 4 * CELL_FLOATS * i;
            let v: [f32; CELL_FLOATS] = std::array::from_fn(|k| f32_at(at + 4 * k));
            let valid = v.iter().all(|v| v.is_finite())
                && (0.0..=1.0).contains(&v[0])
                && (0.0..=1.0).contains(&v[4])
                && (0.0..=1.0).contains(&v[12])
                && v[16..].iter().all(|c| (-1.0..=1.0).contains(c));
            if !valid {
                return Err(AoFieldError::BadCell(i));
            }
            far.push([v[0], v[1], v[2], v[3]]);
            near.push([v[4], v[5], v[6], v[7]]);
            distances.push([v[8], v[9], v[10], v[11]]);
            own.push([v[12], v[13], v[14], v[15]]);
            axes.push(std::array::from_fn(|k| v[16 + k]));
        }
        Ok(Self {
            resolution,
            center,
            half_extent,
            reach,
            near_reach,
            cells: far,
            near_cells: near,
            distances,
            own_surface: own,
            axes,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field() -> AoFieldData {
        let resolution = UVec3::new(3, 2, 4);
        let cells = (0..24).map(|i| [i as f32 / 24.0, 0.0, 1.0, 0.0]).collect();
        let near_cells = (0..24).map(|i| [i as f32 / 48.0, 1.0, 0.0, 0.0]).collect();
        let distances = (0..24)
            .map(|i| [i as f32 - 12.0, 0.25, 0.0, -0.5])
            .collect();
        let own_surface = (0..24).map(|i| [i as f32 / 96.0, 0.0, 0.0, 1.0]).collect();
        let axes = (0..24)
            .map(|i| std::array::from_fn(|k| (i as f32 - k as f32) / 48.0))
            .collect();
        AoFieldData {
            resolution,
            center: Vec3::new(0.5, 1.0, -2.0),
            half_extent: Vec3::new(1.0, 2.0, 3.0),
            reach: 2.0,
            near_reach: 0.75,
            cells,
            near_cells,
            distances,
            own_surface,
            axes,
        }
    }

    #[test]
    fn round_trip() {
        let f = field();
        assert_eq!(AoFieldData::from_bytes(&f.to_bytes()), Ok(f));
    }

    #[test]
    fn bad_files_give_clear_errors() {
        let good = field().to_bytes();
        assert_eq!(
            AoFieldData::from_bytes(&good[..20]),
            Err(AoFieldError::TooShort(20))
        );
        let mut magic = good.clone();
        magic[0] = b'X';
        assert_eq!(AoFieldData::from_bytes(&magic), Err(AoFieldError::BadMagic));
        let mut version = good.clone();
        version[8] = 7;
        assert_eq!(
            AoFieldData::from_bytes(&version),
            Err(AoFieldError::UnsupportedVersion(7))
        );
        let truncated = &good[..good.len() - 17];
        assert!(matches!(
            AoFieldData::from_bytes(truncated),
            Err(AoFieldError::WrongLength { .. })
        ));
        let mut corrupt = good.clone();
        corrupt[HEADER_BYTES + 5] ^= 0x40;
        assert_eq!(
            AoFieldData::from_bytes(&corrupt),
            Err(AoFieldError::ChecksumMismatch)
        );
        let mut huge = field();
        huge.resolution = UVec3::new(1, 2, 2);
        huge.cells.truncate(4);
        huge.near_cells.truncate(4);
        huge.distances.truncate(4);
        huge.own_surface.truncate(4);
        huge.axes.truncate(4);
        assert!(matches!(
            AoFieldData::from_bytes(&huge.to_bytes()),
            Err(AoFieldError::BadResolution(_))
        ));
        let mut nan = field();
        nan.cells[3][0] = f32::NAN;
        assert_eq!(
            AoFieldData::from_bytes(&nan.to_bytes()),
            Err(AoFieldError::BadCell(3))
        );
        let mut own = field();
        own.own_surface[5][0] = 1.5;
        assert_eq!(
            AoFieldData::from_bytes(&own.to_bytes()),
            Err(AoFieldError::BadCell(5))
        );
        let mut axes = field();
        axes.axes[7][11] = -1.5;
        assert_eq!(
            AoFieldData::from_bytes(&axes.to_bytes()),
            Err(AoFieldError::BadCell(7))
        );
        // Every message names the problem in words.
        for error in [
            AoFieldError::BadMagic,
            AoFieldError::UnsupportedVersion(7),
            AoFieldError::ChecksumMismatch,
        ] {
            assert!(
                error.to_string().starts_with("not an AO field")
                    || error.to_string().starts_with("AO field")
            );
        }
    }
}

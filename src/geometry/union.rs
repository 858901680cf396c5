//! Which far-field occluders join by their union at a receiver, and which multiply as independent
//! occluders. Compose takes the union of those that join by it halfway between the largest of them
//! and their product (`compose.wgsl`); the proxies of `spheres::join` and the fields of
//! `fields::join` decide it by the rules of their modules, both in these terms.

use bevy::math::Vec3;

/// How an occluder (a mesh's proxies, or an object's AO field) joins the others at a receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProxyJoin {
    /// As independent occluders, everywhere.
    Independent,
    /// By the union, everywhere.
    Union,
    /// By the union where the receiver lies outside the box `lo`–`hi` (world space, metres,
    /// grown by its rule's receiver margin), as independent occluders inside it.
    UnionOutside {
        /// The box's lower corner.
        lo: Vec3,
        /// The box's upper corner.
        hi: Vec3,
    },
}

impl ProxyJoin {
    /// Whether the occluder joins by the union at the receiver `p`.
    pub fn joins_at(&self, p: Vec3) -> bool {
        match *self {
            Self::Independent => false,
            Self::Union => true,
            Self::UnionOutside { lo, hi } => p.cmplt(lo).any() || p.cmpgt(hi).any(),
        }
    }

    /// The GPU form both splats read: `kind` 0 independent, 1 union, 2 union outside the box
    /// whose lower and upper corners follow (zero for the other kinds).
    pub fn gpu_form(&self) -> (f32, [Vec3; 2]) {
        match *self {
            Self::Independent => (0.0, [Vec3::ZERO; 2]),
            Self::Union => (1.0, [Vec3::ZERO; 2]),
            Self::UnionOutside { lo, hi } => (2.0, [lo, hi]),
        }
    }
}

/// The union of the occluders that join by it, as `compose.wgsl` takes it: both channels of all
/// the occluders' product (`occlusion`) scaled so that those that join by their union at the
/// receiver (their product leaves `union_open` open, the largest single one blocks `largest`)
/// count halfway between that largest one and their product, and every other occluder joins as
/// an independent one.
pub fn occluder_union(occlusion: [f32; 2], union_open: f32, largest: f32) -> [f32; 2] {
    let product = 1.0 - (1.0 - occlusion[0]) * (1.0 - occlusion[1]);
    if product <= 0.0 {
        return occlusion;
    }
    let joined = 1.0 - union_open;
    let floor = largest.min(joined);
    let together = floor + 0.5 * (joined - floor);
    let others_open = ((1.0 - product) / union_open.max(1e-6)).clamp(0.0, 1.0);
    let total = 1.0 - (1.0 - together) * others_open;
    [
        occlusion[0] * total / product,
        occlusion[1] * total / product,
    ]
}

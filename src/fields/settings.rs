//! How AO fields shade a receiver, a part of [`DynamicAo`](crate::DynamicAo).

use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// How an AO field turns its stored occlusion into the share of a receiver's ambient light it
/// blocks (Malmer et al. 2005).
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq, Hash)]
pub enum FieldShading {
    /// The cone of occluded directions clipped by the receiver's tangent plane, with the
    /// diffuse cosine: T_clip(a, cos β) (§3.3.1). Also right on the object's own surface.
    #[default]
    Cone,
    /// Twice the blocked share of the sphere, 2a (§3.2): cheaper, ignores the receiver's
    /// normal, and darkens the object's own surface.
    OcclusionOnly,
}

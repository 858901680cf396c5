//! The occluder component users add, and the spheres the plugin computes for them.

use bevy::ecs::prelude::*;
use bevy::math::{Mat3, Vec3};
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Makes a mesh cast far-field occlusion through a few simple proxies (Shanmugam & Arikan 2007,
/// §5), also where the mesh is off-screen or hidden behind other surfaces.
///
/// Put it on an entity with a `Mesh3d`, or on the root of a glTF scene: then every mesh below it
/// takes part, each with its own proxies. Each mesh is fitted once, in its rest pose, and every
/// frame the proxies follow the skinned and morphed vertices, so they follow animation. A mesh
/// whose `Visibility` hides it casts nothing, and a mesh casts only on the cameras that draw it:
/// those that share a layer of its `RenderLayers` (the mesh entity's own, as Bevy reads them).
///
/// By default the proxies are oriented boxes that fill the mesh's solid ([`ProxyShape::Boxes`]):
/// one for a box, a wall or a floor, a few for a character, a ball for a round rigid part. Each blocks exactly the share of a
/// receiver's ambient light its faces cover within the camera's radius. The paper's own proxies,
/// spheres inside the surface with influence cut off where it falls below ε (eq. 5), are the
/// options [`ProxyShape::Spheres`] and [`ProxyReach::Epsilon`].
///
/// ```no_run
/// # use bevy::prelude::*;
/// # use bevy_dynamic_ao::prelude::*;
/// fn spawn(mut commands: Commands, assets: Res<AssetServer>) {
///     commands.spawn((
///         WorldAssetRoot(assets.load("character.glb#Scene0")),
///         SphereOccluder::default(),
///     ));
/// }
/// # use bevy::world_serialization::WorldAssetRoot;
/// ```
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Default, Clone, Debug)]
pub struct SphereOccluder {
    /// Most proxies per mesh. Boxes: a mesh gets as many as it needs to be filled to 3/4 by
    /// them, up to this. Spheres: Lloyd clusters, fewer where the mesh has fewer distinct
    /// vertices. No unit. Range 1 to [`SphereOccluder::MAX_COUNT`].
    /// Default: [`SphereOccluder::DEFAULT_COUNT`].
    pub count: u32,
    /// What the proxies are. Default: [`ProxyShape::Boxes`].
    pub shape: ProxyShape,
    /// How far a proxy's influence reaches. Default: [`ProxyReach::CameraRadius`].
    pub reach: ProxyReach,
}

/// The shape of far-field proxies.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Clone, Debug, PartialEq, Hash)]
pub enum ProxyShape {
    /// Oriented boxes fitted to the mesh's solid (see [`fit`](super::fit)); a box's occlusion is
    /// the cosine-weighted solid angle of its faces (Lambert's formula for polygons). A part of
    /// an unskinned mesh whose silhouettes a ball matches better than its box gets a ball, whose
    /// box would stick out at its corners.
    #[default]
    Boxes,
    /// Spheres inside the surface at the clusters of a Lloyd clustering of the vertices (the
    /// paper's §5; see [`lloyd`](super::lloyd)). They fill only part of a box-like mesh, and a
    /// floor or a wall gets spheres as thin as itself.
    Spheres,
}

/// How far a proxy's occlusion reaches.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[reflect(Default, Clone, Debug, PartialEq)]
pub enum ProxyReach {
    /// Only what lies within the radius of the camera that renders it
    /// ([`DynamicAo::radius`](crate::DynamicAo::radius)) blocks, as ground truth counts it.
    #[default]
    CameraRadius,
    /// The paper's eq. 5: a proxy's influence is cut off where it falls below this share ε of a
    /// receiver's ambient light (10 radii at ε = 0.01), however far that is; nearer, all of it
    /// counts. Range (0, 1).
    Epsilon(f32),
}

impl SphereOccluder {
    /// Default most proxies per mesh.
    pub const DEFAULT_COUNT: u32 = 16;
    /// The paper's ε of eq. 5, for [`ProxyReach::Epsilon`].
    pub const PAPER_EPSILON: f32 = 0.01;
    /// Most proxies per mesh.
    pub const MAX_COUNT: u32 = 1024;

    /// These settings with out-of-range values replaced: the count clamped into
    /// 1..=[`Self::MAX_COUNT`], a non-finite or out-of-range ε set to [`Self::PAPER_EPSILON`].
    pub fn sanitized(&self) -> Self {
        Self {
            count: self.count.clamp(1, Self::MAX_COUNT),
            shape: self.shape,
            reach: match self.reach {
                ProxyReach::Epsilon(e) if !(e.is_finite() && e > 0.0 && e < 1.0) => {
                    ProxyReach::Epsilon(Self::PAPER_EPSILON)
                }
                reach => reach,
            },
        }
    }
}

impl Default for SphereOccluder {
    fn default() -> Self {
        Self {
            count: Self::DEFAULT_COUNT,
            shape: ProxyShape::Boxes,
            reach: ProxyReach::CameraRadius,
        }
    }
}

/// One far-field proxy in world space: a box or a sphere.
#[derive(Clone, Copy, Debug, PartialEq, Reflect)]
pub struct OccluderSphere {
    /// Centre, world space, metres.
    pub center: Vec3,
    /// Radius of a sphere; of a box, half its diagonal: every point of the proxy lies within it.
    /// Metres.
    pub radius: f32,
    /// Half-extent vectors of a box (columns, world space, metres); `radius` × identity for a
    /// sphere.
    pub axes: Mat3,
    /// Which kind of proxy this is.
    pub shape: ProxyShape,
}

/// The proxies of one mesh this frame, world space. The plugin adds and updates this on every
/// mesh that takes part in a [`SphereOccluder`], after animation and transform propagation;
/// read it to inspect what the far field sees.
#[derive(Component, Clone, Debug, Default, Reflect)]
#[reflect(Component, Default, Clone, Debug)]
pub struct OccluderSpheres {
    /// The proxies; empty while the mesh is still being fitted or when it cannot be.
    pub spheres: Vec<OccluderSphere>,
    /// The reach of the [`SphereOccluder`] this mesh belongs to.
    pub reach: ProxyReach,
    /// The mesh is skinned, or encloses a volume with more than one proxy: its proxies stand one
    /// behind another as a receiver sees them (an arm before the torso, a ring's near side
    /// before its far side), and compose takes their union rather than their product,
    /// everywhere. An open mesh with several proxies (a frame, a room, whose walls surround a
    /// receiver inside it) joins them by the union only where the receiver lies outside them,
    /// and a mesh with one proxy joins as an independent occluder but where it stands inside
    /// such a mesh's proxies ([`join`](super::join) says which).
    pub articulated: bool,
}

/// d_far of Shanmugam & Arikan eq. 5: the distance from a sphere's centre beyond which it
/// blocks less than `epsilon` of a receiver's ambient light, metres.
///
/// With occlusion measured as a fraction of ambient light (A_ψ / π, see
/// `shaders/sphere_occlusion.wgsl`) eq. 5 reads d_far = r / sin(acos(1 − ε/2)).
pub fn far_field_reach(radius: f32, epsilon: f32) -> f32 {
    let cos = 1.0 - 0.5 * epsilon;
    radius / (1.0 - cos * cos).max(1e-12).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_match_the_docs() {
        let d = SphereOccluder::default();
        assert_eq!(d.count, 16);
        assert_eq!(d.shape, ProxyShape::Boxes);
        assert_eq!(d.reach, ProxyReach::CameraRadius);
        assert_eq!(d.sanitized(), d);
        let bad = SphereOccluder {
            count: 0,
            reach: ProxyReach::Epsilon(f32::NAN),
            ..d
        }
        .sanitized();
        assert_eq!((bad.count, bad.reach), (1, ProxyReach::Epsilon(0.01)));
    }
}

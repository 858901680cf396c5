//! The occluder component users add, and the spheres the plugin computes for them.

use bevy::ecs::prelude::*;
use bevy::math::Vec3;
use bevy::reflect::{Reflect, std_traits::ReflectDefault};

/// Makes a mesh cast far-field occlusion through spheres (Shanmugam & Arikan 2007, §5).
///
/// Put it on an entity with a `Mesh3d`, or on the root of a glTF scene: then every mesh below it
/// takes part, each with its own spheres. The rest pose of each mesh is clustered once (Lloyd,
/// area-weighted) into `count` spheres, and every frame the spheres are refit from the skinned and
/// morphed vertices, so they follow animation. Each sphere darkens every visible surface within
/// its reach d_far (eq. 5), also when the mesh itself is off-screen or behind other surfaces.
/// A mesh whose `Visibility` hides it casts nothing.
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
    /// Spheres per mesh (Lloyd clusters). Units: N/A. Range 1 to [`SphereOccluder::MAX_COUNT`];
    /// a mesh with fewer distinct vertices gets fewer. Default [`SphereOccluder::DEFAULT_COUNT`].
    pub count: u32,
    /// ε of eq. 5: the occlusion, as a fraction of ambient light, below which a sphere's
    /// influence is cut off. It sets the reach d_far of each sphere (10 radii at 0.01); smaller
    /// is wider and costlier. Units: N/A. Range (0, 1). Default
    /// [`SphereOccluder::DEFAULT_EPSILON`].
    pub epsilon: f32,
}

impl SphereOccluder {
    /// Default sphere count per mesh.
    pub const DEFAULT_COUNT: u32 = 16;
    /// Default cut-off occlusion ε.
    pub const DEFAULT_EPSILON: f32 = 0.01;
    /// Most spheres per mesh.
    pub const MAX_COUNT: u32 = 1024;

    /// These settings with out-of-range values replaced: the count clamped into
    /// 1..=[`Self::MAX_COUNT`], a non-finite or out-of-range ε set to the default.
    pub fn sanitized(&self) -> Self {
        Self {
            count: self.count.clamp(1, Self::MAX_COUNT),
            epsilon: if self.epsilon.is_finite() && self.epsilon > 0.0 && self.epsilon < 1.0 {
                self.epsilon
            } else {
                Self::DEFAULT_EPSILON
            },
        }
    }
}

impl Default for SphereOccluder {
    fn default() -> Self {
        Self {
            count: Self::DEFAULT_COUNT,
            epsilon: Self::DEFAULT_EPSILON,
        }
    }
}

/// One occluding sphere in world space.
#[derive(Clone, Copy, Debug, PartialEq, Reflect)]
pub struct OccluderSphere {
    /// Centre, world space, metres.
    pub center: Vec3,
    /// Radius, metres.
    pub radius: f32,
}

/// The spheres of one mesh this frame, world space. The plugin adds and updates this on every
/// mesh that takes part in a [`SphereOccluder`], after animation and transform propagation;
/// read it to inspect what the far field sees.
#[derive(Component, Clone, Debug, Default, Reflect)]
#[reflect(Component, Default, Clone, Debug)]
pub struct OccluderSpheres {
    /// The spheres; empty while the mesh is still being clustered or when it cannot be.
    pub spheres: Vec<OccluderSphere>,
    /// ε of the [`SphereOccluder`] this mesh belongs to.
    pub epsilon: f32,
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
    use crate::reference::near_field::sphere_occlusion;

    #[test]
    fn defaults_match_the_docs() {
        let d = SphereOccluder::default();
        assert_eq!(d.count, 16);
        assert_eq!(d.epsilon, 0.01);
        assert_eq!(d.sanitized(), d);
        let bad = SphereOccluder {
            count: 0,
            epsilon: f32::NAN,
        }
        .sanitized();
        assert_eq!((bad.count, bad.epsilon), (1, 0.01));
    }

    #[test]
    fn occlusion_at_reach_is_epsilon() {
        for epsilon in [0.005, 0.02, 0.1] {
            let reach = far_field_reach(0.3, epsilon);
            // Facing the sphere, at exactly d_far.
            let a = sphere_occlusion(Vec3::new(0.0, reach, 0.0), 0.3, Vec3::ZERO, Vec3::Y);
            assert!((a - epsilon).abs() < 1e-4, "ε {epsilon}: {a}");
            let beyond =
                sphere_occlusion(Vec3::new(0.0, reach * 1.1, 0.0), 0.3, Vec3::ZERO, Vec3::Y);
            assert!(beyond < epsilon);
        }
        assert!((far_field_reach(1.0, 0.01) - 10.01).abs() < 0.01);
    }
}

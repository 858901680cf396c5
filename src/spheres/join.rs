//! How each mesh's proxies join the others' at a receiver: by their union (parts of one object
//! that stand one behind another as the receiver sees them) or as independent occluders.
//!
//! Compose takes the union of the proxies that join by it halfway between the largest of them and
//! their product (`compose.wgsl`); every other proxy multiplies. Which proxies join by the union:
//!
//! - every proxy of a skinned mesh, and of a closed mesh with several (a character's arm before
//!   its torso, a ring's near side before its far side): [`ProxyJoin::Union`];
//! - the proxies of an open rigid mesh with several (a window frame, a chair, a room), where the
//!   receiver lies outside the box that bounds them, and as independent occluders inside it: seen
//!   from outside, an object's parts lie on one side and hide one another (the 16 boxes of a cube
//!   frame multiplied darkened the floor around it to 5× the error of the image-space term alone
//!   at 2 m), while a room's walls stand round the floor inside it and hide nothing of one another
//!   (joined by their union everywhere, CornellBox's error rose by a quarter):
//!   [`ProxyJoin::UnionOutside`];
//! - a mesh whose proxies lie within such a box joins that mesh's union there, outside the box:
//!   the box inside a frame stands behind the frame's bars as the floor beside them sees it;
//! - every other proxy is an independent occluder ([`ProxyJoin::Independent`]): one box per mesh
//!   for a floor, a wall, a prop, which lie in different directions from what they shade.
//!
//! The union is one for the whole view, not per object: two objects side by side both seen from
//! outside join by it too, which counts less than the two cast together.

use bevy::math::Vec3;

use super::component::OccluderSpheres;
pub use crate::geometry::union::ProxyJoin;

/// Grows a mesh's proxy bounds on every side by this share of their longest side before a
/// receiver is tested against them: receivers on the mesh's own outer surface, which the shrunk
/// proxies may not reach, and on a flat mesh's plane count as inside.
const RECEIVER_MARGIN: f32 = 0.02;
/// A mesh's proxies lie within another's bounds where they lie within those bounds grown by this
/// share of their longest side (the box inside a frame reaches the frame's faces, which the
/// frame's shrunk proxies do not).
const NEST_MARGIN: f32 = 0.05;

/// The box that bounds every proxy of `occluder` (world space, metres), `None` where it has none
/// or one that is not finite.
fn proxy_bounds(occluder: &OccluderSpheres) -> Option<(Vec3, Vec3)> {
    let mut bounds: Option<(Vec3, Vec3)> = None;
    for proxy in &occluder.spheres {
        let extent = proxy.axes.x_axis.abs() + proxy.axes.y_axis.abs() + proxy.axes.z_axis.abs();
        let (lo, hi) = (proxy.center - extent, proxy.center + extent);
        if !lo.is_finite() || !hi.is_finite() {
            return None;
        }
        bounds = Some(bounds.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
    }
    bounds
}

/// `lo`–`hi` grown on every side by `share` of its longest side.
fn grown((lo, hi): (Vec3, Vec3), share: f32) -> (Vec3, Vec3) {
    let margin = Vec3::splat((hi - lo).max_element() * share);
    (lo - margin, hi + margin)
}

/// How the proxies of each of `occluders` join the rest, in their order.
pub fn proxy_joins<'a>(
    occluders: impl IntoIterator<Item = &'a OccluderSpheres> + Clone,
) -> Vec<ProxyJoin> {
    // The open rigid meshes with several proxies, and the boxes that bound them.
    let groups: Vec<(Vec3, Vec3)> = occluders
        .clone()
        .into_iter()
        .filter(|o| !o.articulated && o.spheres.len() > 1)
        .filter_map(proxy_bounds)
        .collect();
    let volume = |(lo, hi): &(Vec3, Vec3)| (*hi - *lo).max(Vec3::splat(1e-6)).element_product();
    occluders
        .into_iter()
        .map(|occluder| {
            if occluder.articulated {
                return ProxyJoin::Union;
            }
            let Some(own) = proxy_bounds(occluder) else {
                return ProxyJoin::Independent;
            };
            let group = if occluder.spheres.len() > 1 {
                Some(own)
            } else {
                // The tightest group box this mesh's proxies lie within.
                groups
                    .iter()
                    .filter(|outer| {
                        let (lo, hi) = grown(**outer, NEST_MARGIN);
                        own.0.cmpge(lo).all() && own.1.cmple(hi).all()
                    })
                    .min_by(|a, b| volume(a).total_cmp(&volume(b)))
                    .copied()
            };
            group.map_or(ProxyJoin::Independent, |bounds| {
                let (lo, hi) = grown(bounds, RECEIVER_MARGIN);
                ProxyJoin::UnionOutside { lo, hi }
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spheres::{OccluderSphere, ProxyShape};
    use bevy::math::Mat3;

    fn cube(center: Vec3, half: f32) -> OccluderSphere {
        OccluderSphere {
            center,
            radius: half * 3f32.sqrt(),
            axes: Mat3::from_diagonal(Vec3::splat(half)),
            shape: ProxyShape::Boxes,
        }
    }

    fn mesh(proxies: Vec<OccluderSphere>, articulated: bool) -> OccluderSpheres {
        OccluderSpheres {
            spheres: proxies,
            articulated,
            ..OccluderSpheres::default()
        }
    }

    #[test]
    fn a_frame_joins_outside_its_bounds_with_what_it_holds() {
        // Eight corner blocks of a 1 m frame, a box inside it, a box beside it, a floor's one
        // flat box under everything, a character.
        let corners = (0..8)
            .map(|i| {
                let s = |bit: usize| if i & bit == 0 { -0.4 } else { 0.4 };
                cube(Vec3::new(s(1), 0.5 + s(2), s(4)), 0.1)
            })
            .collect();
        let floor = OccluderSphere {
            axes: Mat3::from_diagonal(Vec3::new(10.0, 0.0, 10.0)),
            ..cube(Vec3::ZERO, 10.0)
        };
        let occluders = [
            mesh(corners, false),
            mesh(vec![cube(Vec3::new(0.0, 0.5, 0.0), 0.3)], false),
            mesh(vec![cube(Vec3::new(2.0, 0.5, 0.0), 0.3)], false),
            mesh(vec![floor], false),
            mesh(vec![cube(Vec3::X, 0.2), cube(Vec3::Z, 0.2)], true),
            mesh(Vec::new(), false),
        ];
        let joins = proxy_joins(&occluders);
        let ProxyJoin::UnionOutside { lo, hi } = joins[0] else {
            panic!("the frame: {:?}", joins[0]);
        };
        // Its proxies' bounds, grown by 2 cm.
        assert!(lo.abs_diff_eq(Vec3::new(-0.52, -0.02, -0.52), 1e-5), "{lo}");
        assert!(hi.abs_diff_eq(Vec3::new(0.52, 1.02, 0.52), 1e-5), "{hi}");
        assert_eq!(
            joins[1], joins[0],
            "the box inside the frame joins its union"
        );
        assert_eq!(
            joins[2],
            ProxyJoin::Independent,
            "the box beside it does not"
        );
        assert_eq!(joins[3], ProxyJoin::Independent, "nor the floor");
        assert_eq!(joins[4], ProxyJoin::Union);
        assert_eq!(joins[5], ProxyJoin::Independent);
        // The floor beside the frame sees its parts one behind another; the floor inside it, a
        // point on its own face and one within the margin are inside.
        assert!(joins[0].joins_at(Vec3::new(0.8, 0.0, 0.0)));
        assert!(joins[0].joins_at(Vec3::new(0.0, 1.5, 0.0)));
        for inside in [
            Vec3::ZERO,
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(0.0, 0.5, -0.515),
        ] {
            assert!(!joins[0].joins_at(inside), "{inside}");
        }
        assert!(!ProxyJoin::Independent.joins_at(Vec3::ZERO));
        assert!(ProxyJoin::Union.joins_at(Vec3::ZERO));
    }

    #[test]
    fn a_box_joins_the_tightest_group_it_lies_in_and_bad_proxies_join_none() {
        let room = mesh(
            vec![
                cube(Vec3::new(-2.0, 1.0, 0.0), 1.0),
                cube(Vec3::new(2.0, 1.0, 0.0), 1.0),
            ],
            false,
        );
        let shelf = mesh(
            vec![
                cube(Vec3::new(-0.2, 0.5, 0.0), 0.2),
                cube(Vec3::new(0.2, 0.5, 0.0), 0.2),
            ],
            false,
        );
        let book = mesh(vec![cube(Vec3::new(0.1, 0.5, 0.0), 0.05)], false);
        let broken = mesh(vec![cube(Vec3::NAN, 0.1), cube(Vec3::ZERO, 0.1)], false);
        let joins = proxy_joins(&[room, shelf, book, broken]);
        assert_eq!(joins[2], joins[1], "the book joins the shelf, not the room");
        assert_ne!(joins[1], joins[0]);
        assert_eq!(joins[3], ProxyJoin::Independent);
    }
}

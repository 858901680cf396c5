//! How each object's AO field joins the others' at a receiver (`geometry::union`): by their union
//! where one object fills another's bounds (lies within them and takes at least a quarter of
//! their volume) and the receiver lies outside them, as independent occluders everywhere else.
//!
//! Blending multiplies the fields (Malmer et al. §3.3.2), which counts an occluder once only where
//! the objects lie in different directions from the receiver. An object within another's bounds
//! (the box inside BoxAnimated's frame, which fills it at the start of its animation; a model's
//! parts within its body) stands behind the outer object's surface as a receiver outside it sees
//! them: multiplied, the two fields counted what they share twice, and a floor around the frame
//! read darker than with no field at all. Both join compose's union there, halfway between the
//! larger and their product, as a character's proxies do (`spheres::join`); inside the outer
//! bounds (a room's floor among the boxes standing on it) they multiply.

use bevy::math::{Affine3A, Vec3};

use super::format::AoFieldData;
pub use crate::geometry::union::ProxyJoin;

/// An object lies within another's bounds where it lies within them grown by this share of each
/// side (a box that fills a frame meets the frame's faces).
const NEST_MARGIN: f32 = 0.05;
/// A receiver lies outside an object's bounds where it lies outside them grown by this share of
/// each side: receivers on the object's own surface count as inside.
const RECEIVER_MARGIN: f32 = 0.02;
/// Each side's margin is taken of at least this share of the longest side, so that a flat
/// object's plane (a floor's) has a margin across it too.
const FLAT_SIDE: f32 = 0.1;
/// An object joins the union of the bounds it lies within only where its bounds take at least
/// this share of their volume: one that fills another (a box in its frame, a model's clothes on
/// its body) stands behind it in every direction a receiver outside sees it in, while a small
/// box in an open room is seen through the opening beside the walls (CornellBox on a floor,
/// every mesh a field, joined to the default at R = 2 m: 0.0931 independent, 0.0966 joined by
/// the union).
const FILL_SHARE: f32 = 0.25;

fn volume((lo, hi): (Vec3, Vec3)) -> f32 {
    (hi - lo).max(Vec3::ZERO).element_product()
}

/// Whether `inner` lies within `outer` and fills at least [`FILL_SHARE`] of it.
fn fills(inner: (Vec3, Vec3), outer: (Vec3, Vec3)) -> bool {
    let (lo, hi) = grown(outer, NEST_MARGIN);
    inner.0.cmpge(lo).all()
        && inner.1.cmple(hi).all()
        && volume(inner) >= FILL_SHARE * volume(outer)
}

/// `lo`–`hi` grown on each side by `share` of that side (of at least [`FLAT_SIDE`] of the
/// longest).
fn grown((lo, hi): (Vec3, Vec3), share: f32) -> (Vec3, Vec3) {
    let size = hi - lo;
    let margin = size.max(Vec3::splat(FLAT_SIDE * size.max_element())) * share;
    (lo - margin, hi + margin)
}

/// The world-space box that bounds the object a field was baked from, placed by
/// `world_from_field`; `None` for a field with no finite reach (its grid box says nothing of the
/// object's size) or a transform that is not finite.
pub fn object_bounds(field: &AoFieldData, world_from_field: Affine3A) -> Option<(Vec3, Vec3)> {
    if !(field.reach > 0.0 && field.reach.is_finite()) {
        return None;
    }
    let half = (field.half_extent - Vec3::splat(field.reach)).max(Vec3::ZERO);
    let mut bounds: Option<(Vec3, Vec3)> = None;
    for corner in 0..8 {
        let sign = Vec3::new(
            if corner & 1 == 0 { -1.0 } else { 1.0 },
            if corner & 2 == 0 { -1.0 } else { 1.0 },
            if corner & 4 == 0 { -1.0 } else { 1.0 },
        );
        let p = world_from_field.transform_point3(field.center + sign * half);
        if !p.is_finite() {
            return None;
        }
        bounds = Some(bounds.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
    }
    bounds
}

/// How the field of each object, bounded by `bounds` (world space; `None`: unknown), joins the
/// others, in their order.
pub fn field_joins(bounds: &[Option<(Vec3, Vec3)>]) -> Vec<ProxyJoin> {
    let known: Vec<(usize, (Vec3, Vec3))> = bounds
        .iter()
        .enumerate()
        .filter_map(|(i, b)| b.map(|b| (i, b)))
        .collect();
    let boxes: Vec<(Vec3, Vec3)> = known.iter().map(|(_, b)| *b).collect();
    let mut joins = vec![ProxyJoin::Independent; bounds.len()];
    for (k, (i, own)) in known.iter().enumerate() {
        // The tightest bounds of another object this one fills.
        let outer = boxes
            .iter()
            .enumerate()
            .filter(|(m, outer)| *m != k && fills(*own, **outer))
            .map(|(_, outer)| *outer)
            .min_by(|a, b| volume(*a).total_cmp(&volume(*b)));
        let holds_another = || {
            boxes
                .iter()
                .enumerate()
                .any(|(m, inner)| m != k && fills(*inner, *own))
        };
        let group = outer.or_else(|| holds_another().then_some(*own));
        if let Some(group) = group {
            let (lo, hi) = grown(group, RECEIVER_MARGIN);
            joins[*i] = ProxyJoin::UnionOutside { lo, hi };
        }
    }
    joins
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(center: Vec3, half: f32) -> Option<(Vec3, Vec3)> {
        Some((center - half, center + half))
    }

    #[test]
    fn an_object_within_another_joins_it_outside_its_bounds() {
        let frame = cube(Vec3::new(0.0, 0.6, 0.0), 0.6);
        // Fills the frame (BoxAnimated at the start of its animation).
        let inner = cube(Vec3::new(0.0, 0.6, 0.0), 0.6);
        let floor = Some((Vec3::new(-10.0, -0.1, -10.0), Vec3::new(10.0, 0.0, 10.0)));
        let apart = cube(Vec3::new(4.0, 0.5, 0.0), 0.5);
        let joins = field_joins(&[floor, frame, inner, apart, None]);
        assert_eq!(joins[0], ProxyJoin::Independent, "the floor holds nothing");
        assert_eq!(
            joins[3],
            ProxyJoin::Independent,
            "nothing holds the box apart"
        );
        assert_eq!(joins[4], ProxyJoin::Independent, "unknown bounds");
        for join in [joins[1], joins[2]] {
            let ProxyJoin::UnionOutside { lo, hi } = join else {
                panic!("{join:?}");
            };
            // The frame's bounds grown by 2 %: its own faces count as inside.
            assert!((lo - Vec3::new(-0.624, -0.024, -0.624)).abs().max_element() < 1e-5);
            assert!((hi - Vec3::new(0.624, 1.224, 0.624)).abs().max_element() < 1e-5);
            assert!(
                join.joins_at(Vec3::new(1.0, 0.0, 0.0)),
                "the floor beside it"
            );
            assert!(
                !join.joins_at(Vec3::new(0.3, 0.0, 0.0)),
                "the floor under it"
            );
            assert!(!join.joins_at(Vec3::new(0.6, 0.5, 0.0)), "its own face");
        }
    }

    #[test]
    fn a_box_on_a_floor_or_small_in_a_room_multiplies_and_one_that_fills_another_joins_it() {
        let floor = Some((Vec3::new(-10.0, -0.1, -10.0), Vec3::new(10.0, 0.0, 10.0)));
        // A counter 0.9 m tall on the floor: above the floor's bounds grown by 0.1 m.
        let counter = Some((Vec3::new(-1.6, 0.0, -0.5), Vec3::new(1.6, 0.9, 0.5)));
        // A 1 m chest in a 4 m room: within its bounds, but a 64th of them.
        let room = cube(Vec3::ZERO, 2.0);
        let chest = cube(Vec3::new(0.5, -1.5, 0.5), 0.5);
        assert_eq!(
            field_joins(&[floor, counter, room, chest]),
            vec![ProxyJoin::Independent; 4]
        );
        // A crate, a liner filling it, and a box filling the liner: each joins the tightest
        // bounds it fills, the crate its own.
        let crate_box = cube(Vec3::ZERO, 0.5);
        let liner = cube(Vec3::ZERO, 0.4);
        let inner = cube(Vec3::ZERO, 0.3);
        let joins = field_joins(&[crate_box, liner, inner]);
        let bounds = |join: ProxyJoin| match join {
            ProxyJoin::UnionOutside { lo, hi } => (lo, hi),
            other => panic!("{other:?}"),
        };
        assert_eq!(bounds(joins[0]), grown(crate_box.unwrap(), RECEIVER_MARGIN));
        assert_eq!(bounds(joins[1]), grown(crate_box.unwrap(), RECEIVER_MARGIN));
        assert_eq!(bounds(joins[2]), grown(liner.unwrap(), RECEIVER_MARGIN));
    }
}

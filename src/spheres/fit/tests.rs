use bevy::math::Quat;
use bevy::prelude::*;

use super::*;

fn rest(mesh: Mesh, transform: Transform) -> RestMesh {
    RestMesh::from_mesh(&mesh.transformed_by(transform)).unwrap()
}

fn half_extents(s: &RestSphere) -> Vec3 {
    Vec3::new(
        s.axes.x_axis.length(),
        s.axes.y_axis.length(),
        s.axes.z_axis.length(),
    )
}

#[test]
fn a_box_is_one_box() {
    let turned = Transform::from_rotation(Quat::from_euler(EulerRot::XYZ, 0.3, 0.7, -0.2));
    let fitted = fit_boxes(&rest(Cuboid::new(1.0, 0.5, 2.0).into(), turned), 16);
    assert_eq!(fitted.spheres.len(), 1, "{:?}", fitted.spheres);
    assert_eq!(fitted.spheres[0].shape, ProxyShape::Boxes);
    let mut half = half_extents(&fitted.spheres[0]).to_array();
    half.sort_by(f32::total_cmp);
    for (got, want) in half.iter().zip([0.25, 0.5, 1.0]) {
        assert!((got - want).abs() < 0.03, "{half:?}");
    }
    assert!(fitted.spheres[0].center.length() < 0.02);
}

#[test]
fn a_floor_is_one_flat_box() {
    let fitted = fit_boxes(
        &rest(
            Plane3d::default().mesh().size(20.0, 20.0).build(),
            Transform::IDENTITY,
        ),
        16,
    );
    assert_eq!(fitted.spheres.len(), 1);
    let h = half_extents(&fitted.spheres[0]);
    let mut sorted = h.to_array();
    sorted.sort_by(f32::total_cmp);
    assert!(sorted[0] < 1e-4, "a floor has no thickness: {h}");
    assert!(
        (sorted[1] - 10.0).abs() < 0.1 && (sorted[2] - 10.0).abs() < 0.1,
        "{h}"
    );
}

#[test]
fn an_l_shape_takes_two_boxes() {
    // Two 1 × 0.2 × 0.2 bars meeting at a corner.
    let mut mesh: Mesh = Cuboid::new(1.0, 0.2, 0.2).into();
    mesh = mesh.transformed_by(Transform::from_xyz(0.5, 0.0, 0.0));
    let mut other: Mesh = Cuboid::new(0.2, 1.0, 0.2).into();
    other = other.transformed_by(Transform::from_xyz(-0.1, 0.6, 0.0));
    mesh.merge(&other).unwrap();
    let fitted = fit_boxes(&RestMesh::from_mesh(&mesh).unwrap(), 16);
    assert!(
        (2..=4).contains(&fitted.spheres.len()),
        "{} boxes",
        fitted.spheres.len()
    );
    let volume: f32 = fitted
        .spheres
        .iter()
        .map(|s| 8.0 * half_extents(s).x * half_extents(s).y * half_extents(s).z)
        .sum();
    // The solid is 0.08 m³; its bounding box 0.24 m³.
    assert!((0.06..0.12).contains(&volume), "boxes hold {volume} m³");
}

#[test]
fn a_ball_gets_a_ball_of_its_mean_silhouette() {
    let fitted = fit_boxes(
        &rest(Sphere::new(0.5).mesh().uv(32, 16), Transform::IDENTITY),
        1,
    );
    assert_eq!(fitted.spheres.len(), 1);
    let ball = &fitted.spheres[0];
    assert_eq!(
        ball.shape,
        ProxyShape::Spheres,
        "a ball's box sticks out at its corners"
    );
    // Its silhouette area is the ball's, a little less for the sampled surface's facets.
    for radius in half_extents(ball)
        .to_array()
        .into_iter()
        .chain([ball.radius])
    {
        assert!((radius - 0.5).abs() < 0.02, "radius {radius}");
    }
    assert!(ball.center.length() < 0.01, "{}", ball.center);
}

#[test]
fn boxes_and_cylinders_stay_boxes() {
    // A cylinder is round seen along its axis but not across it: its box matches more of its
    // silhouettes than any ball. A long ellipsoid, too: no ball fits it.
    for (mesh, transform) in [
        (Cuboid::new(0.6, 0.6, 0.6).into(), Transform::IDENTITY),
        (
            Cylinder::new(0.3, 0.6).mesh().resolution(32).build(),
            Transform::IDENTITY,
        ),
        (
            Sphere::new(0.5).mesh().uv(32, 16),
            Transform::from_scale(Vec3::new(1.0, 0.4, 0.4)),
        ),
    ] {
        let fitted = fit_boxes(&rest(mesh, transform), 1);
        assert_eq!(fitted.spheres[0].shape, ProxyShape::Boxes);
    }
}

#[test]
fn every_vertex_belongs_to_a_box() {
    let mesh = rest(Capsule3d::new(0.2, 1.0).mesh().into(), Transform::IDENTITY);
    let fitted = fit_boxes(&mesh, 4);
    assert_eq!(fitted.order.len(), mesh.positions.len());
    assert!(!fitted.spheres.is_empty() && fitted.spheres.len() <= 4);
}

/// Samples along a vertical bar of square section, `joint` moving them all.
fn bar(x: f32, y: std::ops::Range<f32>, side: f32, joint: u16) -> Vec<samples::Sample> {
    let step = 0.01;
    let mut out = Vec::new();
    let mut h = y.start;
    while h < y.end {
        for i in 0..=(side / step) as i32 {
            for (dx, dz) in [(i as f32 * step, 0.0), (i as f32 * step, side)] {
                out.push(samples::Sample {
                    position: Vec3::new(x + dx, h, dz),
                    weight: step * step,
                    normal: Vec3::Z,
                    joint,
                });
            }
        }
        h += step;
    }
    out
}

#[test]
fn a_foot_joins_its_own_leg_not_the_foot_beside_it() {
    // Two legs 0.3 m apart, each a thigh (0.5 m, 8 cm thick) over a lighter shin (0.45 m,
    // 6 cm). The shins' centres are 0.3 m apart, each 0.475 m from its own thigh's.
    let cell = 0.02;
    let samples: Vec<_> = [
        bar(-0.15, 0.5..1.0, 0.08, 0),
        bar(-0.15, 0.05..0.5, 0.06, 1),
        bar(0.15, 0.5..1.0, 0.08, 2),
        bar(0.15, 0.05..0.5, 0.06, 3),
    ]
    .concat();
    let clusters = joint_clusters(samples, 3, cell);
    assert_eq!(clusters.len(), 3);
    for c in &clusters {
        let sides = (
            c.samples.iter().any(|s| s.position.x < 0.0),
            c.samples.iter().any(|s| s.position.x > 0.0),
        );
        assert!(
            sides != (true, true),
            "a box spans both legs: {:?}",
            c.center
        );
    }
}

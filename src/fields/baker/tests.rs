use bevy::math::Affine3A;
use bevy::prelude::*;

use super::*;
use crate::geometry::triangles::TriangleScene;

fn cube() -> Vec<Triangle> {
    let mut scene = TriangleScene::default();
    scene.add_mesh(&Cuboid::new(1.0, 1.0, 1.0).into(), Affine3A::IDENTITY);
    scene.triangles
}

/// Blocked fraction of all directions at `p`, by testing every triangle for each of many
/// pseudo-random directions: no BVH, no shared direction set.
fn brute_force(triangles: &[Triangle], p: Vec3, rays: u32) -> f32 {
    let mut blocked = 0;
    let mut state = 12345u32;
    let mut next = || {
        state = crate::geometry::hash::pcg_hash(state);
        state as f32 / u32::MAX as f32
    };
    for _ in 0..rays {
        let z = 2.0 * next() - 1.0;
        let phi = std::f32::consts::TAU * next();
        let r = (1.0 - z * z).sqrt();
        let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let hit = triangles.iter().any(|t| {
            let [a, b, c] = t.vertices;
            let (e1, e2) = (b - a, c - a);
            let h = d.cross(e2);
            let det = e1.dot(h);
            if det.abs() < 1e-9 {
                return false;
            }
            let s = p - a;
            let u = s.dot(h) / det;
            let q = s.cross(e1);
            let v = d.dot(q) / det;
            u >= 0.0 && v >= 0.0 && u + v <= 1.0 && e2.dot(q) / det > 0.0
        });
        blocked += u32::from(hit);
    }
    blocked as f32 / rays as f32
}

#[test]
fn extent_follows_equation_4() {
    let (center, e) = grid_box(Vec3::splat(-0.5), Vec3::splat(0.5), 0.1);
    assert_eq!(center, Vec3::ZERO);
    // r = 0.5, A = 1: e = 0.5 + sqrt(1 / 0.4π) ≈ 1.392, about 3 r as the paper says.
    assert!(
        (e.x - 1.392).abs() < 1e-3 && e.x == e.y && e.y == e.z,
        "{e}"
    );
    // An elongated box gets a grid that is relatively thinner along its long axis.
    let (_, e) = grid_box(
        Vec3::new(-1.0, -0.25, -0.25),
        Vec3::new(1.0, 0.25, 0.25),
        0.1,
    );
    assert!((e.x - (1.0 + (0.25f32 / (0.4 * std::f32::consts::PI)).sqrt())).abs() < 1e-4);
    assert!(e.x / 1.0 < e.y / 0.25);
}

#[test]
fn baked_values_match_a_brute_force_ray_cast() {
    let settings = BakeSettings {
        resolution: 8,
        rays: 1024,
        ..BakeSettings::paper()
    }
    .without_fixes();
    let triangles = cube();
    let field = bake(triangles.clone(), &settings, &|_, _| {}).unwrap();
    let cell = 2.0 * field.half_extent / 8.0;
    let mut compared = 0;
    for (x, y, z) in [
        (0, 0, 0),
        (1, 3, 4),
        (2, 4, 4),
        (3, 7, 2),
        (5, 5, 1),
        (7, 4, 4),
    ] {
        let p = field.center - field.half_extent
            + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * cell;
        let expected = brute_force(&triangles, p, 4096);
        let got = field.cells[field.index(x, y, z)][0];
        // 1024 lattice rays against 4096 random ones: both within about 0.01 of the truth.
        assert!(
            (got - expected).abs() < 0.03,
            "cell ({x},{y},{z}) at {p}: baked {got}, brute force {expected}"
        );
        compared += 1;
    }
    assert_eq!(compared, 6);
    // Beside the cube on +x, the occluded directions point back at it.
    let c = field.cells[field.index(7, 4, 4)];
    assert!(c[1] < -0.9, "{c:?}");
}

#[test]
fn border_rescale_leaves_no_step_at_the_boundary() {
    let settings = BakeSettings {
        resolution: 12,
        rays: 256,
        ..BakeSettings::paper()
    };
    let field = bake(cube(), &settings, &|_, _| {}).unwrap();
    let r = field.resolution;
    let mut boundary_max = 0.0f32;
    let mut inner_max = 0.0f32;
    for z in 0..r.z {
        for y in 0..r.y {
            for x in 0..r.x {
                let a = field.cells[field.index(x, y, z)][0];
                let edge = [x, y, z].iter().any(|&c| c == 0 || c == r.x - 1);
                if edge {
                    boundary_max = boundary_max.max(a);
                } else {
                    inner_max = inner_max.max(a);
                }
            }
        }
    }
    // Outside the grid there is no occlusion, so the boundary must be 0 to meet it.
    assert_eq!(boundary_max, 0.0);
    assert!(
        inner_max > 0.3,
        "the contact occlusion must survive the rescale"
    );
    // Without the rescale the boundary holds the occlusion eq. 4 neglects, up to about ε.
    let raw = bake(
        cube(),
        &BakeSettings {
            rescale_border: false,
            ..settings
        },
        &|_, _| {},
    )
    .unwrap();
    let raw_max = raw.cells.iter().map(|c| c[0]).fold(0.0f32, f32::max);
    assert!(raw_max > 0.0);
}

#[test]
fn interior_cells_take_their_open_neighbours_values() {
    let settings = BakeSettings {
        resolution: 8,
        rays: 128,
        rescale_border: false,
        ..BakeSettings::paper()
    };
    let filled = bake(cube(), &settings, &|_, _| {}).unwrap();
    let raw = bake(
        cube(),
        &BakeSettings {
            fill_interior: false,
            ..settings
        },
        &|_, _| {},
    )
    .unwrap();
    let inside: Vec<usize> = (0..raw.cells.len())
        .filter(|&i| raw.cells[i][0] >= 1.0)
        .collect();
    assert!(!inside.is_empty(), "the cube should hold interior cells");
    assert!(inside.iter().any(|&i| filled.cells[i][0] < 1.0));
}

#[test]
fn bad_input_is_refused() {
    assert_eq!(
        bake(Vec::new(), &BakeSettings::default(), &|_, _| {}),
        Err(BakeError::NoTriangles)
    );
    for settings in [
        BakeSettings {
            resolution: 1,
            ..default()
        },
        BakeSettings {
            reach: FieldReach::Unlimited { epsilon: 0.0 },
            ..default()
        },
        BakeSettings {
            reach: FieldReach::Distance {
                reach: f32::NAN,
                near: 0.5,
            },
            ..default()
        },
        BakeSettings {
            rays: 0,
            ..default()
        },
        // Past the cap: `u32::MAX` rays would take the process down before a single cell.
        BakeSettings {
            rays: u32::MAX,
            ..default()
        },
        BakeSettings {
            rays: BakeSettings::MAX_RAYS + 1,
            ..default()
        },
    ] {
        assert!(matches!(
            bake(cube(), &settings, &|_, _| {}),
            Err(BakeError::BadSettings(_))
        ));
    }
}

#[test]
fn a_finite_reach_counts_only_near_hits_and_ends_the_grid_where_nothing_reaches() {
    let settings = BakeSettings {
        resolution: 16,
        rays: 512,
        reach: FieldReach::Distance {
            reach: 0.75,
            near: 0.3,
        },
        ..default()
    };
    let field = bake(cube(), &settings, &|_, _| {}).unwrap();
    assert_eq!((field.reach, field.near_reach), (0.75, 0.3));
    // The grid is the cube's bounds grown by the reach.
    assert!((field.half_extent - Vec3::splat(1.25)).abs().max_element() < 1e-5);
    let r = field.resolution;
    let cell = 2.0 * field.half_extent / r.as_vec3();
    let at = |i: usize| {
        let (x, y, z) = (
            i as u32 % r.x,
            (i as u32 / r.x) % r.y,
            i as u32 / (r.x * r.y),
        );
        field.center - field.half_extent + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * cell
    };
    for (i, c) in field.cells.iter().enumerate() {
        let p = at(i);
        // Distance from the cube's surface (outside) of this grid point.
        let outside = (p.abs() - Vec3::splat(0.5)).max(Vec3::ZERO).length();
        if outside >= 0.75 {
            assert_eq!(c[0], 0.0, "{p} lies beyond the reach");
        }
        let near = field.near_cells[i][0];
        assert!(near <= c[0] + 1e-6, "the near part is part of the whole");
        if outside >= 0.3 {
            assert_eq!(near, 0.0, "{p} lies beyond the near reach");
        }
        // The signed distance is the distance to the surface, negative inside.
        let [signed, ox, oy, oz] = field.distances[i];
        let mean = Vec3::new(ox, oy, oz).length();
        if p.abs().max_element() < 0.45 {
            assert!(signed < 0.0, "{p} is inside: {signed}");
        } else if outside > 0.05 && outside < 0.3 {
            // The nearest of 512 rays: a little long where the nearest point is an edge.
            assert!(
                signed >= outside - 0.01 && signed < 1.15 * outside + 0.01,
                "{p}: {signed} vs {outside}"
            );
        }
        if near > 0.0 {
            assert!(mean > 0.0 && mean < 0.3, "{mean}");
        }
    }
    // Right beside a face, half the sphere is blocked within reach.
    let beside = field
        .cells
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            let p = at(*i);
            (p.x - 0.55).abs() < 0.06 && p.y.abs() < 0.1 && p.z.abs() < 0.1
        })
        .map(|(_, c)| c[0])
        .next()
        .expect("a cell beside the +x face");
    assert!((0.35..0.5).contains(&beside), "{beside}");
}

#[test]
fn thin_axes_get_a_least_number_of_cells_and_the_rest_share_the_budget() {
    // A 20 m floor at R = 0.75 m: cubic cells would cross its 1.5 m height in 4 cells of 36 cm.
    let floor = grid_resolution(Vec3::new(10.75, 0.75, 10.75), 32);
    assert_eq!(floor.y, 12, "{floor}");
    assert!(
        floor.x == floor.z && (50..=52).contains(&floor.x),
        "{floor}"
    );
    assert!(floor.element_product() <= 32 * 32 * 32, "{floor}");
    // A 10 m wall 10 cm thick: only its thickness is raised; the rest keep their cubic cells.
    let wall = grid_resolution(Vec3::new(5.75, 2.25, 0.8), 32);
    assert_eq!(wall, UVec3::new(64, 25, 12));
    // A 10 m pole: both thin axes raised, the long one keeps its cells.
    let pole = grid_resolution(Vec3::new(0.8, 5.75, 0.8), 32);
    assert_eq!(pole, UVec3::new(12, 64, 12));
    // Objects of about equal sides keep cubic cells.
    assert_eq!(grid_resolution(Vec3::splat(1.0), 32), UVec3::splat(32));
    assert_eq!(
        grid_resolution(Vec3::new(2.35, 1.2, 1.25), 32),
        UVec3::new(49, 25, 26)
    );
    // Tiny budgets keep at least 2 cells an axis.
    assert_eq!(
        grid_resolution(Vec3::new(10.0, 0.1, 10.0), 2),
        UVec3::new(2, 2, 2)
    );
}

#[test]
fn baking_is_deterministic() {
    let settings = BakeSettings {
        resolution: 6,
        rays: 64,
        ..default()
    };
    assert_eq!(
        bake(cube(), &settings, &|_, _| {}),
        bake(cube(), &settings, &|_, _| {})
    );
}

/// Two facing 1 m × 1 m walls of one open mesh, 0.6 m apart: wall A in the plane x = 0 facing +x,
/// wall B in x = 0.6 facing −x.
fn channel() -> Vec<Triangle> {
    let quad = |x: f32, facing: f32| {
        let corner = |y: f32, z: f32| Vec3::new(x, y, z);
        let (a, b, c, d) = (
            corner(0.0, -0.5),
            corner(1.0, -0.5),
            corner(1.0, 0.5),
            corner(0.0, 0.5),
        );
        let tri = |v: [Vec3; 3]| Triangle {
            vertices: v,
            normals: None,
        };
        // Counter-clockwise seen from +x when `facing` > 0.
        if facing > 0.0 {
            [tri([a, b, c]), tri([a, c, d])]
        } else {
            [tri([a, c, b]), tri([a, d, c])]
        }
    };
    quad(0.0, 1.0).into_iter().chain(quad(0.6, -1.0)).collect()
}

/// Of cosine-weighted pseudo-random directions about `n` at `p` that meet nothing within `near`,
/// the share that meets a triangle within `reach`: every triangle tested, no BVH, no shared
/// direction set.
fn brute_force_beyond(triangles: &[Triangle], p: Vec3, n: Vec3, near: f32, reach: f32) -> f32 {
    let mut state = 777u32;
    let mut next = || {
        state = crate::geometry::hash::pcg_hash(state);
        state as f32 / u32::MAX as f32
    };
    let (t1, t2) = n.any_orthonormal_pair();
    let (mut open, mut beyond) = (0u32, 0u32);
    for _ in 0..4096 {
        let (r, phi) = (next().sqrt(), std::f32::consts::TAU * next());
        let d = t1 * r * phi.cos() + t2 * r * phi.sin() + n * (1.0 - r * r).max(0.0).sqrt();
        let t = triangles
            .iter()
            .filter_map(|t| {
                let [a, b, c] = t.vertices;
                let (e1, e2) = (b - a, c - a);
                let h = d.cross(e2);
                let det = e1.dot(h);
                let s = p - a;
                let (u, q) = (s.dot(h) / det, s.cross(e1));
                let v = d.dot(q) / det;
                let t = e2.dot(q) / det;
                (det.abs() > 1e-9 && u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 1e-4).then_some(t)
            })
            .fold(f32::INFINITY, f32::min);
        if t >= near {
            open += 1;
            beyond += u32::from(t < reach);
        }
    }
    beyond as f32 / open as f32
}

#[test]
fn the_own_surface_gets_its_share_beyond_the_near_reach_on_its_side_only() {
    use crate::reference::fields::occluder_occlusion;
    use crate::settings::FieldShading;
    let (reach, near) = (1.0, 0.3);
    let settings = BakeSettings {
        resolution: 24,
        rays: 512,
        reach: FieldReach::Distance { reach, near },
        ..default()
    };
    let field = bake(channel(), &settings, &|_, _| {}).unwrap();
    let nothing_held = |_: Vec3, _: f32| 0.0;
    let lookup = |p: Vec3, n: Vec3| {
        occluder_occlusion(
            &field,
            Affine3A::IDENTITY,
            p,
            n,
            FieldShading::Cone,
            near,
            &nothing_held,
        )
    };
    for p in [
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::new(0.0, 0.3, 0.2),
        Vec3::new(0.6, 0.6, -0.1),
    ] {
        let inward = if p.x < 0.3 { Vec3::X } else { Vec3::NEG_X };
        let truth = brute_force_beyond(&channel(), p, inward, near, reach);
        let [near_part, beyond] = lookup(p, inward);
        // The facing wall 0.6 m away lies wholly beyond the near reach: only the second part.
        assert!(near_part < 1e-4, "{p}: {near_part}");
        println!("{p}: own surface beyond the near reach {beyond}, brute force {truth}");
        assert!(
            truth > 0.25 && (beyond - truth).abs() < 0.015,
            "{p}: {beyond} against {truth}"
        );
        // The wall's other side sees nothing of the object, and does not read this side's share.
        let [near_part, beyond] = lookup(p, -inward);
        assert!(near_part < 1e-4, "{p}: {near_part}");
        assert!(beyond < 0.01, "{p}, outer side: {beyond}");
    }
    // A convex object blocks nothing of its own surface's hemispheres, and the points inside it
    // store nothing (from under a box's bottom face they would see its inside).
    let convex = bake(cube(), &settings, &|_, _| {}).unwrap();
    assert!(convex.own_surface.iter().all(|c| c[0] == 0.0));
    assert!(
        convex.own_surface.iter().any(|c| c[1..] != [0.0; 3]),
        "the points next to its faces store their side"
    );
    // Without a near reach below the reach (the near field reaches R), nothing is stored.
    let settings = BakeSettings {
        reach: FieldReach::Distance { reach, near: reach },
        ..settings
    };
    let field = bake(channel(), &settings, &|_, _| {}).unwrap();
    assert!(field.own_surface.iter().all(|c| *c == [0.0; 4]));
}

/// A surface that stands across the object next to it (a shelf touching a wall, a slab on a
/// floor) gets the field's full value there, as a ray tracer finds it; the object's own surface
/// at the same point fades, and the shelf once faded with it.
#[test]
fn a_surface_touching_the_object_across_it_keeps_the_full_value() {
    use crate::reference::fields::occluder_occlusion;
    use crate::settings::FieldShading;
    let wall: Vec<Triangle> = channel().into_iter().take(2).collect();
    let settings = BakeSettings {
        resolution: 24,
        rays: 512,
        reach: FieldReach::Distance {
            reach: 1.0,
            near: 0.3,
        },
        ..default()
    };
    let field = bake(wall.clone(), &settings, &|_, _| {}).unwrap();
    let lookup = |p: Vec3, n: Vec3| {
        occluder_occlusion(
            &field,
            Affine3A::IDENTITY,
            p,
            n,
            FieldShading::Cone,
            0.0,
            &|_, _| 0.0,
        )[1]
    };
    // A quarter of the fade's width off the wall, where the fade alone kept 16 %.
    let p = Vec3::new(0.25 * field.own_surface_fade(), 0.5, 0.1);
    let truth = brute_force_beyond(&wall, p, Vec3::Y, 0.0, 1.0);
    let shelf = lookup(p, Vec3::Y);
    println!("shelf against the wall: field {shelf}, brute force {truth}");
    assert!(
        truth > 0.2 && (shelf - truth).abs() < 0.05,
        "{shelf} against {truth}"
    );
    let own = lookup(p, Vec3::X);
    assert!(own < 0.2 * truth, "the wall's own surface reads {own}");
}

//! The occlusion a proxy set casts around its mesh against the occlusion the mesh itself casts:
//! how the sphere occluders' box fitting (`spheres::fit`) is checked against ray tracing.

use bevy::math::Affine3A;
use bevy::prelude::*;

use crate::geometry::bvh::Bvh;
use crate::geometry::triangles::{Triangle, triangle_bounds};
use crate::geometry::union::occluder_union;
use crate::reference::ground_truth::point_occlusion;
use crate::reference::spheres::proxy_occlusion;
use crate::spheres::OccluderSphere;

/// Cosine-weighted share of rays from `p` that meet `bvh` within `reach`.
fn traced(bvh: &Bvh, p: Vec3, n: Vec3, reach: f32) -> f32 {
    point_occlusion(bvh, p + n * 1e-4, n, reach, 4096)
}

/// Mean occlusion (proxies, mesh) over 96 receivers on a sphere around the mesh's bounds,
/// `distance` times their half diagonal from the centre, facing the centre, counted within
/// `reach`; the proxies join as `compose` joins them.
fn proxies_and_mesh(
    triangles: Vec<Triangle>,
    proxies: &[OccluderSphere],
    distance: f32,
    reach: f32,
) -> (f32, f32) {
    let (lo, hi) = triangle_bounds(&triangles);
    let (centre, size) = ((lo + hi) / 2.0, (hi - lo).length() / 2.0);
    let bvh = Bvh::new(triangles);
    let (mut ours, mut theirs) = (0.0, 0.0);
    let count = 96;
    for i in 0..count {
        let a = i as f32 * 2.399_963;
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / count as f32;
        let dir = Vec3::new(
            (1.0 - z * z).sqrt() * a.cos(),
            z,
            (1.0 - z * z).sqrt() * a.sin(),
        );
        let p = centre + dir * size * distance;
        let n = -dir;
        let mut open = 1.0;
        for q in proxies {
            open *= 1.0 - proxy_occlusion(q, p, n, reach).clamp(0.0, 1.0);
        }
        // A rigid mesh's proxies: no skinned proxy, so the union is their product.
        ours += occluder_union([0.0, 1.0 - open], 1.0, 0.0)[1];
        theirs += traced(&bvh, p, n, if reach > 0.0 { reach } else { f32::INFINITY });
    }
    (ours / count as f32, theirs / count as f32)
}

/// The proxies of a fit, placed where the mesh was fitted.
fn rest_proxies(fitted: &crate::spheres::lloyd::ClusteredMesh) -> Vec<OccluderSphere> {
    fitted
        .spheres
        .iter()
        .map(|s| OccluderSphere {
            center: s.center,
            radius: s.radius,
            axes: s.axes,
            shape: s.shape,
        })
        .collect()
}

/// The triangles of `mesh` placed by `placed`.
fn triangles(mesh: &Mesh, placed: Affine3A) -> Vec<Triangle> {
    let mut scene = crate::geometry::triangles::TriangleScene::default();
    scene.add_mesh(mesh, placed);
    scene.triangles
}

#[cfg(test)]
mod tests {
    use bevy::math::Affine3A;
    use bevy::prelude::*;

    use super::*;
    use crate::geometry::rest_mesh::RestMesh;
    use crate::spheres::fit::fit_boxes;

    /// The occlusion a box, a wall, a thin rod and a ball cast through their proxies (the ball's
    /// a ball), against the occlusion the meshes themselves cast, on receivers 1.5 and 3
    /// half-diagonals from their centre (within 2 m and unlimited). Measured: box and wall within
    /// 1.5 %, the ball 3 % over (9 % with its box, which covers more than a round part seen
    /// obliquely), the 3 cm rod about 20 % over.
    #[test]
    fn proxies_cast_what_their_meshes_cast() {
        for (name, mesh, bound) in [
            ("box", Mesh::from(Cuboid::new(1.0, 0.6, 0.8)), 0.03),
            ("wall", Mesh::from(Cuboid::new(4.0, 2.5, 0.1)), 0.03),
            (
                "rod",
                Mesh::from(Cylinder::new(0.03, 1.5).mesh().resolution(16)),
                0.25,
            ),
            ("ball", Sphere::new(0.5).mesh().uv(32, 16), 0.05),
        ] {
            let rest = RestMesh::from_mesh(&mesh).unwrap();
            let fitted = fit_boxes(&rest, 16);
            assert_eq!(fitted.spheres.len(), 1, "{name} is one proxy");
            for (distance, reach) in [(1.5, 2.0), (3.0, 0.0)] {
                let (ours, theirs) = proxies_and_mesh(
                    triangles(&mesh, Affine3A::IDENTITY),
                    &rest_proxies(&fitted),
                    distance,
                    reach,
                );
                println!(
                    "{name}, {distance} half-diagonals, reach {reach}: proxies {ours:.4}, mesh \
                     {theirs:.4}"
                );
                assert!(theirs > 1e-3, "{name}: the receivers should see the mesh");
                assert!(
                    (ours / theirs - 1.0).abs() < bound,
                    "{name}: proxies {ours}, mesh {theirs}"
                );
            }
        }
    }
}

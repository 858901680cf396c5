//! Moving the rest-pose spheres with the deformed vertices, every frame (Shanmugam & Arikan 2007,
//! §5.3: "we make use of the correspondence between the spheres and the underlying geometry to
//! trivially recalculate the positions/radii of the spheres").
//!
//! For each cluster the deformed vertices give the new area-weighted centroid and spread; the
//! sphere keeps its rest-pose offset from the centroid (turned by the cluster's blended joint
//! matrix) and its rest-pose ratio of radius to spread. A cluster bound to one joint therefore
//! moves exactly with that joint, and one that stretches grows with it. The cost is one skinning
//! per vertex plus a few additions: linear in the vertex count.

use bevy::math::{Affine3A, Mat3, Mat3A, Vec3, Vec3A};

use super::OccluderSphere;
use super::lloyd::{ClusteredMesh, RestSphere, axis_spreads};
use crate::geometry::deform::{Deformer, Pose};
use crate::geometry::rest_mesh::RestMesh;

/// Writes the world-space spheres of `clustered` in `pose` into `out` (cleared first). Spheres
/// that come out non-finite (a NaN joint, say) are left out; the return value counts them.
pub fn refit(
    mesh: &RestMesh,
    clustered: &ClusteredMesh,
    pose: &Pose,
    out: &mut Vec<OccluderSphere>,
) -> usize {
    out.clear();
    let skin = mesh.skin.as_deref().filter(|_| !pose.joints.is_empty());
    let mut dropped = 0;
    if Deformer::is_rigid(mesh, pose) {
        // A rigid mesh: its spheres move with it and no vertex needs touching.
        let scale = max_axis_scale(pose.world_from_mesh.matrix3);
        let linear = Mat3::from(pose.world_from_mesh.matrix3);
        for s in &clustered.spheres {
            push_finite(
                out,
                &mut dropped,
                OccluderSphere {
                    center: pose.world_from_mesh.transform_point3(s.center),
                    radius: s.radius * scale,
                    axes: linear * s.axes,
                    shape: s.shape,
                },
            );
        }
        return dropped;
    }

    let deformer = Deformer::new(mesh, pose);
    // No bone carries an unskinned box: it takes the shape of its morphed vertices, which are
    // walked twice (centroid, then spread per axis) and so deformed once, into `deformed`.
    let morphed_boxes = skin.is_none() && clustered.shape == super::ProxyShape::Boxes;
    let mut deformed: Vec<Vec3A> = Vec::new();

    for (i, rest) in clustered.spheres.iter().enumerate() {
        let (start, end) = clustered.ranges[i];
        let members = &clustered.order[start as usize..end as usize];
        if morphed_boxes {
            deformed.clear();
            deformed.extend(members.iter().map(|&v| deformer.point(v as usize)));
        }
        let at = |j: usize| {
            if morphed_boxes {
                deformed[j]
            } else {
                deformer.point(members[j] as usize)
            }
        };
        // Sums relative to the first vertex keep the spread accurate far from the origin.
        let origin = at(0);
        let (mut area, mut sum, mut sum2) = (0.0f32, Vec3A::ZERO, 0.0f32);
        for (j, &v) in members.iter().enumerate() {
            let d = at(j) - origin;
            let a = mesh.areas[v as usize];
            area += a;
            sum += d * a;
            sum2 += d.length_squared() * a;
        }
        let mean = sum / area;
        let spread = (sum2 / area - mean.length_squared()).max(0.0).sqrt();
        let centroid = origin + mean;
        let linear = match skin {
            Some(_) => {
                let mut m = Mat3A::ZERO;
                for &(joint, w) in &clustered.sphere_joints[i] {
                    let joint = pose
                        .joints
                        .get(joint as usize)
                        .unwrap_or(&Affine3A::IDENTITY);
                    m += joint.matrix3 * w;
                }
                m
            }
            None => pose.world_from_mesh.matrix3,
        };
        let mut center = Vec3::from(centroid + linear * Vec3A::from(rest.center - rest.centroid));
        if skin.is_some() && clustered.shape == super::ProxyShape::Boxes {
            // Skinned like a vertex with the box's joint weights, so a box on one bone moves
            // exactly with it.
            let mut skinned = Vec3A::ZERO;
            for &(joint, w) in &clustered.sphere_joints[i] {
                let joint = pose
                    .joints
                    .get(joint as usize)
                    .unwrap_or(&Affine3A::IDENTITY);
                skinned += joint.transform_point3a(Vec3A::from(rest.center)) * w;
            }
            center = Vec3::from(skinned);
        }
        let ratio = if rest.spread > 1e-4 * rest.radius {
            spread / rest.spread
        } else {
            // Coinciding vertices carry no size; the joints' scale does.
            max_axis_scale(linear)
        };
        // A sphere's size follows the spread of its vertices (S&A §5.3). A box follows its
        // joints' blended matrix: turned, stretched and scaled with them, so one on a single
        // bone moves exactly with it (the spread of its vertices would grow as neighbouring parts
        // bend away).
        let mut axes = match clustered.shape {
            super::ProxyShape::Spheres => rest.axes * ratio,
            super::ProxyShape::Boxes => Mat3::from(linear) * rest.axes,
        };
        if morphed_boxes {
            // Morph targets reshape an unskinned box, and it takes the shape of its vertices
            // along each of its axes. Kept at its rest size, the box of AnimatedMorphCube,
            // flattened to two thirds of its depth by a target, stood out of the cube's front
            // face and darkened the floor there as if it lay inside the cube.
            let points = members.iter().zip(&deformed);
            let points = points.map(|(&v, &p)| (mesh.areas[v as usize], p));
            let stretch = box_stretch(points, rest, linear);
            let offset = rest.center - rest.centroid;
            for (k, factor) in stretch.into_iter().enumerate() {
                let along = rest.axes.col(k).normalize_or_zero();
                *axes.col_mut(k) *= factor;
                center += Mat3::from(linear) * (along * along.dot(offset) * (factor - 1.0));
            }
        }
        let radius = match (clustered.shape, rest.shape) {
            (super::ProxyShape::Spheres, _) => rest.radius * ratio,
            (super::ProxyShape::Boxes, super::ProxyShape::Boxes) => (axes.x_axis.length_squared()
                + axes.y_axis.length_squared()
                + axes.z_axis.length_squared())
            .sqrt(),
            (super::ProxyShape::Boxes, super::ProxyShape::Spheres) => {
                // A box fit's ball, moved (and stretched by a morph) as its boxes are: the ball
                // of the same volume.
                let lengths = Vec3::new(
                    axes.x_axis.length(),
                    axes.y_axis.length(),
                    axes.z_axis.length(),
                );
                let r = lengths.element_product().cbrt();
                axes = Mat3::from_diagonal(Vec3::splat(r));
                r
            }
        };
        push_finite(
            out,
            &mut dropped,
            OccluderSphere {
                center,
                radius,
                axes,
                shape: rest.shape,
            },
        );
    }
    dropped
}

/// How much the deformed vertices of a box, `points` (area m², world position), stretch along
/// each of its axes against its rest vertices (`rest`, mesh space) carried rigidly by `linear`:
/// the ratio of their area-weighted spreads along the axis. An axis along which the rest
/// vertices have no spread (a floor's thickness) keeps its size.
fn box_stretch(
    points: impl Iterator<Item = (f32, Vec3A)>,
    rest: &RestSphere,
    linear: Mat3A,
) -> [f32; 3] {
    // Each axis carried by `linear` (world space), as a unit vector and the length `linear`
    // gives it.
    let turned = [0, 1, 2].map(|k| linear * Vec3A::from(rest.axes.col(k).normalize_or_zero()));
    let scale = turned.map(|t| t.length());
    let turned = [0, 1, 2].map(|k| turned[k] / scale[k].max(f32::MIN_POSITIVE));
    let deformed = axis_spreads(points, turned);
    [0, 1, 2].map(|k| {
        let rest_spread = rest.axis_spreads[k] * scale[k];
        let size = scale[k] * rest.axes.col(k).length();
        if rest_spread > 1e-3 * size {
            deformed[k] / rest_spread
        } else {
            1.0
        }
    })
}

fn push_finite(out: &mut Vec<OccluderSphere>, dropped: &mut usize, proxy: OccluderSphere) {
    if proxy.center.is_finite()
        && proxy.radius.is_finite()
        && proxy.radius > 0.0
        && proxy.axes.is_finite()
    {
        out.push(proxy);
    } else {
        *dropped += 1;
    }
}

/// The largest factor by which `m` stretches any direction's axis: a radius that stays
/// conservative under non-uniform scale.
fn max_axis_scale(m: Mat3A) -> f32 {
    m.x_axis
        .length()
        .max(m.y_axis.length())
        .max(m.z_axis.length())
}

#[cfg(test)]
mod tests {
    use bevy::math::{Quat, Vec3, Vec3Swizzles};

    use super::*;
    use crate::geometry::rest_mesh::VertexSkin;
    use crate::spheres::lloyd::cluster;

    /// A square column from y = 0 to y = 2, rings every 0.1 m; vertices below y = 1 follow
    /// joint 0, the others joint 1.
    fn two_bone_column() -> RestMesh {
        let mut positions = Vec::new();
        let mut skin = Vec::new();
        let corners = [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)];
        let rings = 21;
        for r in 0..rings {
            let y = r as f32 * 0.1;
            for (x, z) in corners {
                positions.push(Vec3::new(x, y, z));
                let joint = if y < 1.0 { 0 } else { 1 };
                skin.push(VertexSkin {
                    joints: [joint, 0, 0, 0],
                    weights: [1.0, 0.0, 0.0, 0.0],
                });
            }
        }
        let mut indices = Vec::new();
        for r in 0..rings - 1 {
            for k in 0..4 {
                let (a, b) = (r * 4 + k, r * 4 + (k + 1) % 4);
                let (c, d) = (a + 4, b + 4);
                indices.extend([a, b, d, a, d, c]);
            }
        }
        RestMesh::new(positions, None, &indices, Some(skin), Vec::new(), 0).unwrap()
    }

    fn skin_point(mesh: &RestMesh, joints: &[Affine3A], v: usize) -> Vec3 {
        let s = mesh.skin.as_ref().unwrap()[v];
        (0..4)
            .map(|k| {
                joints[s.joints[k] as usize].transform_point3(mesh.positions[v]) * s.weights[k]
            })
            .sum()
    }

    #[test]
    fn spheres_of_a_limb_follow_its_bone() {
        let mesh = two_bone_column();
        let clustered = cluster(&mesh, 6);
        // The upper bone bends 60° about the knee at y = 1 and the whole body moves.
        let body = Affine3A::from_translation(Vec3::new(3.0, 0.0, -2.0));
        let knee = Vec3::Y;
        let bend = Affine3A::from_translation(knee)
            * Affine3A::from_quat(Quat::from_rotation_z(1.0))
            * Affine3A::from_translation(-knee);
        let joints = [body, body * bend];
        let pose = Pose {
            world_from_mesh: Affine3A::IDENTITY,
            joints: &joints,
            morph_weights: &[],
        };
        let mut spheres = Vec::new();
        assert_eq!(refit(&mesh, &clustered, &pose, &mut spheres), 0);
        assert_eq!(spheres.len(), clustered.spheres.len());
        let mut checked = 0;
        for (i, (moved, rest)) in spheres.iter().zip(&clustered.spheres).enumerate() {
            let (start, end) = clustered.ranges[i];
            let members = &clustered.order[start as usize..end as usize];
            let joints_used: Vec<u16> = members
                .iter()
                .map(|&v| mesh.skin.as_ref().unwrap()[v as usize].joints[0])
                .collect();
            // The centroid of the CPU-skinned vertices of the cluster.
            let area: f32 = members.iter().map(|&v| mesh.areas[v as usize]).sum();
            let centroid: Vec3 = members
                .iter()
                .map(|&v| skin_point(&mesh, &joints, v as usize) * mesh.areas[v as usize])
                .sum::<Vec3>()
                / area;
            if joints_used.iter().all(|j| *j == joints_used[0]) {
                let bone = joints[joints_used[0] as usize];
                let expected = bone.transform_point3(rest.center);
                assert!(
                    moved.center.distance(expected) < 1e-4,
                    "sphere {i}: {} vs {expected}",
                    moved.center
                );
                assert!((moved.radius - rest.radius).abs() < 1e-4);
                // The centre keeps its rest-pose offset from the skinned centroid.
                let offset = bone.transform_vector3(rest.center - rest.centroid);
                assert!((moved.center - centroid - offset).length() < 1e-4);
                checked += 1;
            }
        }
        assert!(checked >= 4, "only {checked} clusters lie on one bone");
    }

    #[test]
    fn a_stretched_cluster_grows() {
        let mesh = two_bone_column();
        let clustered = cluster(&mesh, 2);
        let stretch = Affine3A::from_scale(Vec3::splat(2.0));
        let joints = [stretch, stretch];
        let pose = Pose {
            world_from_mesh: Affine3A::IDENTITY,
            joints: &joints,
            morph_weights: &[],
        };
        let mut spheres = Vec::new();
        refit(&mesh, &clustered, &pose, &mut spheres);
        for (moved, rest) in spheres.iter().zip(&clustered.spheres) {
            assert!((moved.radius - 2.0 * rest.radius).abs() < 1e-4);
            assert!(moved.center.distance(2.0 * rest.center) < 1e-4);
        }
    }

    #[test]
    fn morph_targets_move_the_spheres() {
        let base = two_bone_column();
        let count = base.positions.len();
        // One target lifts every vertex by 0.5 m.
        let mesh = RestMesh::new(
            base.positions.clone(),
            None,
            &base
                .triangles
                .iter()
                .flatten()
                .map(|&i| i as usize)
                .collect::<Vec<_>>(),
            None,
            vec![Vec3::new(0.0, 0.5, 0.0); count],
            1,
        )
        .unwrap();
        let clustered = cluster(&mesh, 3);
        let mut spheres = Vec::new();
        let pose = Pose {
            world_from_mesh: Affine3A::from_translation(Vec3::X),
            joints: &[],
            morph_weights: &[0.5],
        };
        refit(&mesh, &clustered, &pose, &mut spheres);
        for (moved, rest) in spheres.iter().zip(&clustered.spheres) {
            let expected = rest.center + Vec3::new(1.0, 0.25, 0.0);
            assert!(moved.center.distance(expected) < 1e-4);
        }
    }

    /// A unit cube, turned and moved, whose one morph target lifts its lower face by 0.5 m: at
    /// full weight the box proxy is the cube's upper half (half its height, its centre 0.25 m
    /// up); at rest size it stood out below the flattened cube.
    #[test]
    fn a_morph_target_that_flattens_a_box_flattens_its_proxy() {
        use bevy::prelude::{Cuboid, Mesh};
        let cube = RestMesh::from_mesh(&Mesh::from(Cuboid::new(1.0, 1.0, 1.0))).unwrap();
        let lift: Vec<Vec3> = cube
            .positions
            .iter()
            .map(|p| Vec3::new(0.0, if p.y < 0.0 { 0.5 } else { 0.0 }, 0.0))
            .collect();
        let indices: Vec<usize> = cube
            .triangles
            .iter()
            .flatten()
            .map(|&i| i as usize)
            .collect();
        let mesh = RestMesh::new(cube.positions.clone(), None, &indices, None, lift, 1).unwrap();
        let clustered = crate::spheres::fit::fit_boxes(&mesh, 8);
        assert_eq!(clustered.spheres.len(), 1);
        let turn = Quat::from_rotation_z(0.4);
        let world_from_mesh = Affine3A::from_rotation_translation(turn, Vec3::new(2.0, 1.0, 0.0));
        for (weight, height, rise) in [(0.0, 1.0, 0.0), (0.5, 0.75, 0.125), (1.0, 0.5, 0.25)] {
            let weights = [weight];
            let pose = Pose {
                world_from_mesh,
                joints: &[],
                morph_weights: &weights,
            };
            let mut boxes = Vec::new();
            refit(&mesh, &clustered, &pose, &mut boxes);
            let proxy = boxes[0];
            // The box's extent along the mesh's turned y axis, whichever of its axes that is.
            let up = turn * Vec3::Y;
            let extent: f32 = (0..3).map(|k| proxy.axes.col(k).dot(up).abs()).sum::<f32>() * 2.0;
            let centre = turn.inverse() * (proxy.center - Vec3::new(2.0, 1.0, 0.0));
            let fitted = clustered.spheres[0].axes.y_axis.length() * 2.0;
            assert!(
                (extent - height * fitted).abs() < 0.02,
                "weight {weight}: height {extent}, expected {}",
                height * fitted
            );
            assert!(
                (centre.y - rise).abs() < 0.02 && centre.xz().length() < 0.02,
                "weight {weight}: centre {centre}"
            );
            for k in 0..3 {
                let across = proxy.axes.col(k) - up * proxy.axes.col(k).dot(up);
                let rest = clustered.spheres[0].axes.col(k);
                let rest_across = rest - Vec3::Y * rest.y;
                assert!((across.length() - rest_across.length()).abs() < 0.02);
            }
        }
    }

    #[test]
    fn nan_joints_drop_spheres_instead_of_spreading_nan() {
        let mesh = two_bone_column();
        let clustered = cluster(&mesh, 4);
        let mut broken = Affine3A::IDENTITY;
        broken.translation.x = f32::NAN;
        let joints = [Affine3A::IDENTITY, broken];
        let pose = Pose {
            world_from_mesh: Affine3A::IDENTITY,
            joints: &joints,
            morph_weights: &[],
        };
        let mut spheres = Vec::new();
        let dropped = refit(&mesh, &clustered, &pose, &mut spheres);
        assert!(dropped > 0);
        assert!(!spheres.is_empty());
        assert!(spheres.iter().all(|s| s.center.is_finite()));
    }
}

//! The back-face layer deforms like the front layer: a column bent by a two-joint skin, or by a
//! morph target, has the same silhouette in both ND-buffer layers (Bevy's prepass deforms the
//! front layer; our pass must deform the back one the same way).

use bevy::asset::RenderAssetUsages;
use bevy::camera::visibility::NoFrustumCulling;
use bevy::mesh::morph::{MeshMorphWeights, MorphAttributes};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;

use crate::harness::{Frame, Gpu, HEIGHT, SceneSpec, WIDTH, plain_ao};

pub(crate) const HALF: f32 = 0.15;
pub(crate) const LENGTH: f32 = 1.2;
const RINGS: usize = 12;

/// A square column along +Y; vertices above half its length belong to the second joint.
pub(crate) fn column() -> Mesh {
    let (mut positions, mut normals, mut joints, mut weights, mut indices) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut vertex = |p: Vec3, n: Vec3, positions: &mut Vec<[f32; 3]>| {
        let joint = u16::from(p.y > LENGTH / 2.0 + 1e-4);
        positions.push(p.to_array());
        normals.push(n.to_array());
        joints.push([joint, 0, 0, 0]);
        weights.push([1.0f32, 0.0, 0.0, 0.0]);
        positions.len() as u32 - 1
    };
    for n in [Vec3::X, Vec3::Z, -Vec3::X, -Vec3::Z] {
        let t = Vec3::Y.cross(n);
        let first = positions.len() as u32;
        for ring in 0..=RINGS {
            let y = LENGTH * ring as f32 / RINGS as f32;
            for a in [-1.0, 1.0] {
                vertex(n * HALF + t * (a * HALF) + Vec3::Y * y, n, &mut positions);
            }
        }
        for ring in 0..RINGS as u32 {
            let v = first + ring * 2;
            indices.extend([v, v + 1, v + 3, v, v + 3, v + 2]);
        }
    }
    for (y, n) in [(LENGTH, Vec3::Y), (0.0, -Vec3::Y)] {
        let corners = [(-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0)]
            .map(|(x, z)| vertex(Vec3::new(x * HALF, y, z * HALF), n, &mut positions));
        let [a, b, c, d] = if n.y > 0.0 {
            corners
        } else {
            [corners[3], corners[2], corners[1], corners[0]]
        };
        indices.extend([a, b, c, a, c, d]);
    }
    Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
    .with_inserted_attribute(
        Mesh::ATTRIBUTE_JOINT_INDEX,
        VertexAttributeValues::Uint16x4(joints),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT, weights)
    .with_inserted_indices(Indices::U32(indices))
}

/// The inverse bind poses of the column's two joints: the root, and the elbow halfway up.
pub(crate) fn column_bindposes(world: &mut World) -> Handle<SkinnedMeshInverseBindposes> {
    world
        .resource_mut::<Assets<SkinnedMeshInverseBindposes>>()
        .add(vec![
            Mat4::IDENTITY,
            Mat4::from_translation(-Vec3::Y * (LENGTH / 2.0)),
        ])
}

fn camera() -> Transform {
    Transform::from_xyz(0.0, 0.7, 2.2).looking_at(Vec3::new(0.2, 0.65, 0.0), Vec3::Y)
}

/// Renders the column `spawn` adds under both ways the back layer is drawn, with normals (the
/// near field) and its depth alone, with a vertex stage of its own (the ray march, the default's
/// technique), and checks each frame with `assert_same_bent_silhouette`.
fn under_both_back_layer_draws(what: &str, spawn: impl Fn(&mut World)) {
    for technique in [AoTechnique::NearField, AoTechnique::RayMarch] {
        let mut gpu = Gpu::new(
            &SceneSpec::new(camera()),
            plain_ao().with_technique(technique),
        );
        spawn(gpu.app.world_mut());
        let frame = gpu.frame(6);
        assert_same_bent_silhouette(&frame, &format!("{what} ({technique:?})"));
    }
}

#[test]
fn back_layer_follows_the_skin() {
    under_both_back_layer_draws("skinned", spawn_skinned_column);
}

fn spawn_skinned_column(world: &mut World) {
    let bindposes = column_bindposes(world);
    let mesh = world.resource_mut::<Assets<Mesh>>().add(column());
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    let root = world.spawn(Transform::IDENTITY).id();
    let elbow = world
        .spawn((
            Transform::from_xyz(0.0, LENGTH / 2.0, 0.0).with_rotation(Quat::from_rotation_z(-0.8)),
            ChildOf(root),
        ))
        .id();
    world.spawn((
        Mesh3d(mesh),
        MeshMaterial3d(material),
        SkinnedMesh {
            inverse_bindposes: bindposes,
            joints: vec![root, elbow],
        },
        NoFrustumCulling,
        Transform::IDENTITY,
    ));
}

#[test]
fn back_layer_follows_morph_targets() {
    under_both_back_layer_draws("morphed", spawn_morphed_column);
}

fn spawn_morphed_column(world: &mut World) {
    let mut mesh = column();
    mesh.remove_attribute(Mesh::ATTRIBUTE_JOINT_INDEX);
    mesh.remove_attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT);
    let Some(VertexAttributeValues::Float32x3(positions)) =
        mesh.attribute(Mesh::ATTRIBUTE_POSITION)
    else {
        unreachable!()
    };
    // One target that shears the upper half to +x.
    let target: Vec<MorphAttributes> = positions
        .iter()
        .map(|p| {
            let lean = (p[1] - LENGTH / 2.0).max(0.0) * 0.8;
            MorphAttributes::new(Vec3::X * lean, Vec3::ZERO, Vec3::ZERO)
        })
        .collect();
    mesh.set_morph_targets(target);
    let mesh = world.resource_mut::<Assets<Mesh>>().add(mesh);
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    world.spawn((
        Mesh3d(mesh),
        MeshMaterial3d(material),
        MeshMorphWeights::Value { weights: vec![1.0] },
        NoFrustumCulling,
        Transform::IDENTITY,
    ));
}

fn assert_same_bent_silhouette(frame: &Frame, what: &str) {
    let front: Vec<bool> = frame.nd.front.iter().map(|t| t.depth > 0.0).collect();
    let back: Vec<bool> = frame.nd.back.iter().map(|t| t.depth > 0.0).collect();
    let count = front.iter().filter(|f| **f).count();
    let differ = front.iter().zip(&back).filter(|(f, b)| f != b).count();
    println!("{what} column: {count} front pixels, {differ} differ in the back layer");
    assert!(
        count > 800,
        "the column should fill part of the image ({count} pixels)"
    );
    assert!(
        differ * 50 < count,
        "silhouettes of the two layers differ in {differ} pixels"
    );

    // The bend is really there: the upper rows of the silhouette lie to the right of the lower.
    let centre_of_rows = |rows: std::ops::Range<u32>| {
        let (mut sum, mut n) = (0.0f32, 0.0f32);
        for y in rows {
            for x in 0..WIDTH {
                if front[(y * WIDTH + x) as usize] {
                    sum += x as f32;
                    n += 1.0;
                }
            }
        }
        sum / n.max(1.0)
    };
    let top = centre_of_rows(0..HEIGHT / 3);
    let bottom = centre_of_rows(2 * HEIGHT / 3..HEIGHT);
    assert!(
        top - bottom > 8.0,
        "the {what} column should bend right: top {top}, bottom {bottom}"
    );
    for (f, b) in frame.nd.front.iter().zip(&frame.nd.back) {
        assert!(
            b.depth <= f.depth + 1e-6,
            "a back face in front of the front layer"
        );
    }
}

/// Proxies refit every frame follow the skin: bending the elbow further turns the proxies of the
/// upper half about the elbow by the same angle, as a CPU skinning of those vertices does, and
/// leaves the lower half where it was. The paper's spheres (eight Lloyd clusters) and the default
/// boxes (one per bone of this column, turned with it).
#[test]
fn occluder_spheres_follow_the_skin() {
    for (shape, count) in [(ProxyShape::Spheres, 8), (ProxyShape::Boxes, 2)] {
        let mut gpu = Gpu::new(&SceneSpec::new(camera()), plain_ao());
        let world = gpu.app.world_mut();
        let bindposes = column_bindposes(world);
        let mesh = world.resource_mut::<Assets<Mesh>>().add(column());
        let root = world.spawn(Transform::IDENTITY).id();
        let elbow = world
            .spawn((
                Transform::from_xyz(0.0, LENGTH / 2.0, 0.0)
                    .with_rotation(Quat::from_rotation_z(-0.3)),
                ChildOf(root),
            ))
            .id();
        let column = world
            .spawn((
                Mesh3d(mesh),
                SkinnedMesh {
                    inverse_bindposes: bindposes,
                    joints: vec![root, elbow],
                },
                SphereOccluder {
                    count: 8,
                    shape,
                    ..default()
                },
                Transform::IDENTITY,
            ))
            .id();
        gpu.update(2);
        let proxies = |gpu: &mut Gpu| {
            gpu.app
                .world()
                .get::<OccluderSpheres>(column)
                .expect("the plugin adds OccluderSpheres")
                .spheres
                .clone()
        };
        let before = proxies(&mut gpu);
        gpu.app
            .world_mut()
            .get_mut::<Transform>(elbow)
            .unwrap()
            .rotation = Quat::from_rotation_z(-1.0);
        gpu.update(1);
        let after = proxies(&mut gpu);
        assert_eq!(before.len(), count, "{shape:?}");
        assert_eq!(after.len(), count, "{shape:?}");

        let knee = Vec3::Y * (LENGTH / 2.0);
        let turn = Quat::from_rotation_z(-0.7);
        let (mut upper, mut lower) = (0, 0);
        for (b, a) in before.iter().zip(&after) {
            // Which bone a proxy belongs to, from where it sat before the bend; a sphere's
            // cluster is about 0.2 m long, so those near the elbow may hold vertices of both and
            // are left out.
            let on_upper_bone = (Quat::from_rotation_z(0.3) * (b.center - knee)).y > 0.15;
            let (expected, axes) = if on_upper_bone {
                upper += 1;
                (
                    knee + turn * (b.center - knee),
                    Mat3::from_quat(turn) * b.axes,
                )
            } else if b.center.y < LENGTH / 2.0 - 0.15 {
                lower += 1;
                (b.center, b.axes)
            } else {
                continue;
            };
            assert!(
                a.center.distance(expected) < 1e-3,
                "{shape:?}: proxy at {} moved to {}, expected {expected}",
                b.center,
                a.center
            );
            assert!(
                (a.radius - b.radius).abs() < 1e-4,
                "{shape:?}: rigid parts keep their size"
            );
            if shape == ProxyShape::Boxes {
                assert!(
                    (a.axes - axes)
                        .abs()
                        .to_cols_array()
                        .iter()
                        .all(|d| *d < 1e-3),
                    "a box turns with its bone"
                );
            }
        }
        let least = if shape == ProxyShape::Boxes { 1 } else { 2 };
        assert!(
            upper >= least && lower >= least,
            "{shape:?}: {upper} upper, {lower} lower proxies"
        );
    }
}

/// A `SkinnedMesh` on a mesh without joint attributes, and a skin with a NaN joint: a warning
/// each, spheres that follow the transform or leave out what is not finite, and no panic.
///
/// Bevy 0.19.1's own prepass and main pass reject a *visible* `SkinnedMesh` whose mesh has no
/// joint attributes (a bind group layout mismatch that stops the app), so that mesh stands out of
/// view here; its spheres are still computed, as for any off-screen occluder.
#[test]
fn bad_skins_fall_back() {
    let mut gpu = Gpu::new(&SceneSpec::new(camera()), plain_ao());
    let world = gpu.app.world_mut();
    let bindposes = column_bindposes(world);
    let mut unskinned = column();
    unskinned.remove_attribute(Mesh::ATTRIBUTE_JOINT_INDEX);
    unskinned.remove_attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT);
    let unskinned = world.resource_mut::<Assets<Mesh>>().add(unskinned);
    let skinned = world.resource_mut::<Assets<Mesh>>().add(column());
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    let root = world.spawn(Transform::IDENTITY).id();
    let mut broken = Transform::from_xyz(0.0, LENGTH / 2.0, 0.0);
    broken.translation.y = f32::NAN;
    let elbow = world.spawn((broken, ChildOf(root))).id();
    // The paper's spheres: six clusters of the column, some of them on the broken joint.
    let occluder = SphereOccluder {
        count: 6,
        shape: ProxyShape::Spheres,
        ..default()
    };
    let without_skin_data = world
        .spawn((
            Mesh3d(unskinned),
            MeshMaterial3d(material.clone()),
            SkinnedMesh {
                inverse_bindposes: bindposes.clone(),
                joints: vec![root, elbow],
            },
            occluder,
            Transform::from_xyz(30.0, 0.0, 0.0),
        ))
        .id();
    let nan_joint = world
        .spawn((
            Mesh3d(skinned),
            MeshMaterial3d(material),
            SkinnedMesh {
                inverse_bindposes: bindposes,
                joints: vec![root, elbow],
            },
            occluder,
            Transform::IDENTITY,
        ))
        .id();
    let frame = gpu.frame(4);
    let world = gpu.app.world();
    let spheres = |entity| {
        world
            .get::<OccluderSpheres>(entity)
            .expect("the plugin adds OccluderSpheres")
            .spheres
            .clone()
    };
    let plain = spheres(without_skin_data);
    let partial = spheres(nan_joint);
    println!(
        "NaN joint: {} of 6 spheres kept; no skin data: {} spheres",
        partial.len(),
        plain.len()
    );
    assert_eq!(
        plain.len(),
        6,
        "without skin data the spheres follow the transform"
    );
    assert!(plain.iter().all(|s| (s.center.x - 30.0).abs() < HALF));
    assert!(partial.len() < 6 && !partial.is_empty());
    assert!(
        partial
            .iter()
            .all(|s| s.center.is_finite() && s.radius.is_finite())
    );
    assert!(frame.visibility.iter().all(|v| v.is_finite()));
}

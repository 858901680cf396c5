//! A skinned, animated walker written as binary glTF by the project's own code: tapered tubes
//! around an eleven-joint skeleton, with a one-second walk cycle. Deterministic output.
#![allow(dead_code)]

use bevy::math::{Quat, Vec3};
use serde_json::json;

use crate::gltf_scene::GlbBuilder;

/// One bone: its joint (head) position in the rest pose, where its tube ends, its parent.
struct Bone {
    name: &'static str,
    parent: Option<usize>,
    head: Vec3,
    tail: Vec3,
    /// Tube radius, metres; 0 draws no tube.
    radius: f32,
}

fn skeleton() -> Vec<Bone> {
    let bone = |name, parent, head: [f32; 3], tail: [f32; 3], radius| Bone {
        name,
        parent,
        head: Vec3::from(head),
        tail: Vec3::from(tail),
        radius,
    };
    vec![
        bone("hips", None, [0.0, 0.95, 0.0], [0.0, 0.95, 0.0], 0.0),
        bone("spine", Some(0), [0.0, 0.95, 0.0], [0.0, 1.5, 0.0], 0.17),
        bone("head", Some(1), [0.0, 1.5, 0.0], [0.0, 1.78, 0.0], 0.11),
        bone("arm.l", Some(1), [0.24, 1.42, 0.0], [0.24, 1.14, 0.0], 0.05),
        bone(
            "forearm.l",
            Some(3),
            [0.24, 1.14, 0.0],
            [0.24, 0.86, 0.0],
            0.045,
        ),
        bone(
            "arm.r",
            Some(1),
            [-0.24, 1.42, 0.0],
            [-0.24, 1.14, 0.0],
            0.05,
        ),
        bone(
            "forearm.r",
            Some(5),
            [-0.24, 1.14, 0.0],
            [-0.24, 0.86, 0.0],
            0.045,
        ),
        bone("thigh.l", Some(0), [0.1, 0.92, 0.0], [0.1, 0.5, 0.0], 0.075),
        bone("shin.l", Some(7), [0.1, 0.5, 0.0], [0.1, 0.06, 0.0], 0.06),
        bone(
            "thigh.r",
            Some(0),
            [-0.1, 0.92, 0.0],
            [-0.1, 0.5, 0.0],
            0.075,
        ),
        bone("shin.r", Some(9), [-0.1, 0.5, 0.0], [-0.1, 0.06, 0.0], 0.06),
    ]
}

/// Local rotation of each bone at phase `t` of the walk cycle (0..1); the hips also bob.
fn pose(bone: usize, t: f32) -> Quat {
    let s = (std::f32::consts::TAU * t).sin();
    let c = (std::f32::consts::TAU * t).cos();
    match bone {
        1 => Quat::from_rotation_y(0.12 * s),
        3 => Quat::from_rotation_x(-0.45 * s),
        4 => Quat::from_rotation_x(-0.25 - 0.1 * s),
        5 => Quat::from_rotation_x(0.45 * s),
        6 => Quat::from_rotation_x(-0.25 + 0.1 * s),
        7 => Quat::from_rotation_x(0.5 * s),
        8 => Quat::from_rotation_x(0.7 * (-c).max(0.0)),
        9 => Quat::from_rotation_x(-0.5 * s),
        10 => Quat::from_rotation_x(0.7 * c.max(0.0)),
        _ => Quat::IDENTITY,
    }
}

const SEGMENTS: usize = 12;
/// Rings per metre of tube.
const RING_DENSITY: f32 = 24.0;
const KEYFRAMES: usize = 17;
/// Length of the walk cycle, seconds.
pub const CYCLE_SECONDS: f32 = 1.0;

struct Skin {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
    indices: Vec<u32>,
}

/// Closed tubes around every bone; the first fifth of a tube blends into the parent bone so
/// joints bend smoothly.
fn skin_mesh(bones: &[Bone]) -> Skin {
    let mut m = Skin {
        positions: vec![],
        normals: vec![],
        joints: vec![],
        weights: vec![],
        indices: vec![],
    };
    for (b, bone) in bones.iter().enumerate() {
        if bone.radius <= 0.0 {
            continue;
        }
        let axis = (bone.tail - bone.head).normalize();
        let side = if axis.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
        let u = axis.cross(side).normalize();
        let v = axis.cross(u);
        let length = bone.head.distance(bone.tail);
        let rings = ((length * RING_DENSITY) as usize).max(2);
        let weight_of = |s: f32| -> ([u16; 4], [f32; 4]) {
            match bone.parent {
                Some(parent) if s < 0.2 => {
                    let w = 0.5 + 2.5 * s;
                    ([b as u16, parent as u16, 0, 0], [w, 1.0 - w, 0.0, 0.0])
                }
                _ => ([b as u16, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
            }
        };
        let first = m.positions.len() as u32;
        for r in 0..=rings {
            let s = r as f32 / rings as f32;
            // Tapered towards both ends, so the tube reads as a limb.
            let radius = bone.radius * (1.0 - 0.25 * (2.0 * s - 1.0).powi(2));
            let centre = bone.head.lerp(bone.tail, s);
            let (joints, weights) = weight_of(s);
            for k in 0..SEGMENTS {
                let a = std::f32::consts::TAU * k as f32 / SEGMENTS as f32;
                let n = u * a.cos() + v * a.sin();
                m.positions.push((centre + n * radius).to_array());
                m.normals.push(n.to_array());
                m.joints.push(joints);
                m.weights.push(weights);
            }
        }
        for r in 0..rings as u32 {
            for k in 0..SEGMENTS as u32 {
                let a = first + r * SEGMENTS as u32 + k;
                let b2 = first + r * SEGMENTS as u32 + (k + 1) % SEGMENTS as u32;
                let (c, d) = (a + SEGMENTS as u32, b2 + SEGMENTS as u32);
                // Counter-clockwise seen from outside: the walls face out.
                m.indices.extend([a, b2, c, b2, d, c]);
            }
        }
        // Caps: a centre vertex per end, fanned to its ring.
        for (ring, centre, normal, s) in [
            (0u32, bone.head, -axis, 0.0f32),
            (rings as u32, bone.tail, axis, 1.0),
        ] {
            let (joints, weights) = weight_of(s);
            let middle = m.positions.len() as u32;
            m.positions.push(centre.to_array());
            m.normals.push(normal.to_array());
            m.joints.push(joints);
            m.weights.push(weights);
            for k in 0..SEGMENTS as u32 {
                let a = first + ring * SEGMENTS as u32 + k;
                let b2 = first + ring * SEGMENTS as u32 + (k + 1) % SEGMENTS as u32;
                if ring == 0 {
                    m.indices.extend([middle, b2, a]);
                } else {
                    m.indices.extend([middle, a, b2]);
                }
            }
        }
    }
    m
}

/// The walker as a `.glb`: node 0 is the root, node 1 the skinned body, nodes 2.. the joints.
pub fn walker_glb() -> Vec<u8> {
    let bones = skeleton();
    let skin = skin_mesh(&bones);
    let mut glb = GlbBuilder::default();
    let mut push = |bytes, target, accessor| glb.push(bytes, target, accessor);
    let f32_bytes =
        |v: &mut dyn Iterator<Item = f32>| -> Vec<u8> { v.flat_map(|f| f.to_le_bytes()).collect() };

    let count = skin.positions.len();
    let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for p in &skin.positions {
        min = min.min(Vec3::from(*p));
        max = max.max(Vec3::from(*p));
    }
    let position = push(
        f32_bytes(&mut skin.positions.iter().flatten().copied()),
        Some(34962),
        json!({ "componentType": 5126, "count": count, "type": "VEC3",
                "min": min.to_array(), "max": max.to_array() }),
    );
    let normal = push(
        f32_bytes(&mut skin.normals.iter().flatten().copied()),
        Some(34962),
        json!({ "componentType": 5126, "count": count, "type": "VEC3" }),
    );
    let joints = push(
        skin.joints
            .iter()
            .flatten()
            .flat_map(|j| j.to_le_bytes())
            .collect(),
        Some(34962),
        json!({ "componentType": 5123, "count": count, "type": "VEC4" }),
    );
    let weights = push(
        f32_bytes(&mut skin.weights.iter().flatten().copied()),
        Some(34962),
        json!({ "componentType": 5126, "count": count, "type": "VEC4" }),
    );
    let indices = push(
        skin.indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
        Some(34963),
        json!({ "componentType": 5125, "count": skin.indices.len(), "type": "SCALAR" }),
    );
    // Joints carry only translations in the rest pose, so each inverse bind matrix is a
    // translation by minus the joint's rest position (column-major).
    let inverse_binds: Vec<f32> = bones
        .iter()
        .flat_map(|b| {
            let t = -b.head;
            [
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, t.x, t.y, t.z, 1.0,
            ]
        })
        .collect();
    let inverse_bind = push(
        f32_bytes(&mut inverse_binds.into_iter()),
        None,
        json!({ "componentType": 5126, "count": bones.len(), "type": "MAT4" }),
    );

    let times: Vec<f32> = (0..KEYFRAMES)
        .map(|k| CYCLE_SECONDS * k as f32 / (KEYFRAMES - 1) as f32)
        .collect();
    let input = push(
        f32_bytes(&mut times.iter().copied()),
        None,
        json!({ "componentType": 5126, "count": KEYFRAMES, "type": "SCALAR",
                "min": [0.0], "max": [CYCLE_SECONDS] }),
    );
    let (mut samplers, mut channels) = (Vec::new(), Vec::new());
    for b in 1..bones.len() {
        let rotations: Vec<f32> = times
            .iter()
            .flat_map(|t| pose(b, t / CYCLE_SECONDS).to_array())
            .collect();
        let output = push(
            f32_bytes(&mut rotations.into_iter()),
            None,
            json!({ "componentType": 5126, "count": KEYFRAMES, "type": "VEC4" }),
        );
        samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
        channels.push(json!({ "sampler": samplers.len() - 1,
            "target": { "node": 2 + b, "path": "rotation" } }));
    }
    // The hips bob twice per cycle.
    let bob: Vec<f32> = times
        .iter()
        .flat_map(|t| {
            let y = bones[0].head.y + 0.03 * (2.0 * std::f32::consts::TAU * t).cos();
            [0.0, y, 0.0]
        })
        .collect();
    let output = push(
        f32_bytes(&mut bob.into_iter()),
        None,
        json!({ "componentType": 5126, "count": KEYFRAMES, "type": "VEC3" }),
    );
    samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
    channels.push(json!({ "sampler": samplers.len() - 1,
        "target": { "node": 2, "path": "translation" } }));

    let mut nodes = vec![
        json!({ "name": "walker", "children": [1, 2] }),
        json!({ "name": "body", "mesh": 0, "skin": 0 }),
    ];
    for (b, bone) in bones.iter().enumerate() {
        let local = bone.head - bone.parent.map_or(Vec3::ZERO, |p| bones[p].head);
        let children: Vec<usize> = bones
            .iter()
            .enumerate()
            .filter(|(_, c)| c.parent == Some(b))
            .map(|(c, _)| 2 + c)
            .collect();
        let mut node = json!({ "name": bone.name, "translation": local.to_array() });
        if !children.is_empty() {
            node["children"] = json!(children);
        }
        nodes.push(node);
    }
    let doc = json!({
        "asset": { "version": "2.0", "generator": "bevy_dynamic_ao generate_assets" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": nodes,
        "meshes": [{ "primitives": [{
            "attributes": { "POSITION": position, "NORMAL": normal,
                            "JOINTS_0": joints, "WEIGHTS_0": weights },
            "indices": indices, "material": 0 }] }],
        "skins": [{ "inverseBindMatrices": inverse_bind, "skeleton": 2,
                    "joints": (2..2 + bones.len()).collect::<Vec<_>>() }],
        "materials": [{ "pbrMetallicRoughness": {
            "baseColorFactor": [0.75, 0.45, 0.3, 1.0], "metallicFactor": 0.0,
            "roughnessFactor": 0.8 } }],
        "animations": [{ "name": "walk", "channels": channels, "samplers": samplers }],
    });
    glb.finish(doc)
}

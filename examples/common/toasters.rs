//! The toaster scene, written as binary glTF by the project's own code: a floor, a kitchen
//! counter and six toaster-like boxes that fly in, tumble and land on the counter (node
//! animation, four seconds, looping), and a camera. Deterministic output.
#![allow(dead_code)]

use bevy::math::{Quat, Vec3};
use serde_json::json;

use crate::gltf_scene::{GlbBuilder, MeshData, box_mesh};

/// Length of the animation, seconds.
pub const SECONDS: f32 = 4.0;
/// Toasters in the scene.
pub const TOASTERS: usize = 6;
/// Height of the counter top, metres.
pub const COUNTER_TOP: f32 = 0.9;
const KEYFRAMES: usize = 33;

/// A toaster: a body with two bread slots and a lever, merged into one mesh, base at y = 0.
pub fn toaster_mesh() -> MeshData {
    let parts = [
        (Vec3::new(0.30, 0.19, 0.17), Vec3::new(0.0, 0.095, 0.0)),
        // Two slot rims on top.
        (Vec3::new(0.22, 0.012, 0.035), Vec3::new(0.0, 0.196, -0.035)),
        (Vec3::new(0.22, 0.012, 0.035), Vec3::new(0.0, 0.196, 0.035)),
        // The lever on the side.
        (Vec3::new(0.02, 0.03, 0.04), Vec3::new(0.16, 0.12, 0.0)),
    ];
    let mut mesh = MeshData {
        positions: vec![],
        normals: vec![],
        indices: vec![],
    };
    for (size, offset) in parts {
        let part = box_mesh(size);
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            part.positions
                .iter()
                .map(|p| (Vec3::from(*p) + offset).to_array()),
        );
        mesh.normals.extend(part.normals);
        mesh.indices.extend(part.indices.iter().map(|i| i + base));
    }
    mesh
}

/// Where toaster `k` starts, where it lands, and how it tumbles on the way.
fn flight(k: usize) -> (Vec3, Vec3, Vec3) {
    let side = if k.is_multiple_of(2) { -1.0 } else { 1.0 };
    let start = Vec3::new(
        side * (2.5 + 0.3 * k as f32),
        2.4 + 0.2 * k as f32,
        -1.5 + 0.5 * k as f32,
    );
    let land = Vec3::new(
        -1.1 + 0.44 * k as f32,
        COUNTER_TOP,
        0.1 * (k % 3) as f32 - 0.1,
    );
    let axis = Vec3::new(1.0, 0.3 * k as f32, side).normalize();
    (start, land, axis)
}

/// Pose of toaster `k` at time `t`: a ballistic arc from its start to its landing spot over the
/// first three seconds, tumbling twice, then resting upright on the counter.
pub fn pose(k: usize, t: f32) -> (Vec3, Quat) {
    let (start, land, axis) = flight(k);
    let flight_time = 2.4 + 0.1 * k as f32;
    let s = (t / flight_time).clamp(0.0, 1.0);
    let arc = 4.0 * s * (1.0 - s) * 0.8;
    let position = start.lerp(land, s) + Vec3::Y * arc;
    let spin = (1.0 - s) * std::f32::consts::TAU * 2.0;
    (position, Quat::from_axis_angle(axis, spin))
}

/// The scene as a `.glb`: nodes floor, counter, toaster0..5, camera.
pub fn toasters_glb() -> Vec<u8> {
    let meshes = [
        box_mesh(Vec3::new(8.0, 0.1, 8.0)),
        box_mesh(Vec3::new(3.2, COUNTER_TOP, 1.0)),
        toaster_mesh(),
    ];
    let mut glb = GlbBuilder::default();
    let mesh_json: Vec<serde_json::Value> = meshes.iter().map(|m| glb.push_mesh(m)).collect();
    let times: Vec<f32> = (0..KEYFRAMES)
        .map(|i| SECONDS * i as f32 / (KEYFRAMES - 1) as f32)
        .collect();
    let input = glb.push(
        times.iter().flat_map(|t| t.to_le_bytes()).collect(),
        None,
        json!({ "componentType": 5126, "count": KEYFRAMES, "type": "SCALAR",
                "min": [0.0], "max": [SECONDS] }),
    );
    let mut nodes = vec![
        json!({ "name": "floor", "mesh": 0, "translation": [0.0, -0.05, 0.0] }),
        json!({ "name": "counter", "mesh": 1, "translation": [0.0, COUNTER_TOP / 2.0, 0.0] }),
    ];
    let (mut samplers, mut channels) = (Vec::new(), Vec::new());
    for k in 0..TOASTERS {
        let node = nodes.len();
        let (position, rotation) = pose(k, 0.0);
        nodes.push(json!({ "name": format!("toaster{k}"), "mesh": 2,
            "translation": position.to_array(), "rotation": rotation.to_array() }));
        let translations: Vec<u8> = times
            .iter()
            .flat_map(|t| pose(k, *t).0.to_array())
            .flat_map(|f| f.to_le_bytes())
            .collect();
        let rotations: Vec<u8> = times
            .iter()
            .flat_map(|t| pose(k, *t).1.to_array())
            .flat_map(|f| f.to_le_bytes())
            .collect();
        let t_out = glb.push(
            translations,
            None,
            json!({ "componentType": 5126, "count": KEYFRAMES, "type": "VEC3" }),
        );
        let r_out = glb.push(
            rotations,
            None,
            json!({ "componentType": 5126, "count": KEYFRAMES, "type": "VEC4" }),
        );
        for (output, path) in [(t_out, "translation"), (r_out, "rotation")] {
            samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
            channels.push(json!({ "sampler": samplers.len() - 1,
                "target": { "node": node, "path": path } }));
        }
    }
    let camera = bevy::transform::components::Transform::from_xyz(0.6, 2.2, 3.4)
        .looking_at(Vec3::new(0.0, 0.8, 0.0), Vec3::Y);
    nodes.push(json!({ "name": "camera", "camera": 0,
        "translation": camera.translation.to_array(),
        "rotation": camera.rotation.normalize().to_array() }));
    let doc = json!({
        "asset": { "version": "2.0", "generator": "bevy_dynamic_ao generate_assets" },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": mesh_json,
        "cameras": [{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.05 } }],
        "materials": [{ "pbrMetallicRoughness": {
            "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0,
            "roughnessFactor": 0.7 } }],
        "animations": [{ "name": "fly", "channels": channels, "samplers": samplers }],
    });
    glb.finish(doc)
}

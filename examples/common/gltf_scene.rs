//! Writes the project's own test scenes as binary glTF (`.glb`), so examples and tests never
//! depend on third-party models. Output is deterministic: the same code writes the same bytes.
#![allow(dead_code)]

use bevy::math::Vec3;
use bevy::transform::components::Transform;
use serde_json::{Value, json};

/// A triangle mesh: positions, normals, indices.
pub struct MeshData {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
}

/// An axis-aligned box of the given size centred on the origin, one quad per face.
pub fn box_mesh(size: Vec3) -> MeshData {
    let h = size / 2.0;
    let mut mesh = MeshData {
        positions: vec![],
        normals: vec![],
        indices: vec![],
    };
    for (normal, up) in [
        (Vec3::X, Vec3::Y),
        (-Vec3::X, Vec3::Y),
        (Vec3::Y, Vec3::Z),
        (-Vec3::Y, Vec3::Z),
        (Vec3::Z, Vec3::Y),
        (-Vec3::Z, Vec3::Y),
    ] {
        let right = up.cross(normal);
        let base = mesh.positions.len() as u32;
        for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let p = (normal + right * a + up * b) * h;
            mesh.positions.push(p.to_array());
            mesh.normals.push(normal.to_array());
        }
        mesh.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    mesh
}

/// A node of the scene: a mesh (index into the mesh list) or a camera, placed by `transform`.
pub enum NodeKind {
    Mesh(usize),
    Camera { yfov: f32 },
}

pub struct Node {
    pub name: &'static str,
    pub kind: NodeKind,
    pub transform: Transform,
    /// Keyframes (seconds, translation) of a linear translation animation.
    pub animation: Vec<(f32, Vec3)>,
}

/// The scene every capture test uses: a 6 m floor, a 1 m cube that slides along x over two
/// seconds, a tall box near it, and a camera looking at them.
pub fn cube_on_plane() -> (Vec<MeshData>, Vec<Node>) {
    let meshes = vec![
        box_mesh(Vec3::new(6.0, 0.1, 6.0)),
        box_mesh(Vec3::ONE),
        box_mesh(Vec3::new(0.5, 1.6, 0.5)),
    ];
    let nodes = vec![
        Node {
            name: "floor",
            kind: NodeKind::Mesh(0),
            transform: Transform::from_xyz(0.0, -0.05, 0.0),
            animation: vec![],
        },
        Node {
            name: "cube",
            kind: NodeKind::Mesh(1),
            transform: Transform::from_xyz(-0.5, 0.5, 0.0),
            animation: vec![
                (0.0, Vec3::new(-0.5, 0.5, 0.0)),
                (2.0, Vec3::new(0.5, 0.5, 0.0)),
            ],
        },
        Node {
            name: "pillar",
            kind: NodeKind::Mesh(2),
            transform: Transform::from_xyz(1.4, 0.8, -0.6),
            animation: vec![],
        },
        Node {
            name: "camera",
            kind: NodeKind::Camera { yfov: 0.8 },
            transform: Transform::from_xyz(2.2, 2.4, 4.2)
                .looking_at(Vec3::new(0.2, 0.3, 0.0), Vec3::Y),
            animation: vec![],
        },
    ];
    (meshes, nodes)
}

/// Encodes meshes and nodes as a `.glb` file.
pub fn write_glb(meshes: &[MeshData], nodes: &[Node]) -> Vec<u8> {
    let mut glb = GlbBuilder::default();
    let mesh_json: Vec<Value> = meshes.iter().map(|m| glb.push_mesh(m)).collect();
    let mut push = |bytes, target, accessor| glb.push(bytes, target, accessor);
    let floats = |v: &[[f32; 3]]| {
        v.iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect::<Vec<u8>>()
    };

    let mut node_json = Vec::new();
    let mut cameras = Vec::new();
    let mut channels = Vec::new();
    let mut samplers = Vec::new();
    for (index, node) in nodes.iter().enumerate() {
        let t = node.transform;
        let mut value = json!({
            "name": node.name,
            "translation": t.translation.to_array(),
            "rotation": t.rotation.normalize().to_array(),
        });
        match node.kind {
            NodeKind::Mesh(mesh) => value["mesh"] = json!(mesh),
            NodeKind::Camera { yfov } => {
                value["camera"] = json!(cameras.len());
                cameras.push(json!({ "type": "perspective",
                    "perspective": { "yfov": yfov, "znear": 0.05 } }));
            }
        }
        if !node.animation.is_empty() {
            let times: Vec<f32> = node.animation.iter().map(|(t, _)| *t).collect();
            let input = push(
                times.iter().flat_map(|f| f.to_le_bytes()).collect(),
                None,
                json!({
                "componentType": 5126, "count": times.len(), "type": "SCALAR",
                "min": [times[0]], "max": [times[times.len() - 1]] }),
            );
            let values: Vec<[f32; 3]> = node.animation.iter().map(|(_, v)| v.to_array()).collect();
            let output = push(
                floats(&values),
                None,
                json!({
                "componentType": 5126, "count": values.len(), "type": "VEC3" }),
            );
            samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
            channels.push(json!({ "sampler": samplers.len() - 1,
                "target": { "node": index, "path": "translation" } }));
        }
        node_json.push(value);
    }

    let mut doc = json!({
        "asset": { "version": "2.0", "generator": "bevy_dynamic_ao generate_assets" },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": node_json,
        "meshes": mesh_json,
        "materials": [{ "pbrMetallicRoughness": {
            "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9 } }],
    });
    if !cameras.is_empty() {
        doc["cameras"] = json!(cameras);
    }
    if !channels.is_empty() {
        doc["animations"] =
            json!([{ "name": "slide", "channels": channels, "samplers": samplers }]);
    }
    glb.finish(doc)
}

/// Collects the binary chunk of a `.glb` and the accessors and buffer views that point into it.
#[derive(Default)]
pub struct GlbBuilder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl GlbBuilder {
    /// Appends `bytes` as a buffer view (with `target`, if any) and `accessor` over it; returns
    /// the accessor's index.
    pub fn push(&mut self, bytes: Vec<u8>, target: Option<u32>, mut accessor: Value) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view =
            json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.bin.extend(bytes);
        self.views.push(view);
        accessor["bufferView"] = json!(self.views.len() - 1);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Appends a mesh's positions, normals and indices; returns its glTF mesh object (material 0).
    pub fn push_mesh(&mut self, mesh: &MeshData) -> Value {
        let floats = |v: &[[f32; 3]]| -> Vec<u8> {
            v.iter().flatten().flat_map(|f| f.to_le_bytes()).collect()
        };
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for p in &mesh.positions {
            min = min.min(Vec3::from(*p));
            max = max.max(Vec3::from(*p));
        }
        let count = mesh.positions.len();
        let position = self.push(
            floats(&mesh.positions),
            Some(34962),
            json!({ "componentType": 5126, "count": count, "type": "VEC3",
                    "min": min.to_array(), "max": max.to_array() }),
        );
        let normal = self.push(
            floats(&mesh.normals),
            Some(34962),
            json!({ "componentType": 5126, "count": count, "type": "VEC3" }),
        );
        let indices = self.push(
            mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
            Some(34963),
            json!({ "componentType": 5125, "count": mesh.indices.len(), "type": "SCALAR" }),
        );
        json!({ "primitives": [{
            "attributes": { "POSITION": position, "NORMAL": normal },
            "indices": indices, "material": 0 }] })
    }

    /// The `.glb` file of `doc` with the collected accessors, views and binary chunk.
    pub fn finish(self, mut doc: Value) -> Vec<u8> {
        let mut bin = self.bin;
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        doc["accessors"] = json!(self.accessors);
        doc["bufferViews"] = json!(self.views);
        doc["buffers"] = json!([{ "byteLength": bin.len() }]);
        let mut text = serde_json::to_vec(&doc).expect("glTF JSON serializes");
        while !text.len().is_multiple_of(4) {
            text.push(b' ');
        }
        let total = 12 + 8 + text.len() + 8 + bin.len();
        let mut glb = Vec::with_capacity(total);
        glb.extend(b"glTF");
        glb.extend(2u32.to_le_bytes());
        glb.extend((total as u32).to_le_bytes());
        glb.extend((text.len() as u32).to_le_bytes());
        glb.extend(b"JSON");
        glb.extend(text);
        glb.extend((bin.len() as u32).to_le_bytes());
        glb.extend(b"BIN\0");
        glb.extend(bin);
        glb
    }
}

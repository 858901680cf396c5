//! A look at the file's glTF structure before Bevy's loader reads it. Some malformed files make
//! the glTF reader inside Bevy's loader panic rather than return an error:
//!
//! - an attribute that names an accessor the file does not have (the validator indexes it before
//!   it reports it);
//! - a buffer view whose stride is shorter than the elements its accessors read;
//! - an accessor read as elements of another shape than it holds: indices that are not single
//!   unsigned integers, morph targets that are not three floats, animation key times that are
//!   not single floats, key values of another shape than their channel's property, inverse bind
//!   matrices that are not 4 × 4 floats;
//! - an animation channel whose target node or sampler the file does not have.
//!
//! Bevy catches the loader's panic, but its message and backtrace end up on stderr; the capture
//! names the fault in one line instead and does not hand the file on.

use std::panic;
use std::path::Path;

use gltf::json::{
    self,
    accessor::{ComponentType, Type},
    animation::Property,
    validation::Checked,
};

/// What is wrong with the glTF file at `path`, where it is one of the kinds above. Anything else
/// (a missing file, a file that is no glTF) is left to Bevy's loader, which reports it.
pub fn check(path: &Path) -> Result<(), String> {
    let Ok(bytes) = std::fs::read(path) else {
        return Ok(());
    };
    // The validator's panic is the answer here, not a fault of the capture: keep it off stderr.
    let hook = panic::take_hook();
    panic::set_hook(Box::new(|_| {}));
    let parsed = panic::catch_unwind(|| gltf::Gltf::from_slice(&bytes));
    panic::set_hook(hook);
    let gltf = match parsed {
        Err(_) => {
            return Err(format!(
                "cannot load {}: its glTF structure names an object it does not have (the glTF \
                 validator failed on it)",
                path.display()
            ));
        }
        Ok(Err(_)) => return Ok(()),
        Ok(Ok(gltf)) => gltf,
    };
    let fault = |what: String| Err(format!("cannot load {}: {what}", path.display()));
    for accessor in gltf.accessors() {
        let Some(view) = accessor.view() else {
            continue;
        };
        if let Some(stride) = view.stride()
            && stride < accessor.size()
        {
            return fault(format!(
                "accessor {} reads elements of {} bytes through buffer view {}, whose stride is \
                 {} bytes",
                accessor.index(),
                accessor.size(),
                view.index(),
                stride
            ));
        }
    }
    match element_shapes(gltf.document.as_json()) {
        Some(what) => fault(what),
        None => Ok(()),
    }
}

/// The first accessor that Bevy's loader would read as elements of another shape than it holds,
/// or an animation channel that names a node or sampler the file does not have, in words.
/// Indices are taken from the JSON and checked here: the validator leaves some unchecked, and
/// the reader's own lookups unwrap them.
fn element_shapes(root: &json::Root) -> Option<String> {
    mesh_faults(root)
        .or_else(|| skin_faults(root))
        .or_else(|| animation_faults(root))
}

/// Rotations and morph weights may be stored as floats or as normalized integers.
const FLOAT_OR_NORMALIZED: [ComponentType; 5] = [
    ComponentType::F32,
    ComponentType::I8,
    ComponentType::U8,
    ComponentType::I16,
    ComponentType::U16,
];

/// What accessor `index` holds, where that is not `kind` of one of `components`; `None` where it
/// is, or where the file has no such accessor (the validator reports that).
fn wrong_shape(
    root: &json::Root,
    index: usize,
    kind: Type,
    components: &[ComponentType],
) -> Option<(Type, ComponentType)> {
    let accessor = root.accessors.get(index)?;
    match (accessor.type_, accessor.component_type) {
        (Checked::Valid(k), Checked::Valid(c)) if k != kind || !components.contains(&c.0) => {
            Some((k, c.0))
        }
        _ => None,
    }
}

/// Indices that are not single unsigned integers, morph targets that are not three floats.
fn mesh_faults(root: &json::Root) -> Option<String> {
    let unsigned = [ComponentType::U8, ComponentType::U16, ComponentType::U32];
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(indices) = primitive.indices.map(|i| i.value())
                && let Some(found) = wrong_shape(root, indices, Type::Scalar, &unsigned)
            {
                return Some(format!(
                    "primitive {p} of mesh {m} reads its indices from accessor {indices}, which \
                     holds {}; indices are single unsigned integers",
                    describe(found)
                ));
            }
            for (t, target) in primitive.targets.iter().flatten().enumerate() {
                for (attribute, index) in [
                    ("POSITION", target.positions),
                    ("NORMAL", target.normals),
                    ("TANGENT", target.tangents),
                ] {
                    let Some(index) = index.map(|i| i.value()) else {
                        continue;
                    };
                    if let Some(found) = wrong_shape(root, index, Type::Vec3, &[ComponentType::F32])
                    {
                        return Some(format!(
                            "morph target {t} of primitive {p} of mesh {m} reads its {attribute} \
                             from accessor {index}, which holds {}; a morph target's {attribute} \
                             is VEC3 of FLOAT",
                            describe(found)
                        ));
                    }
                }
            }
        }
    }
    None
}

/// Inverse bind matrices that are not 4 × 4 floats.
fn skin_faults(root: &json::Root) -> Option<String> {
    for (s, skin) in root.skins.iter().enumerate() {
        let Some(matrices) = skin.inverse_bind_matrices.map(|i| i.value()) else {
            continue;
        };
        if let Some(found) = wrong_shape(root, matrices, Type::Mat4, &[ComponentType::F32]) {
            return Some(format!(
                "skin {s} reads its inverse bind matrices from accessor {matrices}, which holds \
                 {}; they are 4 × 4 matrices of floats",
                describe(found)
            ));
        }
    }
    None
}

/// Channels that move a node or use a sampler the file does not have, key times that are not
/// single floats, key values of another shape than the channel's property.
fn animation_faults(root: &json::Root) -> Option<String> {
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let node = channel.target.node.value();
            if node >= root.nodes.len() {
                return Some(format!(
                    "channel {c} of animation {a} moves node {node}, and the file has {} nodes",
                    root.nodes.len()
                ));
            }
            let Some(sampler) = animation.samplers.get(channel.sampler.value()) else {
                return Some(format!(
                    "channel {c} of animation {a} uses sampler {}, and the animation has {}",
                    channel.sampler.value(),
                    animation.samplers.len()
                ));
            };
            let input = sampler.input.value();
            if let Some(found) = wrong_shape(root, input, Type::Scalar, &[ComponentType::F32]) {
                return Some(format!(
                    "channel {c} of animation {a} reads its key times from accessor {input}, \
                     which holds {}; key times are single floats",
                    describe(found)
                ));
            }
            let (kind, components, property, takes) = match channel.target.path {
                Checked::Valid(Property::Translation) => (
                    Type::Vec3,
                    &[ComponentType::F32][..],
                    "a translation",
                    "VEC3 of FLOAT",
                ),
                Checked::Valid(Property::Scale) => (
                    Type::Vec3,
                    &[ComponentType::F32][..],
                    "a scale",
                    "VEC3 of FLOAT",
                ),
                Checked::Valid(Property::Rotation) => (
                    Type::Vec4,
                    &FLOAT_OR_NORMALIZED[..],
                    "a rotation",
                    "VEC4 of FLOAT or of normalized integers",
                ),
                Checked::Valid(Property::MorphTargetWeights) => (
                    Type::Scalar,
                    &FLOAT_OR_NORMALIZED[..],
                    "morph target weights",
                    "SCALAR of FLOAT or of normalized integers",
                ),
                Checked::Invalid => continue,
            };
            let output = sampler.output.value();
            if let Some(found) = wrong_shape(root, output, kind, components) {
                return Some(format!(
                    "channel {c} of animation {a} animates {property} from accessor {output}, \
                     which holds {}; such a channel reads {takes}",
                    describe(found)
                ));
            }
        }
    }
    None
}

/// An accessor's element as the glTF specification names it: "VEC3 of FLOAT".
fn describe((kind, component): (Type, ComponentType)) -> String {
    let kind = match kind {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    };
    let component = match component {
        ComponentType::I8 => "BYTE",
        ComponentType::U8 => "UNSIGNED_BYTE",
        ComponentType::I16 => "SHORT",
        ComponentType::U16 => "UNSIGNED_SHORT",
        ComponentType::U32 => "UNSIGNED_INT",
        ComponentType::F32 => "FLOAT",
    };
    format!("{kind} of {component}")
}

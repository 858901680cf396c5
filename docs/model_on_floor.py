#!/usr/bin/env python3
"""Stands a binary glTF model (.glb) on a 20 m floor quad and adds a camera, so that
`ao_capture` (which renders through a file's first camera) can capture it: the way the tests set
up third-party models (`tests/gpu/far_scenes.rs`, `third_party`), for any model and framing.
The model is moved (and with `--height`, scaled: the tests scale each model to a height) so
that the lowest point of its meshes in their rest pose (node transforms applied, skins and morph
targets not) lies at the origin's height, centred over it, just above the floor (y = 0); the
camera (vertical field of view 0.8 rad, aspect 4:3) stands at EYE looking at TARGET, metres. The
model's own cameras are dropped. Writes OUT only; the
input is read, never copied anywhere else. Standard library only.

    python3 docs/model_on_floor.py MODEL.glb OUT.glb [--height 1.8] --eye 0,1.5,3.6 --target 0,0.6,0

BENCHMARKS.md ("DamagedHelmet close up") uses it on `../shared/assets/DamagedHelmet`.
"""
import argparse
import json
import math
import struct

GLB_MAGIC = 0x46546C67
JSON_CHUNK = 0x4E4F534A
BIN_CHUNK = 0x004E4942


def read_glb(path):
    data = open(path, "rb").read()
    magic, _, _ = struct.unpack_from("<III", data, 0)
    if magic != GLB_MAGIC:
        raise SystemExit(f"{path}: not a binary glTF file")
    offset, doc, binary = 12, None, bytearray()
    while offset + 8 <= len(data):
        length, kind = struct.unpack_from("<II", data, offset)
        chunk = data[offset + 8 : offset + 8 + length]
        if kind == JSON_CHUNK:
            doc = json.loads(chunk)
        elif kind == BIN_CHUNK:
            binary = bytearray(chunk)
        offset += 8 + length
    if doc is None:
        raise SystemExit(f"{path}: no JSON chunk")
    return doc, binary


def write_glb(path, doc, binary):
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    with open(path, "wb") as out:
        out.write(struct.pack("<III", GLB_MAGIC, 2, total))
        out.write(struct.pack("<II", len(text), JSON_CHUNK) + text)
        out.write(struct.pack("<II", len(binary), BIN_CHUNK) + bytes(binary))


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def node_matrix(node):
    if "matrix" in node:
        m = node["matrix"]
        return [[m[c * 4 + r] for c in range(4)] for r in range(4)]
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    sx, sy, sz = node.get("scale", [1, 1, 1])
    tx, ty, tz = node.get("translation", [0, 0, 0])
    r = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    return [
        [r[0][0] * sx, r[0][1] * sy, r[0][2] * sz, tx],
        [r[1][0] * sx, r[1][1] * sy, r[1][2] * sz, ty],
        [r[2][0] * sx, r[2][1] * sy, r[2][2] * sz, tz],
        [0, 0, 0, 1],
    ]


def world_bounds(doc):
    """Bounds of every mesh's POSITION accessor (its min and max), through the node tree."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    identity = [[float(i == j) for j in range(4)] for i in range(4)]
    scene = doc.get("scenes", [{}])[doc.get("scene", 0)]
    stack = [(n, identity) for n in scene.get("nodes", [])]
    while stack:
        index, parent = stack.pop()
        node = doc["nodes"][index]
        m = mat_mul(parent, node_matrix(node))
        stack.extend((child, m) for child in node.get("children", []))
        if "mesh" not in node:
            continue
        for primitive in doc["meshes"][node["mesh"]]["primitives"]:
            accessor = doc["accessors"][primitive["attributes"]["POSITION"]]
            a, b = accessor.get("min"), accessor.get("max")
            if a is None or b is None:
                continue
            for corner in range(8):
                p = [b[i] if corner >> i & 1 else a[i] for i in range(3)] + [1]
                q = [sum(m[r][k] * p[k] for k in range(4)) for r in range(3)]
                lo = [min(lo[i], q[i]) for i in range(3)]
                hi = [max(hi[i], q[i]) for i in range(3)]
    if not all(math.isfinite(v) for v in lo + hi):
        raise SystemExit("the model has no mesh with POSITION bounds")
    return lo, hi


def look_rotation(eye, target):
    """The quaternion (x, y, z, w) that turns a glTF camera (looking down −z, y up) from `eye`
    toward `target`."""
    f = [target[i] - eye[i] for i in range(3)]
    n = math.sqrt(sum(v * v for v in f))
    f = [v / n for v in f]
    r = [-f[2], 0.0, f[0]]  # f × (0, 1, 0)
    n = math.sqrt(sum(v * v for v in r)) or 1.0
    r = [v / n for v in r]
    u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
    m = [[r[i], u[i], -f[i]] for i in range(3)]  # columns: right, up, back
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0:
        s = math.sqrt(trace + 1.0) * 2
        return [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4]
    i = max(range(3), key=lambda k: m[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = math.sqrt(1.0 + m[i][i] - m[j][j] - m[k][k]) * 2
    q = [0.0] * 4
    q[i] = s / 4
    q[j] = (m[j][i] + m[i][j]) / s
    q[k] = (m[k][i] + m[i][k]) / s
    q[3] = (m[k][j] - m[j][k]) / s
    return q


def vector(text):
    values = [float(v) for v in text.split(",")]
    if len(values) != 3:
        raise argparse.ArgumentTypeError("three comma-separated numbers")
    return values


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model")
    parser.add_argument("out")
    parser.add_argument("--eye", type=vector, default=[0.0, 1.5, 3.6])
    parser.add_argument("--target", type=vector, default=[0.0, 0.6, 0.0])
    parser.add_argument("--height", type=float, help="scale the model to this height, metres")
    args = parser.parse_args()

    doc, binary = read_glb(args.model)
    lo, hi = world_bounds(doc)
    scale = args.height / (hi[1] - lo[1]) if args.height else 1.0
    if not math.isfinite(scale) or scale <= 0:
        raise SystemExit("the model has no height to scale")
    centre = [(lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2]
    scene = doc["scenes"][doc.get("scene", 0)]
    doc["nodes"].append(
        {
            "name": "model",
            "children": scene.get("nodes", []),
            "scale": [scale] * 3,
            "translation": [-c * scale + (1e-3 if i == 1 else 0.0) for i, c in enumerate(centre)],
        }
    )
    scene["nodes"] = [len(doc["nodes"]) - 1]
    centre, y = [0.0, 0.0, 0.0], 0.0

    binary += b"\0" * (-len(binary) % 4)
    offset = len(binary)
    half = 10.0
    corners = [(-half, -half), (half, -half), (half, half), (-half, half)]
    positions = [v for x, z in corners for v in (centre[0] + x, y, centre[2] + z)]
    binary += struct.pack("<12f", *positions)
    binary += struct.pack("<12f", *[0.0, 1.0, 0.0] * 4)
    binary += struct.pack("<6H", 0, 2, 1, 0, 3, 2)
    views = len(doc.setdefault("bufferViews", []))
    doc["bufferViews"] += [
        {"buffer": 0, "byteOffset": offset, "byteLength": 48},
        {"buffer": 0, "byteOffset": offset + 48, "byteLength": 48},
        {"buffer": 0, "byteOffset": offset + 96, "byteLength": 12},
    ]
    accessors = len(doc.setdefault("accessors", []))
    doc["accessors"] += [
        {
            "bufferView": views,
            "componentType": 5126,
            "count": 4,
            "type": "VEC3",
            "min": [centre[0] - half, y, centre[2] - half],
            "max": [centre[0] + half, y, centre[2] + half],
        },
        {"bufferView": views + 1, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": views + 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
    ]
    doc.setdefault("materials", []).append(
        {
            "name": "floor",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 1.0,
            },
        }
    )
    doc["meshes"].append(
        {
            "name": "floor",
            "primitives": [
                {
                    "attributes": {"POSITION": accessors, "NORMAL": accessors + 1},
                    "indices": accessors + 2,
                    "material": len(doc["materials"]) - 1,
                }
            ],
        }
    )
    for node in doc["nodes"]:
        node.pop("camera", None)
    doc["cameras"] = [
        {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05, "aspectRatio": 4 / 3}}
    ]
    eye = [centre[i] + args.eye[i] for i in range(3)]
    target = [centre[i] + args.target[i] for i in range(3)]
    doc["nodes"].append({"name": "floor", "mesh": len(doc["meshes"]) - 1})
    scene["nodes"].append(len(doc["nodes"]) - 1)
    doc["nodes"].append({"name": "camera", "camera": 0, "translation": eye,
                         "rotation": look_rotation(eye, target)})
    scene["nodes"].append(len(doc["nodes"]) - 1)
    if not doc.get("buffers"):
        doc["buffers"] = [{}]
    doc["buffers"][0]["byteLength"] = len(binary) + (-len(binary) % 4)
    write_glb(args.out, doc, binary)


if __name__ == "__main__":
    main()

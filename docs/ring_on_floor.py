#!/usr/bin/env python3
"""Writes ring_on_floor.glb: a bumpy ring of 60,000 triangles (major radius 0.6 m, tube radius
0.25 m with bumps of 15 % of it, 250 x 120 segments) on a 10 m floor quad, and a camera at
(2, 1.6, 2.4) looking at (0, 0.3, 0) with a vertical field of view of 0.8 rad: a concave,
finely detailed object on a floor of zero thickness, for `ao_capture --out-truth`
(BENCHMARKS.md, "A bumpy ring on a floor"). Standard library only.

    python3 docs/ring_on_floor.py /tmp/ring_on_floor.glb
"""
import json
import math
import struct
import sys


def ring(major, tube, nu, nv):
    positions, normals, indices = [], [], []
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            v = 2 * math.pi * j / nv
            r = tube * (1 + 0.15 * math.sin(12 * u) * math.cos(7 * v))
            x = (major + r * math.cos(v)) * math.cos(u)
            z = (major + r * math.cos(v)) * math.sin(u)
            positions.append((x, r * math.sin(v) + 0.45, z))
            normals.append((math.cos(v) * math.cos(u), math.sin(v), math.cos(v) * math.sin(u)))
    for i in range(nu):
        for j in range(nv):
            a = i * nv + j
            b = ((i + 1) % nu) * nv + j
            c = ((i + 1) % nu) * nv + (j + 1) % nv
            d = i * nv + (j + 1) % nv
            indices += [a, d, b, b, d, c]
    return positions, normals, indices


def look_rotation(eye, target):
    """Quaternion (x, y, z, w) turning -Z towards target, +Y up."""
    f = [t - e for t, e in zip(target, eye)]
    n = math.sqrt(sum(c * c for c in f))
    z = [-c / n for c in f]
    x = [z[2], 0.0, -z[0]]  # (0, 1, 0) x z
    n = math.sqrt(sum(c * c for c in x))
    x = [c / n for c in x]
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    m = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    s = math.sqrt(1 + m[0][0] + m[1][1] + m[2][2]) * 2
    return [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4]


def main(path):
    data, views, accessors = bytearray(), [], []

    def add(values, fmt, kind, component, target, bounds=False):
        offset = len(data)
        for v in values:
            data.extend(struct.pack(fmt, *v) if isinstance(v, tuple) else struct.pack(fmt, v))
        while len(data) % 4:
            data.append(0)
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(data) - offset, "target": target})
        accessor = {"bufferView": len(views) - 1, "componentType": component, "count": len(values), "type": kind}
        if bounds:
            accessor["min"] = [min(v[k] for v in values) for k in range(3)]
            accessor["max"] = [max(v[k] for v in values) for k in range(3)]
        accessors.append(accessor)
        return len(accessors) - 1

    def mesh(positions, normals, indices):
        p = add(positions, "<3f", "VEC3", 5126, 34962, bounds=True)
        n = add(normals, "<3f", "VEC3", 5126, 34962)
        i = add(indices, "<I", "SCALAR", 5125, 34963)
        return {"primitives": [{"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "material": 0}]}

    floor = ([(-5, 0, -5), (5, 0, -5), (5, 0, 5), (-5, 0, 5)], [(0, 1, 0)] * 4, [0, 2, 1, 0, 3, 2])
    eye = (2.0, 1.6, 2.4)
    gltf = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0, "name": "ring"},
            {"mesh": 1, "name": "floor"},
            {"camera": 0, "translation": list(eye), "rotation": look_rotation(eye, (0.0, 0.3, 0.0))},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0]}}],
        "meshes": [mesh(*ring(0.6, 0.25, 250, 120)), mesh(*floor)],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(data)}],
    }
    text = json.dumps(gltf).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(data)
    with open(path, "wb") as out:
        out.write(struct.pack("<III", 0x46546C67, 2, total))
        out.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
        out.write(struct.pack("<II", len(data), 0x004E4942) + bytes(data))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "ring_on_floor.glb")

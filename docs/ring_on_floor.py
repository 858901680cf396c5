#!/usr/bin/env python3
"""Writes ring_on_floor.glb: a bumpy ring of 60,000 triangles (major radius 0.6 m, tube radius
0.25 m with bumps of 15 % of it, 250 x 120 segments) on a 10 m floor quad, and a camera at
(2, 1.6, 2.4) looking at (0, 0.3, 0) with a vertical field of view of 0.8 rad: a concave,
finely detailed object on a floor of zero thickness, for `ao_capture --out-truth`
(BENCHMARKS.md, "A bumpy ring on a floor"). With `--blob`, the same floor and camera with a
bumpy ball of 60,000 triangles (radius 0.45 m, normals from its faces) resting on the floor and a
1.6 x 1.1 m slab 8 cm thick beside it, reaching out of the view. With `--fins`, the same floor
and camera with a heat sink: a 0.8 x 0.5 m base 4 cm thick carrying 20 fins 8 mm thick, 0.2 m
tall and 4 cm apart (gaps of about a pixel at 160 x 120, six at 640 x 480), and beside it a
grille of 12 upright bars 1 cm square and 3 cm apart: detail finer than a half-resolution texel
(BENCHMARKS.md, "Past the screen's edge, and fins"). Standard library only.

    python3 docs/ring_on_floor.py /tmp/ring_on_floor.glb
    python3 docs/ring_on_floor.py /tmp/blob_and_slab.glb --blob
    python3 docs/ring_on_floor.py /tmp/fins.glb --fins
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


def blob(radius, nu, nv):
    positions, normals, indices = [], [], []
    for i in range(nu + 1):
        th = math.pi * i / nu
        for j in range(nv):
            ph = 2 * math.pi * j / nv
            r = radius * (1 + 0.08 * math.sin(9 * th) * math.cos(11 * ph) + 0.04 * math.sin(23 * ph + 5 * th))
            n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
            positions.append((r * n[0], r * n[1] + radius * 0.92, r * n[2]))
            normals.append(n)
    for i in range(nu):
        for j in range(nv):
            a = i * nv + j
            b = (i + 1) * nv + j
            c = (i + 1) * nv + (j + 1) % nv
            d = i * nv + (j + 1) % nv
            indices += [a, b, d, d, b, c]
    acc = [[0.0, 0.0, 0.0] for _ in positions]
    for t in range(0, len(indices), 3):
        ia, ib, ic = indices[t:t + 3]
        pa, pb, pc = positions[ia], positions[ib], positions[ic]
        e1 = [pb[k] - pa[k] for k in range(3)]
        e2 = [pc[k] - pa[k] for k in range(3)]
        fn = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
        for v in (ia, ib, ic):
            for k in range(3):
                acc[v][k] += fn[k]
    normals = []
    for v, a in enumerate(acc):
        n = math.sqrt(sum(c * c for c in a)) or 1.0
        normals.append(tuple(c / n for c in a))
    # Face normals of the winding above point inwards: turn normals and winding outwards.
    cx = (0.0, 0.45 * 0.92, 0.0)
    flip = sum((positions[v][k] - cx[k]) * normals[v][k] for v in range(0, len(positions), 97) for k in range(3)) < 0
    if flip:
        normals = [tuple(-c for c in n) for n in normals]
        indices = [indices[t + k] for t in range(0, len(indices), 3) for k in (0, 2, 1)]
    return positions, normals, indices


def slab(cx, cz, w, h, t, y0=0):
    """A box with its base at height y0, top at h, t thick along x and w wide along z."""
    x0, x1, z0, z1 = cx - t / 2, cx + t / 2, cz - w / 2, cz + w / 2
    return box(x0, x1, y0, h, z0, z1)


def box(x0, x1, y0, h, z0, z1):
    b = y0
    faces = [((1,0,0), [(x1,b,z0),(x1,h,z0),(x1,h,z1),(x1,b,z1)]), ((-1,0,0), [(x0,b,z1),(x0,h,z1),(x0,h,z0),(x0,b,z0)]),
             ((0,0,1), [(x0,b,z1),(x1,b,z1),(x1,h,z1),(x0,h,z1)]), ((0,0,-1), [(x1,b,z0),(x0,b,z0),(x0,h,z0),(x1,h,z0)]),
             ((0,1,0), [(x0,h,z0),(x0,h,z1),(x1,h,z1),(x1,h,z0)]), ((0,-1,0), [(x0,b,z0),(x1,b,z0),(x1,b,z1),(x0,b,z1)])]
    positions, normals, indices = [], [], []
    for n, quad in faces:
        k = len(positions)
        positions += quad; normals += [n] * 4
        indices += [k, k + 1, k + 2, k, k + 2, k + 3]
    return positions, normals, indices


def joined(parts):
    """One mesh of several (positions, normals, indices)."""
    positions, normals, indices = [], [], []
    for p, n, i in parts:
        k = len(positions)
        positions += p; normals += n
        indices += [k + j for j in i]
    return positions, normals, indices


def heat_sink():
    base = slab(0.0, 0.0, 0.5, 0.04, 0.8)
    fins = [slab(-0.38 + 0.04 * k, 0.0, 0.5, 0.24, 0.008, 0.04) for k in range(20)]
    return joined([base] + fins)


def grille():
    return joined([box(-0.75 + 0.03 * k, -0.74 + 0.03 * k, 0.0, 0.35, 0.6, 0.61) for k in range(12)])


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


def main(path, scene="ring"):
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
    eye, target = (2.0, 1.6, 2.4), (0.0, 0.3, 0.0)
    if scene == "blob":
        objects = [("blob", blob(0.45, 150, 200)), ("slab", slab(-1.15, -0.3, 1.6, 1.1, 0.08))]
    elif scene == "fins":
        objects = [("heat sink", heat_sink()), ("grille", grille())]
        eye, target = (0.7, 0.8, 1.2), (-0.15, 0.1, 0.1)
    else:
        objects = [("ring", ring(0.6, 0.25, 250, 120))]
    objects.append(("floor", floor))
    nodes = [{"mesh": k, "name": name} for k, (name, _) in enumerate(objects)]
    nodes.append({"camera": 0, "translation": list(eye), "rotation": look_rotation(eye, target)})
    gltf = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0]}}],
        "meshes": [mesh(*geometry) for _, geometry in objects],
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
    if any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(__doc__)
        sys.exit(0)
    flags = [a for a in sys.argv[1:] if a in ("--blob", "--fins")]
    paths = [a for a in sys.argv[1:] if a not in flags]
    unknown = [a for a in paths if a.startswith("-")]
    if unknown or len(paths) > 1:
        sys.exit(f"usage: ring_on_floor.py [OUT.glb] [--blob | --fins]; got {' '.join(sys.argv[1:])}")
    main(paths[0] if paths else "ring_on_floor.glb", flags[0][2:] if flags else "ring")

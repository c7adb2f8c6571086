#!/usr/bin/env python3
"""Writes a small rigged glTF whose bind pose lies on its back and whose clip stands it up, as the Khronos CesiumMan
sample does (its mesh is modelled Z-up in a Y-up file; the clip's root rotation stands it): a 1.8-unit figure (a box
0.5 wide, 0.3 deep) along +Z, two joints (hips at the feet, chest at mid-height), and a clip "stand" that turns the
hips -90 degrees about X (+Z onto +Y) and bends the chest a little. The viewer's framing test opens it: a camera
fitted to the bind pose would frame a box lying on the floor and cut the standing figure's top off.

usage: lying_figure.py OUT.gltf
"""
import base64
import json
import math
import struct
import sys


def main(out):
    w, d, h = 0.25, 0.15, 1.8
    # Two rings of four corners at each of three heights (feet, middle, head), along +Z.
    levels = [0.0, 0.5 * h, h]
    positions = [(x, y, z) for z in levels for (x, y) in ((-w, -d), (w, -d), (w, d), (-w, d))]
    joints = [(0 if z < 0.25 * h else 1, 0, 0, 0) for (_, _, z) in positions]
    weights = [(1.0, 0.0, 0.0, 0.0)] * len(positions)
    triangles = []
    for ring in range(2):  # the sides between consecutive rings
        for k in range(4):
            a, b = 4 * ring + k, 4 * ring + (k + 1) % 4
            triangles += [(a, b, b + 4), (a, b + 4, a + 4)]
    triangles += [(0, 2, 1), (0, 3, 2), (8, 9, 10), (8, 10, 11)]  # the soles and the top

    def identity_with(tz):  # column-major 4x4: a translation along Z
        return [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, tz, 1]

    inverse_bind = identity_with(0.0) + identity_with(-0.5 * h)
    times = [0.0, 1.0]
    s = math.sqrt(0.5)
    stand = [(-s, 0.0, 0.0, s)] * 2  # (x, y, z, w): -90 degrees about X
    bend = [(0.0, 0.0, 0.0, 1.0), (math.sin(0.1), 0.0, 0.0, math.cos(0.1))]

    chunks, views, accessors = [], [], []

    def add(fmt, items, component, kind, count, target=None, minmax=False):
        data = b"".join(struct.pack("<" + fmt, *item) if isinstance(item, tuple) else struct.pack("<" + fmt, item)
                        for item in items)
        offset = sum(len(c) for c in chunks)
        chunks.append(data + b"\0" * (-len(data) % 4))
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(data)}
        if target:
            view["target"] = target
        views.append(view)
        accessor = {"bufferView": len(views) - 1, "componentType": component, "count": count, "type": kind}
        if minmax:
            flat = [item if isinstance(item, tuple) else (item,) for item in items]
            accessor["min"] = [min(v[i] for v in flat) for i in range(len(flat[0]))]
            accessor["max"] = [max(v[i] for v in flat) for i in range(len(flat[0]))]
        accessors.append(accessor)
        return len(accessors) - 1

    position = add("3f", positions, 5126, "VEC3", len(positions), 34962, True)
    joint = add("4B", joints, 5121, "VEC4", len(joints), 34962)
    weight = add("4f", weights, 5126, "VEC4", len(weights), 34962)
    index = add("3H", triangles, 5123, "SCALAR", 3 * len(triangles), 34963)
    inverse = add("16f", [tuple(inverse_bind[:16]), tuple(inverse_bind[16:])], 5126, "MAT4", 2)
    time = add("f", times, 5126, "SCALAR", 2, None, True)
    stand_out = add("4f", stand, 5126, "VEC4", 2)
    bend_out = add("4f", bend, 5126, "VEC4", 2)
    buffer = b"".join(chunks)
    gltf = {
        "asset": {"version": "2.0", "generator": "libdeform samples/tests/lying_figure.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "figure", "mesh": 0, "skin": 0},
            {"name": "hips", "children": [2]},
            {"name": "chest", "translation": [0.0, 0.0, 0.5 * h]},
        ],
        "meshes": [{"name": "figure", "primitives": [{
            "attributes": {"POSITION": position, "JOINTS_0": joint, "WEIGHTS_0": weight}, "indices": index}]}],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": inverse, "skeleton": 1}],
        "animations": [{"name": "stand",
                        "samplers": [{"input": time, "output": stand_out}, {"input": time, "output": bend_out}],
                        "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}},
                                     {"sampler": 1, "target": {"node": 2, "path": "rotation"}}]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(buffer),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(buffer).decode()}],
    }
    with open(out, "w") as f:
        json.dump(gltf, f, indent=1)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])

#!/usr/bin/env python3
"""Writes a small closed room as glTF 2.0 (one file, buffer embedded): a 4 x 3 x 4 m box seen from
inside, a red and a green wall, a block on the floor, a point light (KHR_lights_punctual) and a
camera. A scene as an exporter writes one, for tests that need a file with light in it.

usage: room_gltf.py OUT.gltf
"""

from __future__ import annotations

import base64
import json
import struct
import sys

WIDTH, HEIGHT, DEPTH = 4.0, 3.0, 4.0
WHITE, RED, GREEN = 0, 1, 2


def quads() -> list[tuple[tuple, tuple, int]]:
    """(corners, the normal the lit side faces, material) of every quad."""
    w, h, d = WIDTH, HEIGHT, DEPTH
    x0, x1, z0, z1, top = 1.2, 2.2, 1.2, 2.2, 1.0  # the block
    return [
        (((0, 0, 0), (w, 0, 0), (w, 0, d), (0, 0, d)), (0, 1, 0), WHITE),  # floor
        (((0, h, 0), (0, h, d), (w, h, d), (w, h, 0)), (0, -1, 0), WHITE),  # ceiling
        (((0, 0, 0), (0, h, 0), (w, h, 0), (w, 0, 0)), (0, 0, 1), WHITE),  # back wall
        (((0, 0, 0), (0, 0, d), (0, h, d), (0, h, 0)), (1, 0, 0), RED),  # left wall
        (((w, 0, 0), (w, h, 0), (w, h, d), (w, 0, d)), (-1, 0, 0), GREEN),  # right wall
        (((0, 0, d), (0, h, d), (w, h, d), (w, 0, d)), (0, 0, -1), WHITE),  # front wall, behind the camera
        (((x0, top, z0), (x0, top, z1), (x1, top, z1), (x1, top, z0)), (0, 1, 0), WHITE),
        (((x0, 0, z1), (x1, 0, z1), (x1, top, z1), (x0, top, z1)), (0, 0, 1), WHITE),
        (((x0, 0, z0), (x0, top, z0), (x1, top, z0), (x1, 0, z0)), (0, 0, -1), WHITE),
        (((x0, 0, z0), (x0, 0, z1), (x0, top, z1), (x0, top, z0)), (-1, 0, 0), WHITE),
        (((x1, 0, z0), (x1, top, z0), (x1, top, z1), (x1, 0, z1)), (1, 0, 0), WHITE),
    ]


def main() -> None:
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    buffer = bytearray()
    views, accessors, primitives = [], [], []

    def view(data: bytes, target: int) -> int:
        while len(buffer) % 4:
            buffer.append(0)
        views.append({"buffer": 0, "byteOffset": len(buffer), "byteLength": len(data), "target": target})
        buffer.extend(data)
        return len(views) - 1

    for material in (WHITE, RED, GREEN):
        positions, normals, indices = [], [], []
        for corners, normal, of in quads():
            if of != material:
                continue
            base = len(positions)
            positions += corners
            normals += [normal] * 4
            a, b, c = corners[0], corners[1], corners[2]
            u = [b[i] - a[i] for i in range(3)]
            v = [c[i] - a[i] for i in range(3)]
            cross = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
            # Counter-clockwise seen from the lit side.
            if sum(cross[i] * normal[i] for i in range(3)) > 0:
                indices += [base, base + 1, base + 2, base, base + 2, base + 3]
            else:
                indices += [base, base + 2, base + 1, base, base + 3, base + 2]
        lo = [min(p[i] for p in positions) for i in range(3)]
        hi = [max(p[i] for p in positions) for i in range(3)]
        accessors.append({"bufferView": view(b"".join(struct.pack("<3f", *p) for p in positions), 34962),
                          "componentType": 5126, "count": len(positions), "type": "VEC3", "min": lo, "max": hi})
        accessors.append({"bufferView": view(b"".join(struct.pack("<3f", *n) for n in normals), 34962),
                          "componentType": 5126, "count": len(normals), "type": "VEC3"})
        accessors.append({"bufferView": view(b"".join(struct.pack("<I", i) for i in indices), 34963),
                          "componentType": 5125, "count": len(indices), "type": "SCALAR"})
        primitives.append({"attributes": {"POSITION": len(accessors) - 3, "NORMAL": len(accessors) - 2},
                           "indices": len(accessors) - 1, "material": material})

    def matte(rgb: list[float]) -> dict:
        return {"pbrMetallicRoughness": {"baseColorFactor": rgb + [1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}

    gltf = {
        "asset": {"version": "2.0", "generator": "tests/tools/room_gltf.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 1500.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0, "name": "room"},
                  {"name": "lamp", "translation": [2.8, 2.4, 1.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                  {"name": "camera", "camera": 0, "translation": [2.0, 1.5, 3.9]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.05, "aspectRatio": 1.0}}],
        "meshes": [{"primitives": primitives}],
        "materials": [matte([0.7, 0.7, 0.7]), matte([0.7, 0.1, 0.1]), matte([0.1, 0.7, 0.1])],
        "buffers": [{"byteLength": len(buffer),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buffer)).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    with open(sys.argv[1], "w") as out:
        json.dump(gltf, out)


if __name__ == "__main__":
    main()

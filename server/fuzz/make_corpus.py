#!/usr/bin/env python3
"""Writes the seed corpus of bounce_request_fuzz: python3 server/fuzz/make_corpus.py [DIR].

Each file is a byte stream as a client would send it (docs/protocol.md, "Frames"): a frame of every
request type, scene.load with small .glb uploads (built here), a stream of several requests, a few
broken ones, and the scene-state orders (object.set_transform, light.set, light.remove, camera.set)
with numbers at the edges of their ranges and past them (1e39, -0, 1e400, NaN and Infinity, which
JSON does not allow, and "NaN" as a string), on the scenes the target starts with and on uploads
far from the origin. DIR defaults to server/fuzz/corpus; its files are replaced.
"""
import json
import pathlib
import struct
import sys
import zlib

MAGIC = b"BNCE"
TYPES = {"hello": 1, "ping": 6, "cancel": 8, "scene.load": 16, "scene.unload": 17, "scene.list": 18,
         "scene.describe": 19, "object.set_transform": 20, "light.set": 21, "light.remove": 22,
         "camera.set": 23, "render": 24, "stream.start": 25, "bake": 27, "stats": 28}


def frame(kind, body=None, attachment=b"", request_id=1, version=1):
    text = json.dumps(body, separators=(",", ":")).encode() if body else b""
    header = MAGIC + struct.pack("<HHQII", version, TYPES[kind], request_id, len(text), len(attachment))
    return header + text + attachment


def raw_frame(kind, text, request_id=1):
    """A frame whose body is `text` as given: numbers JSON cannot carry (NaN, Infinity, 1e400)."""
    header = MAGIC + struct.pack("<HHQII", 1, TYPES[kind], request_id, len(text), 0)
    return header + text


def stream(requests):
    """Several frames in one input: (kind, body[, attachment]) each, numbered from 1."""
    return b"".join(frame(kind, body, *rest, request_id=number)
                    for number, (kind, body, *rest) in enumerate(requests, start=1))


def padded(data, fill):
    return data + fill * (-len(data) % 4)


def glb(document, binary):
    text = padded(json.dumps(document, separators=(",", ":")).encode(), b" ")
    binary = padded(binary, b"\0")
    chunks = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(binary), b"BIN\0") + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def png(width, height, rgba):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    rows = b"".join(b"\0" + rgba[y * width * 4:(y + 1) * width * 4] for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def triangle_glb():
    """One triangle: positions and 16-bit indices only, so normals and tangents are generated."""
    positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    indices = padded(struct.pack("<3H", 0, 1, 2), b"\0")
    document = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(positions) + len(indices)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(positions)},
                        {"buffer": 0, "byteOffset": len(positions), "byteLength": 6}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"name": "tri", "mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    return glb(document, positions + indices)


def far_triangle_glb(coordinate, node_matrix=None):
    """One triangle at +-`coordinate` (finite floats at the edge of their range), optionally under a
    node matrix of its own, with a camera placed by another node: what object.set_transform, light.set
    and camera.set then do to an imported scene far from the origin."""
    positions = struct.pack("<9f", -coordinate, -coordinate, 0, coordinate, 0, 0, 0, coordinate, coordinate)
    node = {"name": "far", "mesh": 0}
    if node_matrix is not None:
        node["matrix"] = node_matrix
    document = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(positions)}],
        "bufferViews": [{"buffer": 0, "byteLength": len(positions)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": coordinate}}],
        "nodes": [node, {"name": "eye", "camera": 0, "translation": [0, 0, min(coordinate, 1e6)]}],
        "scenes": [{"nodes": [0, 1]}],
    }
    return glb(document, positions)


def textured_glb():
    """A quad with normals, UVs, a 2x2 PNG base colour, an emissive material, a light and a camera."""
    positions = struct.pack("<12f", -1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0)
    normals = struct.pack("<12f", *([0, 0, 1] * 4))
    uvs = struct.pack("<8f", 0, 1, 1, 1, 1, 0, 0, 0)
    indices = struct.pack("<6I", 0, 1, 2, 0, 2, 3)
    image = padded(png(2, 2, bytes([255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255])), b"\0")
    parts = [positions, normals, uvs, indices, image]
    views, offset = [], 0
    for part in parts:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(part)})
        offset += len(part)
    document = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "key", "type": "spot", "color": [1, 0.9, 0.8], "intensity": 20,
             "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}}]}},
        "buffers": [{"byteLength": offset}],
        "bufferViews": views,
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [-1, -1, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
                      {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
                      {"bufferView": 3, "componentType": 5125, "count": 6, "type": "SCALAR"}],
        "images": [{"bufferView": 4, "mimeType": "image/png"}],
        "samplers": [{}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [{"name": "lit", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                              "metallicFactor": 0, "roughnessFactor": 0.5},
                       "emissiveFactor": [0.1, 0.1, 0.1],
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2}}}],
        "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                                    "indices": 3, "material": 0}]}],
        "cameras": [{"name": "view", "type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
        "nodes": [{"name": "quad", "mesh": 0, "children": [1]},
                  {"name": "spot", "translation": [0, 0, 3], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                  {"name": "eye", "camera": 0, "translation": [0, 0, 4], "rotation": [0, 0, 0, 1]}],
        "scenes": [{"nodes": [0, 2]}],
        "scene": 0,
    }
    return glb(document, b"".join(parts))


def corpus():
    tri, textured = triangle_glb(), textured_glb()
    render = {"scene": "cornell", "method": "direct", "preset": "low", "knobs": {"shadow_map_size": 256},
              "width": 64, "height": 48, "format": "jpeg", "exposure": 0.5, "tone": "reinhard",
              "jpeg_quality": 80, "camera": "default", "min_scene_version": 1, "timeout_ms": 5000}
    files = {
        "hello": frame("hello", {"client": "bounce/0.1", "protocol": 1, "token": "secret"}),
        "ping": frame("ping"),
        "cancel": frame("cancel", {"id": 7}),
        "stats": frame("stats"),
        "stream_start": frame("stream.start", {"scene": "s"}),
        "load_builtin": frame("scene.load", {"name": "cornell", "builtin": "cornell", "dynamic": ["tall_block"]}),
        "load_path": frame("scene.load", {"name": "s", "path": "scenes/room.gltf"}),
        "load_triangle": frame("scene.load", {"name": "tri"}, tri),
        "load_textured": frame("scene.load", {"name": "quad", "dynamic": ["quad"]}, textured),
        "unload": frame("scene.unload", {"name": "s"}),
        "list": frame("scene.list"),
        "describe": frame("scene.describe", {"name": "cornell"}),
        "transform_matrix": frame("object.set_transform", {
            "scene": "cornell", "object": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.1, 0, 0, 1]}),
        "transform_trs": frame("object.set_transform", {"scene": "cornell", "object": "tall_block",
                                                        "translation": [0.1, 0, -0.2], "rotation_deg": [0, 45, 0],
                                                        "scale": 1.5}),
        "light_spot": frame("light.set", {"scene": "cornell", "light": "key", "type": "spot", "position": [0, 1.9, 0],
                                          "direction": [0, -1, 0], "color": [1, 1, 1], "intensity": 10,
                                          "inner_cone_deg": 20, "outer_cone_deg": 40}),
        "light_directional": frame("light.set", {"scene": "cornell", "light": "sun", "type": "directional",
                                                 "direction": [0.3, -1, 0.2]}),
        "light_remove": frame("light.remove", {"scene": "cornell", "light": "key"}),
        "camera_look_at": frame("camera.set", {"scene": "cornell", "position": [0, 1, 3.5], "look_at": [0, 1, 0],
                                               "fov_deg": 40}),
        "camera_orientation": frame("camera.set", {"scene": "cornell", "orientation": [0, 0.38, 0, 0.92]}),
        "camera_named": frame("camera.set", {"scene": "quad", "camera": "view"}),
        "render_direct": frame("render", render),
        "render_reference": frame("render", {"scene": "cornell", "method": "reference", "preset": "draft",
                                             "knobs": {"spp": 4, "bounces": 2, "seed": 9}, "width": 32,
                                             "height": 32, "format": "exr", "exr_half": True}),
        "render_vct": frame("render", {"scene": "cornell", "method": "vct", "preset": "medium",
                                       "knobs": {"resolution": 64, "aperture": 30.5, "dense": 1}}),
        "render_isr": frame("render", {"scene": "cornell", "method": "isr", "knobs": {"mode": 2, "tau": 0.5}}),
        "bake_cssm": frame("bake", {"scene": "cornell", "method": "cssm", "preset": "draft",
                                    "knobs": {"face_size": 16, "bounces": 2, "traversal": 1}}),
        "session": b"".join(frame(kind, body, attachment, request_id) for request_id, (kind, body, attachment) in
                            enumerate([("hello", {"client": "bounce/0.1", "protocol": 1}, b""),
                                       ("scene.load", {"name": "tri"}, tri),
                                       ("light.set", {"scene": "tri", "light": "l", "position": [0, 0, 2]}, b""),
                                       ("render", {"scene": "tri", "width": 16, "height": 16}, b""),
                                       ("scene.unload", {"name": "tri"}, b"")], start=1)),
        # Refused requests: each takes a path to an error reply.
        "bad_render_size": frame("render", {"scene": "cornell", "width": 16384, "height": 16384}),
        "bad_knob": frame("render", {"scene": "cornell", "knobs": {"shadow_map_size": 3.5}}),
        "bad_bake_cpu": frame("bake", {"scene": "cornell", "method": "reference"}),
        "bad_light_cone": frame("light.set", {"scene": "cornell", "light": "l", "inner_cone_deg": 120}),
        "bad_transform": frame("object.set_transform", {"scene": "cornell", "object": -1, "scale": 0}),
        "bad_upload": frame("scene.load", {"name": "broken"}, tri[:40] + b"\xff" * 16 + tri[56:]),
        "bad_json": MAGIC + struct.pack("<HHQII", 1, TYPES["render"], 5, 9, 0) + b'{"scene":',
        "bad_version": frame("hello", {"client": "x"}, version=9),
        "bad_magic": b"BNCF" + frame("ping")[4:],
        "truncated": frame("scene.load", {"name": "tri"}, tri)[:-20],
    }
    files.update(scene_state_seeds(tri, textured))
    return files


def scene_state_seeds(tri, textured):
    """The scene-state orders at the edges of their ranges and past them, on the built-in scenes the
    target starts with ("cornell", "crowded": one light short of the cap) and on uploads."""
    big, angle, colour = 1e7, 1e6, 1e6  # docs/protocol.md, "Numbers"
    extreme_matrix = [big, -big, big, 0, -big, big, big, 0, big, big, -big, 0, big, -big, big, 1]
    return {
        "state_matrix_extreme": frame("object.set_transform", {"scene": "cornell", "object": 0,
                                                               "matrix": extreme_matrix}),
        "state_matrix_negative_zero": frame("object.set_transform", {"scene": "cornell", "object": "tall_block",
                                                                     "matrix": [-0.0] * 16}),
        "state_trs_extreme": frame("object.set_transform", {"scene": "cornell", "object": "short_block",
                                                            "translation": [big, -big, big],
                                                            "rotation_deg": [angle, -angle, 0.5], "scale": 1e6}),
        "state_trs_tiny": frame("object.set_transform", {"scene": "cornell", "object": 1, "scale": 1e-6,
                                                         "translation": [-0.0, 1e-30, -1e-30]}),
        "state_transform_1e39": frame("object.set_transform", {"scene": "cornell", "object": 0,
                                                               "matrix": [1e39] + [0.0] * 15}),
        "state_transform_nan_string": frame("object.set_transform", {"scene": "cornell", "object": 0,
                                                                     "scale": "NaN"}),
        "state_transform_nan": raw_frame("object.set_transform",
                                         b'{"scene":"cornell","object":0,"translation":[NaN,0,0]}'),
        "state_transform_infinity": raw_frame("object.set_transform",
                                              b'{"scene":"cornell","object":0,"scale":Infinity}'),
        "state_transform_1e400": raw_frame("object.set_transform",
                                           b'{"scene":"cornell","object":0,"scale":1e400}'),
        "state_light_extreme": frame("light.set", {"scene": "cornell", "light": "far", "type": "spot",
                                                   "position": [big, big, -big], "direction": [1e-6, -big, 0],
                                                   "color": [colour] * 3, "intensity": 1e12,
                                                   "inner_cone_deg": 90, "outer_cone_deg": 90}),
        "state_light_point_negative_zero": frame("light.set", {"scene": "cornell", "light": "ceiling_light",
                                                               "position": [-0.0, -0.0, -0.0], "intensity": 0,
                                                               "color": [-0.0, 0, 0]}),
        "state_light_tiny_direction": frame("light.set", {"scene": "cornell", "light": "sun",
                                                          "type": "directional", "direction": [1e-20, 0, 0]}),
        "state_light_cap": stream([("light.set", {"scene": "crowded", "light": "one_more"}),
                                   ("light.set", {"scene": "crowded", "light": "past_the_cap"}),
                                   ("light.remove", {"scene": "crowded", "light": "extra_5"}),
                                   ("light.set", {"scene": "crowded", "light": "past_the_cap"})]),
        "state_camera_extreme": frame("camera.set", {"scene": "cornell", "position": [big, big, big],
                                                     "look_at": [-big, -big, -big], "fov_deg": 178.9}),
        "state_camera_close": frame("camera.set", {"scene": "cornell", "position": [0, 1, 1],
                                                   "look_at": [0, 1, 1.000001], "fov_deg": 0.11}),
        "state_camera_down": frame("camera.set", {"scene": "cornell", "position": [0, big, 0],
                                                  "look_at": [0, -big, 0]}),
        "state_camera_orientation": frame("camera.set", {"scene": "cornell",
                                                         "orientation": [1e-7, 0, -0.0, 2e-6]}),
        "state_camera_same_point": frame("camera.set", {"scene": "cornell", "position": [1, 1, 1],
                                                        "look_at": [1, 1, 1]}),
        "state_unloaded": stream([("scene.unload", {"name": "cornell"}),
                                  ("light.set", {"scene": "cornell", "light": "l"}),
                                  ("scene.load", {"name": "cornell", "builtin": "cornell_blob",
                                                  "dynamic": ["blob"]}),
                                  ("object.set_transform", {"scene": "cornell", "object": 1, "scale": 1e6,
                                                            "translation": [big, big, big]}),
                                  ("camera.set", {"scene": "cornell", "position": [-big, 0, 0]})]),
        "state_upload_session": stream([("scene.load", {"name": "quad", "dynamic": ["quad"]}, textured),
                                        ("object.set_transform", {"scene": "quad", "object": "quad",
                                                                  "matrix": extreme_matrix}),
                                        ("light.set", {"scene": "quad", "light": "key", "position": [big, 0, 0],
                                                       "intensity": 1e12}),
                                        ("camera.set", {"scene": "quad", "camera": "view"}),
                                        ("camera.set", {"scene": "quad", "position": [0, 0, -big], "fov_deg": 179}),
                                        ("light.remove", {"scene": "quad", "light": "key"}),
                                        ("scene.load", {"name": "tri"}, tri),
                                        ("object.set_transform", {"scene": "tri", "object": 0, "scale": 1e6,
                                                                  "rotation_deg": [90, 90, 90]})]),
        "state_far_upload": stream([("scene.load", {"name": "far"}, far_triangle_glb(3e38)),
                                    ("object.set_transform", {"scene": "far", "object": "far", "scale": 1e6})]),
        "state_far_scaled": stream([("scene.load", {"name": "far"}, far_triangle_glb(1e14)),
                                    ("object.set_transform", {"scene": "far", "object": "far", "scale": 1e6}),
                                    ("object.set_transform", {"scene": "far", "object": 0,
                                                              "matrix": extreme_matrix}),
                                    ("object.set_transform", {"scene": "far", "object": 0, "scale": 1e3}),
                                    ("light.set", {"scene": "far", "light": "l", "position": [-big, 0, big]}),
                                    ("camera.set", {"scene": "far", "position": [big, big, big],
                                                    "look_at": [0, 0, 0]})]),
        "state_small_and_far": stream([("scene.load", {"name": "small"}, far_triangle_glb(1e-3)),
                                       ("object.set_transform", {"scene": "small", "object": 0,
                                                                 "translation": [big, big, -big]}),
                                       ("light.set", {"scene": "small", "light": "sun", "type": "directional",
                                                      "direction": [0.2, -1, 0.3]})]),
        "state_empty_scene": stream([("scene.load", {"name": "empty"},
                                      glb({"asset": {"version": "2.0"}, "scenes": [{"nodes": []}], "scene": 0}, b"")),
                                     ("light.set", {"scene": "empty", "light": "l", "type": "spot",
                                                    "position": [0, 0, 2]}),
                                     ("camera.set", {"scene": "empty", "position": [big, 0, 0],
                                                     "look_at": [0, 0, 0]})]),
        "state_far_node": stream([("scene.load", {"name": "far"},
                                   far_triangle_glb(1e6, [1e30, 0, 0, 0, 0, 1e30, 0, 0, 0, 0, 1e30, 0, 0, 0, 0, 1])),
                                  ("camera.set", {"scene": "far", "position": [big, 0, 0]})]),
    }


def main():
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path(__file__).parent / "corpus"
    out.mkdir(parents=True, exist_ok=True)
    for old in out.iterdir():
        old.unlink()
    for name, data in sorted(corpus().items()):
        (out / name).write_bytes(data)


if __name__ == "__main__":
    main()

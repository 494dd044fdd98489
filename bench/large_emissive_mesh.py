#!/usr/bin/env python3
"""Writes a large glTF scene whose every triangle emits by a texture: a wavy grid of
2 * N * N triangles (N = 700: 980,000) under one material with base colour, metallic-roughness,
normal, emissive and occlusion textures (2048 x 2048 checkers, UVs tiled 8 times), and renders it
with `photond render` at 512 x 512, preset `final`, printing the passes' seconds
(README.md, "Large scenes"). Standard library only.

    python3 bench/large_emissive_mesh.py --photond build/server/photond [--n 700] [--out DIR]
"""
import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import zlib


def checker_png(path, size, colour_a, colour_b, tile=64):
    """An RGB checkerboard PNG of size x size pixels, tiles of `tile` pixels."""
    def chunk(kind, payload):
        return (struct.pack(">I", len(payload)) + kind + payload +
                struct.pack(">I", zlib.crc32(kind + payload) & 0xffffffff))
    rows = []
    for parity in (0, 1):
        row = bytearray()
        for x in range(size):
            row += bytes(colour_b if ((x // tile) + parity) % 2 else colour_a)
        rows.append(b"\0" + bytes(row))
    raw = b"".join(rows[(y // tile) % 2] for y in range(size))
    ihdr = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) +
                chunk(b"IEND", b""))


def write_scene(out, n):
    positions, uvs, indices = [], [], []
    for j in range(n + 1):
        for i in range(n + 1):
            x, z = i / n * 10 - 5, j / n * 10 - 5
            positions += [x, 0.2 * math.sin(3 * x) * math.cos(3 * z), z]
            uvs += [i / n * 8, j / n * 8]
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            indices += [a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2]
    p = struct.pack("<%df" % len(positions), *positions)
    t = struct.pack("<%df" % len(uvs), *uvs)
    ix = struct.pack("<%dI" % len(indices), *indices)
    with open(os.path.join(out, "mesh.bin"), "wb") as f:
        f.write(p + t + ix)
    images = []
    for k in range(5):
        checker_png(os.path.join(out, "t%d.png" % k), 2048, (50 + 30 * k, 100, 150), (200, 200 - 20 * k, 80))
        images.append({"uri": "t%d.png" % k})
    doc = {
        "asset": {"version": "2.0", "generator": "photond bench/large_emissive_mesh.py"},
        "buffers": [{"byteLength": len(p) + len(t) + len(ix), "uri": "mesh.bin"}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(p)},
                        {"buffer": 0, "byteOffset": len(p), "byteLength": len(t)},
                        {"buffer": 0, "byteOffset": len(p) + len(t), "byteLength": len(ix)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(positions) // 3, "type": "VEC3",
                       "min": [-5, -0.2, -5], "max": [5, 0.2, 5]},
                      {"bufferView": 1, "componentType": 5126, "count": len(uvs) // 2, "type": "VEC2"},
                      {"bufferView": 2, "componentType": 5125, "count": len(indices), "type": "SCALAR"}],
        "images": images,
        "textures": [{"source": k} for k in range(5)],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                "metallicRoughnessTexture": {"index": 1}, "metallicFactor": 0.2},
                       "normalTexture": {"index": 2}, "emissiveTexture": {"index": 3},
                       "emissiveFactor": [0.01, 0.01, 0.01], "occlusionTexture": {"index": 4}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    path = os.path.join(out, "large_emissive_mesh.gltf")
    with open(path, "w") as f:
        json.dump(doc, f)
    return path, len(indices) // 3


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photond", default="build/server/photond")
    parser.add_argument("--n", type=int, default=700, help="grid side in quads")
    parser.add_argument("--out", help="directory for the scene (default: a temporary one)")
    args = parser.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="photond-emissive-mesh-")
    os.makedirs(out, exist_ok=True)
    path, triangles = write_scene(out, args.n)
    print("%s: %d triangles" % (path, triangles), flush=True)
    result = subprocess.run([args.photond, "render", path, "--width", "512", "--height", "512",
                             "--preset", "final", "-o", os.path.join(out, "render.exr")],
                            capture_output=True, text=True)
    sys.stdout.write(result.stderr)
    return result.returncode


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Writes the hand-made glTF test files of tests/scene/gltf_loader_test.cpp.

Standard library only. The generated files are committed; rerun this script (from any directory)
only when a test file has to change, and keep the expected values in the test in step.
"""
import base64
import json
import math
import os
import shutil
import struct
import subprocess
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))

FLOAT, U8, U16, U32 = 5126, 5121, 5123, 5125


class Builder:
    """Accumulates one binary buffer, its bufferViews and accessors, and the rest of the JSON."""

    def __init__(self):
        self.data = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "photond tests/data/gltf/generate.py"},
                    "bufferViews": [], "accessors": []}

    def view(self, payload, stride=None):
        while len(self.data) % 4:
            self.data.append(0)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(payload)}
        if stride:
            view["byteStride"] = stride
        self.data += payload
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, view, component_type, count, type_, byte_offset=0, normalized=False,
                 **extra):
        acc = {"bufferView": view, "componentType": component_type, "count": count, "type": type_}
        if byte_offset:
            acc["byteOffset"] = byte_offset
        if normalized:
            acc["normalized"] = True
        acc.update(extra)
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def floats(self, values, type_, count=None):
        n = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[type_]
        v = self.view(struct.pack("<%df" % len(values), *values))
        return self.accessor(v, FLOAT, count if count is not None else len(values) // n, type_)

    def indices(self, values, component_type):
        fmt = {U8: "B", U16: "H", U32: "I"}[component_type]
        v = self.view(struct.pack("<%d%s" % (len(values), fmt), *values))
        return self.accessor(v, component_type, len(values), "SCALAR")

    def finish(self, uri=None):
        while len(self.data) % 4:
            self.data.append(0)
        if uri is None:
            uri = "data:application/octet-stream;base64," + base64.b64encode(self.data).decode()
        self.doc["buffers"] = [{"byteLength": len(self.data), "uri": uri}]
        return self.doc

    def glb(self):
        doc = dict(self.doc)
        while len(self.data) % 4:
            self.data.append(0)
        doc["buffers"] = [{"byteLength": len(self.data)}]
        js = json.dumps(doc, separators=(",", ":")).encode()
        js += b" " * ((4 - len(js) % 4) % 4)
        total = 12 + 8 + len(js) + 8 + len(self.data)
        return (struct.pack("<4sII", b"glTF", 2, total) +
                struct.pack("<I4s", len(js), b"JSON") + js +
                struct.pack("<I4s", len(self.data), b"BIN\0") + bytes(self.data))


def write(name, doc):
    path = os.path.join(HERE, name)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def png(width, height, rows, bit_depth=8):
    """rows: list of rows of (r, g, b) tuples; RGB colour type."""
    def chunk(kind, payload):
        return (struct.pack(">I", len(payload)) + kind + payload +
                struct.pack(">I", zlib.crc32(kind + payload) & 0xffffffff))
    fmt = ">%d%s" % (width * 3, "B" if bit_depth == 8 else "H")
    raw = b"".join(b"\0" + struct.pack(fmt, *[c for px in row for c in px]) for row in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) +
            chunk(b"IEND", b""))


def png_rgba(width, height, rows):
    """rows: list of rows of (r, g, b, a) tuples, 8 bits; RGBA colour type."""
    def chunk(kind, payload):
        return (struct.pack(">I", len(payload)) + kind + payload +
                struct.pack(">I", zlib.crc32(kind + payload) & 0xffffffff))
    raw = b"".join(b"\0" + bytes(c for px in row for c in px) for row in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) +
            chunk(b"IEND", b""))


def png_data_uri(data):
    return "data:image/png;base64," + base64.b64encode(data).decode()


QUAD_POSITIONS = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0]
QUAD_INDICES = [0, 1, 2, 0, 2, 3]
QUAD_UVS = [0, 0, 1, 0, 1, 1, 0, 1]


def single_mesh_scene(b, primitives, mesh_name="Mesh"):
    b.doc["meshes"] = [{"name": mesh_name, "primitives": primitives}]
    b.doc["nodes"] = [{"name": "Node", "mesh": 0}]
    b.doc["scenes"] = [{"nodes": [0]}]
    b.doc["scene"] = 0


def quad_indexed(index_type):
    """A unit quad in z = 0 facing +Z, two triangles, indices of the given width."""
    b = Builder()
    if index_type == U16:
        # Interleaved POSITION + NORMAL, byteStride 24, NORMAL at byteOffset 12.
        inter = []
        for i in range(4):
            inter += QUAD_POSITIONS[3 * i:3 * i + 3] + [0, 0, 1]
        v = b.view(struct.pack("<24f", *inter), stride=24)
        pos = b.accessor(v, FLOAT, 4, "VEC3", min=[0, 0, 0], max=[1, 1, 0])
        nrm = b.accessor(v, FLOAT, 4, "VEC3", byte_offset=12)
    else:
        pos = b.floats(QUAD_POSITIONS, "VEC3")
        nrm = b.floats([0, 0, 1] * 4, "VEC3")
    if index_type == U8:  # UNSIGNED_BYTE normalized texture coordinates
        uv_view = b.view(bytes(int(c * 255) for c in QUAD_UVS))
        uv = b.accessor(uv_view, U8, 4, "VEC2", normalized=True)
    elif index_type == U32:  # UNSIGNED_SHORT normalized texture coordinates
        uv_view = b.view(struct.pack("<8H", *[int(c * 65535) for c in QUAD_UVS]))
        uv = b.accessor(uv_view, U16, 4, "VEC2", normalized=True)
    else:
        uv = b.floats(QUAD_UVS, "VEC2")
    idx = b.indices(QUAD_INDICES, index_type)
    single_mesh_scene(b, [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv},
                           "indices": idx, "mode": 4}], "Quad")
    return b


def quad_non_indexed():
    b = Builder()
    flat = []
    for i in QUAD_INDICES:
        flat += QUAD_POSITIONS[3 * i:3 * i + 3]
    pos = b.floats(flat, "VEC3")
    nrm = b.floats([0, 0, 1] * 6, "VEC3")
    single_mesh_scene(b, [{"attributes": {"POSITION": pos, "NORMAL": nrm}}], "Quad")
    return b


def strip_and_fan():
    # Strip: zig-zag of 5 vertices -> 3 triangles, all facing +Z (non-indexed).
    b = Builder()
    strip = [0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 2, 0]
    pos = b.floats(strip, "VEC3")
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}, "mode": 5}], "Strip")
    write("strip.gltf", b.finish())
    # Fan: centre plus 4 rim vertices -> 3 triangles facing +Z (indexed, u16).
    b = Builder()
    fan = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 1, 0]
    pos = b.floats(fan, "VEC3")
    idx = b.indices([0, 1, 2, 3, 4], U16)
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}, "indices": idx, "mode": 6}], "Fan")
    write("fan.gltf", b.finish())


def triangle(b, with_normals=True):
    pos = b.floats([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3")
    attrs = {"POSITION": pos}
    if with_normals:
        attrs["NORMAL"] = b.floats([0, 0, 1] * 3, "VEC3")
    return attrs


def hierarchy():
    """Scene 1 (the default) instances one triangle three times through TRS and matrix nodes."""
    b = Builder()
    b.doc["meshes"] = [{"name": "Tri", "primitives": [{"attributes": triangle(b)}]}]
    s = math.sqrt(0.5)
    b.doc["nodes"] = [
        # 0: TRS parent: translate (10,0,0), rotate 90 deg about +Z, uniform scale 2.
        {"name": "Parent", "translation": [10, 0, 0], "rotation": [0, 0, s, s], "scale": [2, 2, 2],
         "mesh": 0, "children": [1]},
        # 1: matrix child: translate (0,0,5) (column-major).
        {"name": "Child", "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1], "mesh": 0},
        # 2: a root with a matrix only: translate (0,-3,0).
        {"name": "Other", "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -3, 0, 1], "mesh": 0},
        # 3: only in scene 0, which is not the default scene.
        {"name": "NotInDefaultScene", "translation": [100, 100, 100], "mesh": 0},
    ]
    b.doc["scenes"] = [{"name": "Unused", "nodes": [3]}, {"name": "Main", "nodes": [0, 2]}]
    b.doc["scene"] = 1
    write("hierarchy.gltf", b.finish())


def negative_scale():
    b = Builder()
    b.doc["meshes"] = [{"name": "Mirrored", "primitives": [{"attributes": triangle(b)},
                                                            {"attributes": triangle(b, False)}]}]
    b.doc["nodes"] = [{"name": "Mirror", "scale": [-1, 1, 1], "mesh": 0}]
    b.doc["scenes"] = [{"nodes": [0]}]
    write("negative_scale.gltf", b.finish())


def flat_normals():
    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    idx = b.indices(QUAD_INDICES, U16)
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}, "indices": idx}], "NoNormals")
    write("flat_normals.gltf", b.finish())


def camera():
    b = Builder()
    b.doc["meshes"] = [{"name": "Tri", "primitives": [{"attributes": triangle(b)}]}]
    s = math.sqrt(0.5)
    b.doc["cameras"] = [
        {"name": "Persp", "type": "perspective",
         "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1, "zfar": 100}},
        {"name": "Ortho", "type": "orthographic",
         "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 100}},
    ]
    b.doc["nodes"] = [
        {"name": "Geometry", "mesh": 0},
        # Rotation of 90 deg about +Y: the camera's -Z axis becomes world -X.
        {"name": "CameraNode", "translation": [1, 2, 3], "rotation": [0, s, 0, s], "camera": 0},
        {"name": "OrthoNode", "camera": 1},
    ]
    b.doc["scenes"] = [{"nodes": [0, 1, 2]}]
    write("camera.gltf", b.finish())


def lights():
    b = Builder()
    b.doc["meshes"] = [{"name": "Tri", "primitives": [{"attributes": triangle(b)}]}]
    s = math.sqrt(0.5)
    b.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    b.doc["extensionsRequired"] = ["KHR_lights_punctual"]
    b.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "Bulb", "type": "point", "color": [1, 0.5, 0.25], "intensity": 10},
        {"name": "Spot", "type": "spot", "intensity": 2,
         "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
        {"name": "Sun", "type": "directional", "color": [1, 1, 1], "intensity": 3},
    ]}}
    b.doc["nodes"] = [
        {"name": "Geometry", "mesh": 0},
        {"name": "BulbNode", "translation": [0, 5, 0],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        # -90 deg about +X: the light's -Z axis points down (-Y).
        {"name": "SpotNode", "translation": [1, 2, 3], "rotation": [-s, 0, 0, s],
         "extensions": {"KHR_lights_punctual": {"light": 1}}},
        # +90 deg about +Y: the light travels along -X.
        {"name": "SunNode", "rotation": [0, s, 0, s],
         "extensions": {"KHR_lights_punctual": {"light": 2}}},
    ]
    b.doc["scenes"] = [{"nodes": [0, 1, 2, 3]}]
    write("lights.gltf", b.finish())


def materials():
    b = Builder()
    exts = ["KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior",
            "KHR_materials_specular"]
    b.doc["extensionsUsed"] = exts
    b.doc["extensionsRequired"] = ["KHR_materials_ior"]
    b.doc["materials"] = [
        {"name": "Everything",
         "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 0.125, 0.5], "metallicFactor": 0.3,
                                  "roughnessFactor": 0.7},
         "emissiveFactor": [1, 0.5, 0.25], "doubleSided": True,
         "extensions": {
             "KHR_materials_emissive_strength": {"emissiveStrength": 4},
             "KHR_materials_transmission": {"transmissionFactor": 0.9},
             "KHR_materials_ior": {"ior": 1.33},
             "KHR_materials_specular": {"specularFactor": 0.6,
                                        "specularColorFactor": [0.9, 0.8, 0.7]},
         }},
        {"name": "Bare"},
    ]
    prims = [{"attributes": triangle(b), "material": 0},
             {"attributes": triangle(b)},  # no material: the glTF default material
             {"attributes": triangle(b), "material": 1}]
    b.doc["meshes"] = [{"name": "Tris", "primitives": prims}]
    b.doc["nodes"] = [{"mesh": 0}]
    b.doc["scenes"] = [{"nodes": [0]}]
    write("materials.gltf", b.finish())


TEXTURE_ROWS = [[(255, 0, 0), (0, 128, 0)], [(0, 0, 64), (188, 188, 188)]]


def textured_quad(b, image):
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    uv = b.floats(QUAD_UVS, "VEC2")
    idx = b.indices(QUAD_INDICES, U16)
    b.doc["images"] = [image]
    b.doc["textures"] = [{"source": 0}]
    b.doc["materials"] = [{"name": "Textured", "pbrMetallicRoughness": {
        "baseColorFactor": [0.5, 1, 1, 1], "baseColorTexture": {"index": 0}}}]
    single_mesh_scene(b, [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "indices": idx,
                           "material": 0}], "TexturedQuad")


def textures():
    b = Builder()
    data = png(2, 2, TEXTURE_ROWS)
    textured_quad(b, {"name": "checker", "uri": png_data_uri(data)})
    write("texture.gltf", b.finish())
    # 16-bit: 32768 / 65535 in every channel of the first texel.
    b = Builder()
    rows16 = [[(32768, 32768, 32768), (65535, 0, 0)], [(0, 65535, 0), (0, 0, 65535)]]
    data = png(2, 2, rows16, bit_depth=16)
    textured_quad(b, {"name": "deep", "uri": png_data_uri(data)})
    write("texture16.gltf", b.finish())
    # GLB: the same textured quad, the PNG stored in a bufferView of the binary chunk.
    b = Builder()
    image_view = b.view(png(2, 2, TEXTURE_ROWS))
    textured_quad(b, {"name": "checker", "bufferView": image_view, "mimeType": "image/png"})
    glb = b.glb()
    with open(os.path.join(HERE, "textured_quad.glb"), "wb") as f:
        f.write(glb)
    with open(os.path.join(HERE, "broken", "truncated.glb"), "wb") as f:
        f.write(glb[:len(glb) // 2])


def material_textures():
    """The rest of the glTF material on the unit quad (tests/scene/material_textures_test.cpp)."""
    # metallicRoughnessTexture: G roughness, B metallic, stored linearly (not sRGB); R, A unused.
    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    nrm = b.floats([0, 0, 1] * 4, "VEC3")
    uv = b.floats(QUAD_UVS, "VEC2")
    idx = b.indices(QUAD_INDICES, U16)
    rows = [[(0, 51, 255, 255), (0, 255, 0, 255)], [(0, 128, 64, 255), (0, 0, 255, 255)]]
    b.doc["images"] = [{"uri": png_data_uri(png_rgba(2, 2, rows))}]
    b.doc["samplers"] = [{"magFilter": 9728}]  # NEAREST
    b.doc["textures"] = [{"source": 0, "sampler": 0}]
    b.doc["materials"] = [{"name": "MR", "pbrMetallicRoughness": {
        "metallicFactor": 1.0, "roughnessFactor": 0.5,
        "metallicRoughnessTexture": {"index": 0}}}]
    single_mesh_scene(b, [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv},
                           "indices": idx, "material": 0}], "MetalRoughQuad")
    write("metallic_roughness.gltf", b.finish())
    # KHR_materials_transmission's transmissionTexture: R multiplies transmissionFactor 0.8, stored
    # linearly; left texel clear (R 255), right texel opaque (R 0); smooth, on an open quad.
    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    nrm = b.floats([0, 0, 1] * 4, "VEC3")
    uv = b.floats(QUAD_UVS, "VEC2")
    idx = b.indices(QUAD_INDICES, U16)
    b.doc["extensionsUsed"] = ["KHR_materials_transmission"]
    b.doc["images"] = [{"uri": png_data_uri(png_rgba(2, 1, [[(255, 0, 0, 255), (0, 255, 255, 255)]]))}]
    b.doc["samplers"] = [{"magFilter": 9728}]  # NEAREST
    b.doc["textures"] = [{"source": 0, "sampler": 0}]
    b.doc["materials"] = [{"name": "PartlyClear", "pbrMetallicRoughness": {
        "baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8,
                                                      "transmissionTexture": {"index": 0}}}}]
    single_mesh_scene(b, [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv},
                           "indices": idx, "material": 0}], "PartlyClearQuad")
    write("transmission_texture.gltf", b.finish())
    # KHR_materials_specular's textures: specularTexture's A multiplies specularFactor (left texel
    # 255, right 0), specularColorTexture's RGB (sRGB) specularColorFactor (left red, right white);
    # a smooth plastic of base colour 0.5 on an open quad.
    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    nrm = b.floats([0, 0, 1] * 4, "VEC3")
    uv = b.floats(QUAD_UVS, "VEC2")
    idx = b.indices(QUAD_INDICES, U16)
    b.doc["extensionsUsed"] = ["KHR_materials_specular"]
    b.doc["images"] = [{"uri": png_data_uri(png_rgba(2, 1, [[(0, 0, 0, 255), (0, 0, 0, 0)]]))},
                       {"uri": png_data_uri(png_rgba(2, 1, [[(255, 0, 0, 255), (255, 255, 255, 255)]]))}]
    b.doc["samplers"] = [{"magFilter": 9728}]  # NEAREST
    b.doc["textures"] = [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}]
    b.doc["materials"] = [{"name": "SpecularMapped", "pbrMetallicRoughness": {
        "baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_specular": {"specularTexture": {"index": 0},
                                                  "specularColorTexture": {"index": 1}}}}]
    single_mesh_scene(b, [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv},
                           "indices": idx, "material": 0}], "SpecularQuad")
    write("specular_texture.gltf", b.finish())

    # KHR_texture_transform (required) on a 2x2 colour texture; the second material reads
    # TEXCOORD_1 through the extension's texCoord override, with CLAMP_TO_EDGE / MIRRORED_REPEAT.
    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    uv0 = b.floats(QUAD_UVS, "VEC2")
    uv1 = b.floats([0.5 * c for c in QUAD_UVS], "VEC2")
    idx = b.indices(QUAD_INDICES, U16)
    b.doc["images"] = [{"uri": png_data_uri(png(2, 2, [[(255, 0, 0), (0, 255, 0)],
                                                      [(0, 0, 255), (255, 255, 255)]]))}]
    b.doc["samplers"] = [{"magFilter": 9728, "wrapS": 33071, "wrapT": 33648}]
    b.doc["textures"] = [{"source": 0, "sampler": 0}]
    b.doc["extensionsUsed"] = ["KHR_texture_transform"]
    b.doc["extensionsRequired"] = ["KHR_texture_transform"]
    b.doc["materials"] = [
        {"name": "Offset", "pbrMetallicRoughness": {"baseColorTexture": {
            "index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.0]}}}}},
        {"name": "RotateScaleSet1", "pbrMetallicRoughness": {"baseColorTexture": {
            "index": 0, "extensions": {"KHR_texture_transform": {
                "rotation": math.pi / 2, "scale": [2.0, 1.0], "texCoord": 1}}},
            "metallicRoughnessTexture": {"index": 0, "texCoord": 0}}}]
    attrs = {"POSITION": pos, "TEXCOORD_0": uv0, "TEXCOORD_1": uv1}
    single_mesh_scene(b, [{"attributes": attrs, "indices": idx, "material": 0},
                          {"attributes": attrs, "indices": idx, "material": 1}], "Transformed")
    write("texture_transform.gltf", b.finish())

    # Alpha: MASK with cutoff 0.3 (factor alpha x texture alpha x COLOR_0 alpha), BLEND, and
    # a normal texture on a quad whose right half mirrors its UVs (no TANGENT: generated).
    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    nrm = b.floats([0, 0, 1] * 4, "VEC3")
    uv = b.floats(QUAD_UVS, "VEC2")
    col = b.view(struct.pack("<16B", *([255, 255, 255, 255] * 2 + [255, 255, 255, 128] * 2)))
    colors = b.accessor(col, U8, 4, "VEC4", normalized=True)
    idx = b.indices(QUAD_INDICES, U16)
    b.doc["images"] = [{"uri": png_data_uri(png_rgba(2, 1, [[(255, 255, 255, 255),
                                                             (255, 255, 255, 102)]]))},
                       {"uri": png_data_uri(png(1, 1, [[(128, 200, 200)]]))}]
    b.doc["textures"] = [{"source": 0}, {"source": 1}]
    b.doc["materials"] = [
        {"name": "Mask", "alphaMode": "MASK", "alphaCutoff": 0.3, "pbrMetallicRoughness": {
            "baseColorFactor": [1, 1, 1, 0.9], "baseColorTexture": {"index": 0}}},
        {"name": "Blend", "alphaMode": "BLEND", "pbrMetallicRoughness": {
            "baseColorFactor": [1, 1, 1, 0.25]}},
        {"name": "Normal", "normalTexture": {"index": 1, "scale": 0.5}}]
    # Two quads side by side for the normal map: x in [0, 1] with u = x, x in [1, 2] with u = 2 - x.
    npos = b.floats([0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 0, 0, 2, 0, 0, 2, 1, 0, 1, 1, 0], "VEC3")
    nnrm = b.floats([0, 0, 1] * 8, "VEC3")
    nuv = b.floats([0, 1, 1, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 0, 1, 0], "VEC2")
    nidx = b.indices([0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7], U16)
    b.doc["meshes"] = [
        {"name": "Alpha", "primitives": [
            {"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv, "COLOR_0": colors},
             "indices": idx, "material": 0},
            {"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": 1}]},
        {"name": "Mirrored", "primitives": [
            {"attributes": {"POSITION": npos, "NORMAL": nnrm, "TEXCOORD_0": nuv},
             "indices": nidx, "material": 2}]}]
    b.doc["nodes"] = [{"name": "AlphaNode", "mesh": 0},
                      {"name": "MirroredNode", "mesh": 1, "translation": [0, 0, 5]}]
    b.doc["scenes"] = [{"nodes": [0, 1]}]
    b.doc["scene"] = 0
    write("alpha_normal.gltf", b.finish())

    # KHR_materials_clearcoat (factor, roughness, a transformed clearcoatTexture) and
    # KHR_materials_volume (attenuation inside a transmissive solid), both required.
    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    uv = b.floats(QUAD_UVS, "VEC2")
    idx = b.indices(QUAD_INDICES, U16)
    b.doc["images"] = [{"uri": png_data_uri(png(1, 1, [[(128, 64, 255)]]))}]
    b.doc["textures"] = [{"source": 0}]
    b.doc["extensionsUsed"] = ["KHR_materials_clearcoat", "KHR_materials_volume",
                               "KHR_materials_transmission", "KHR_texture_transform"]
    b.doc["extensionsRequired"] = ["KHR_materials_clearcoat", "KHR_materials_volume"]
    b.doc["materials"] = [
        {"name": "Coated", "extensions": {"KHR_materials_clearcoat": {
            "clearcoatFactor": 0.7, "clearcoatRoughnessFactor": 0.2,
            "clearcoatTexture": {"index": 0, "extensions": {
                "KHR_texture_transform": {"scale": [2, 2]}}}}}},
        {"name": "Tinted glass", "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_volume": {"thicknessFactor": 0.1, "attenuationDistance": 2.0,
                                     "attenuationColor": [0.5, 0.25, 1.0]}}},
        {"name": "Opaque with volume", "extensions": {
            "KHR_materials_volume": {"attenuationDistance": 2.0, "attenuationColor": [0.5, 0.5, 0.5]}}}]
    attrs = {"POSITION": pos, "TEXCOORD_0": uv}
    single_mesh_scene(b, [{"attributes": attrs, "indices": idx, "material": k} for k in range(3)],
                      "CoatVolume")
    write("coat_volume.gltf", b.finish())


def sparse():
    """Quad whose vertex 2 is moved to (2, 2, 0) by a sparse substitution."""
    b = Builder()
    base = b.view(struct.pack("<12f", *QUAD_POSITIONS))
    sparse_idx = b.view(struct.pack("<H", 2))
    sparse_val = b.view(struct.pack("<3f", 2, 2, 0))
    pos = b.accessor(base, FLOAT, 4, "VEC3", sparse={
        "count": 1, "indices": {"bufferView": sparse_idx, "componentType": U16},
        "values": {"bufferView": sparse_val}})
    idx = b.indices(QUAD_INDICES, U8)
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}, "indices": idx}], "SparseQuad")
    write("sparse.gltf", b.finish())


def broken():
    with open(os.path.join(HERE, "broken", "invalid_json.gltf"), "w") as f:
        f.write('{"asset": {"version": "2.0"}, "meshes": [ {"primitives": [\n')

    b = quad_indexed(U16)
    write("broken/missing_buffer.gltf", b.finish(uri="does_not_exist.bin"))

    # POSITION claims 100 elements in a 48-byte bufferView.
    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3", count=100)
    idx = b.indices(QUAD_INDICES, U16)
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}, "indices": idx}], "TooLong")
    write("broken/accessor_out_of_bounds.gltf", b.finish())

    b = Builder()
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    idx = b.indices([0, 1, 2, 0, 2, 7], U16)
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}, "indices": idx}], "BadIndex")
    write("broken/index_out_of_range.gltf", b.finish())

    b = Builder()
    pos = b.floats([0, 0, 0, 1, 0, 0, 0, float("nan"), 0], "VEC3")
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}}], "Chair")
    write("broken/nan_position.gltf", b.finish())

    # The referenced file exists (tests/data/gltf/broken/outside.bin) but lies above the bundle.
    b = Builder()
    pos = b.floats([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3")
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}}], "Escape")
    data = bytes(b.data)
    write("broken/traversal/traversal.gltf", b.finish(uri="../outside.bin"))
    with open(os.path.join(HERE, "broken", "outside.bin"), "wb") as f:
        f.write(data)

    b = Builder()
    pos = b.floats([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3")
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}}], "Absolute")
    write("broken/absolute_uri.gltf", b.finish(uri="/etc/passwd"))

    b = quad_indexed(U8)
    b.doc["extensionsUsed"] = ["KHR_texture_basisu"]
    b.doc["extensionsRequired"] = ["KHR_texture_basisu"]
    write("broken/unsupported_extension.gltf", b.finish())

    b = Builder()
    pos = b.floats([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3")
    single_mesh_scene(b, [{"attributes": {"POSITION": pos}, "mode": 0},
                          {"attributes": {"POSITION": pos}, "mode": 1}], "PointsAndLines")
    write("broken/no_triangles.gltf", b.finish())

    b = Builder()
    b.doc["meshes"] = [{"name": "Tri", "primitives": [{"attributes": triangle(b)}]}]
    b.doc["nodes"] = [{"name": "A", "mesh": 0, "children": [1]}, {"name": "B", "children": [0]}]
    b.doc["scenes"] = [{"nodes": [0]}]
    write("broken/cycle.gltf", b.finish())

    b = Builder()
    pos = b.floats([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3")
    nrm = b.floats([0, 0, 0, 0, 0, 0], "VEC2")
    single_mesh_scene(b, [{"attributes": {"POSITION": pos, "NORMAL": nrm}}], "Vec2Normals")
    write("broken/wrong_normal_type.gltf", b.finish())

    # A self-contained-looking file whose buffer is external: refused by load_gltf_memory.
    b = quad_non_indexed()
    write("broken/external_buffer.gltf", b.finish(uri="external_buffer.bin"))
    with open(os.path.join(HERE, "broken", "external_buffer.bin"), "wb") as f:
        f.write(bytes(b.data))


def icosphere(subdivisions):
    """Unit icosphere: (positions, triangles), counter-clockwise seen from outside."""
    t = (1 + math.sqrt(5)) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
             (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(subdivisions):
        cache = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = [(verts[a][k] + verts[b][k]) / 2 for k in range(3)]
                n = math.sqrt(sum(x * x for x in m))
                verts.append(tuple(x / n for x in m))
                cache[key] = len(verts) - 1
            return cache[key]
        new_faces = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            new_faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new_faces
    return verts, faces


def box_mesh():
    """Unit cube [-0.5, 0.5]^3 with flat normals: 24 vertices, 12 triangles facing out."""
    positions, normals, indices = [], [], []
    for axis in range(3):
        for sign in (-1, 1):
            n = [0, 0, 0]
            n[axis] = sign
            u, v = [(axis + 1) % 3, (axis + 2) % 3]
            base = len(positions)
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0, 0, 0]
                p[axis] = 0.5 * sign
                p[u] = 0.5 * du
                p[v] = 0.5 * dv
                positions.append(p)
                normals.append(n)
            quad = [0, 1, 2, 0, 2, 3] if sign > 0 else [0, 2, 1, 0, 3, 2]
            indices += [base + i for i in quad]
    return positions, normals, indices


def mesh_primitive(b, positions, normals, indices, material, uvs=None):
    pos = b.floats([c for p in positions for c in p], "VEC3")
    lo = [min(p[k] for p in positions) for k in range(3)]
    hi = [max(p[k] for p in positions) for k in range(3)]
    b.doc["accessors"][pos]["min"] = lo
    b.doc["accessors"][pos]["max"] = hi
    attrs = {"POSITION": pos, "NORMAL": b.floats([c for n in normals for c in n], "VEC3")}
    if uvs is not None:
        attrs["TEXCOORD_0"] = b.floats([c for uv in uvs for c in uv], "VEC2")
    idx = b.indices(indices, U16)
    return {"attributes": attrs, "indices": idx, "material": material}


def floor_and_wall(b, floor_uvs=None):
    """The floor (8 x 7) and back wall (8 x 4) of the lit test rooms, material 0."""
    quad = [[-4, 0, -3], [4, 0, -3], [4, 0, 4], [-4, 0, 4]]
    floor = mesh_primitive(b, quad, [[0, 1, 0]] * 4, [0, 2, 1, 0, 3, 2], 0, uvs=floor_uvs)
    wall_quad = [[-4, 0, -3], [4, 0, -3], [4, 4, -3], [-4, 4, -3]]
    wall = mesh_primitive(b, wall_quad, [[0, 0, 1]] * 4, [0, 1, 2, 0, 2, 3], 0)
    return floor, wall


def bulb_and_view(b):
    """The lit test rooms' point light and camera (light 0, camera 0); returns their nodes."""
    b.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "Bulb", "type": "point", "color": [1, 0.95, 0.9], "intensity": 8000}]}}
    b.doc["cameras"] = [{"name": "View", "type": "perspective",
                         "perspective": {"yfov": 0.8, "znear": 0.05}}]
    return [
        {"name": "LightNode", "translation": [0.5, 2.6, 1.5],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        # Looking down 0.3 rad from (0, 1.6, 4.5).
        {"name": "CameraNode", "camera": 0, "translation": [0, 1.6, 4.5],
         "rotation": [-math.sin(0.15), 0, 0, math.cos(0.15)]},
    ]


def room():
    """A lit test scene for the mesh-compression tests: a floor, a back wall, a smooth sphere and a
    turned, scaled box under a point light, with a camera. gltfpack writes its quantized and
    meshopt-compressed copies (tests/scene/gltf_compression_test.cpp)."""
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    b.doc["materials"] = [
        {"name": "Floor", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1],
                                                    "metallicFactor": 0}},
        {"name": "Red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.15, 1],
                                                  "metallicFactor": 0, "roughnessFactor": 0.5}},
        {"name": "Blue", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.3, 0.8, 1],
                                                   "metallicFactor": 0}},
    ]
    floor, wall = floor_and_wall(b, floor_uvs=[[0, 0], [1, 0], [1, 1], [0, 1]])
    verts, faces = icosphere(2)
    sphere = mesh_primitive(b, verts, verts, [i for f in faces for i in f], 1)
    bp, bn, bi = box_mesh()
    box = mesh_primitive(b, bp, bn, bi, 2)
    b.doc["meshes"] = [{"name": "Floor", "primitives": [floor, wall]},
                       {"name": "Sphere", "primitives": [sphere]},
                       {"name": "Box", "primitives": [box]}]
    light_node, camera_node = bulb_and_view(b)
    s = math.sin(0.3)
    c = math.cos(0.3)
    b.doc["nodes"] = [
        {"name": "FloorNode", "mesh": 0},
        {"name": "SphereNode", "mesh": 1, "translation": [-0.4, 0.7, 0], "scale": [0.7, 0.7, 0.7]},
        {"name": "BoxNode", "mesh": 2, "translation": [1.1, 0.35, -0.3],
         "rotation": [0, s, 0, c], "scale": [0.7, 0.7, 0.9]},
        light_node, camera_node,
    ]
    b.doc["scenes"] = [{"nodes": [0, 1, 2, 3, 4]}]
    b.doc["scene"] = 0
    write("compression/room.gltf", b.finish())
    gltfpack = shutil.which("gltfpack")
    if not gltfpack:
        print("gltfpack not found (Debian package gltfpack): compressed copies not rewritten")
        return
    source = os.path.join(HERE, "compression", "room.gltf")
    for name, flags in (("room_quantized.glb", []), ("room_meshopt.glb", ["-cc"]),
                        ("room_meshopt_float.glb", ["-cc", "-noq"])):
        subprocess.run([gltfpack, "-i", source, "-o", os.path.join(HERE, "compression", name),
                        "-kn", "-km"] + flags, check=True, stdout=subprocess.DEVNULL)


def camera_indexing():
    """cameras[0] is placed by no node, cameras[1] by two, cameras[2] is orthographic."""
    b = Builder()
    b.doc["meshes"] = [{"name": "Tri", "primitives": [{"attributes": triangle(b)}]}]
    b.doc["cameras"] = [
        {"name": "Unplaced", "type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}},
        {"name": "Shared", "type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1}},
        {"name": "Ortho", "type": "orthographic",
         "orthographic": {"xmag": 2, "ymag": 1, "znear": 0.1, "zfar": 100}},
    ]
    b.doc["nodes"] = [
        {"name": "Geometry", "mesh": 0},
        {"name": "OrthoNode", "translation": [0.25, 0.25, 4], "camera": 2},
        {"name": "SharedFirst", "translation": [0, 0, 5], "camera": 1},
        {"name": "SharedSecond", "translation": [9, 9, 9], "camera": 1},
    ]
    b.doc["scenes"] = [{"nodes": [0, 1, 2, 3]}]
    write("camera_indexing.gltf", b.finish())


def quantized():
    """KHR_mesh_quantization: SHORT positions dequantized by the node's scale and translation,
    normalized BYTE normals, UNSIGNED_BYTE (not normalized) texture coordinates."""
    def build(declared):
        b = Builder()
        if declared:
            b.doc["extensionsUsed"] = ["KHR_mesh_quantization"]
            b.doc["extensionsRequired"] = ["KHR_mesh_quantization"]
        # 6-byte elements at a stride of 8, which keeps vertex attributes 4-byte aligned.
        pos_view = b.view(b"".join(struct.pack("<3hxx", *p) for p in
                                   [(0, 0, 0), (1000, 0, 0), (1000, 1000, 0), (0, 1000, 0)]),
                          stride=8)
        pos = b.accessor(pos_view, 5122, 4, "VEC3", min=[0, 0, 0], max=[1000, 1000, 0])
        nrm_view = b.view(struct.pack("<16b", *([0, 0, 127, 0] * 4)), stride=4)
        nrm = b.accessor(nrm_view, 5120, 4, "VEC3", normalized=True)
        uv = b.accessor(b.view(bytes([0, 0, 2, 0, 2, 2, 0, 2])), U8, 4, "VEC2")
        idx = b.indices(QUAD_INDICES, U16)
        b.doc["meshes"] = [{"name": "QuantizedQuad", "primitives": [
            {"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}, "indices": idx}]}]
        b.doc["nodes"] = [{"name": "Dequantize", "mesh": 0, "translation": [1, 0, 0],
                           "scale": [0.002, 0.002, 0.002]}]
        b.doc["scenes"] = [{"nodes": [0]}]
        return b.finish()
    write("quantized.gltf", build(True))
    write("broken/quantized_undeclared.gltf", build(False))


def warnings_file():
    """Features the loader ignores, each of which must come back as a warning."""
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_sheen",
                               "KHR_materials_iridescence", "KHR_materials_anisotropy",
                               "KHR_materials_clearcoat", "KHR_materials_specular"]
    data = png(2, 2, TEXTURE_ROWS)
    b.doc["images"] = [{"uri": png_data_uri(data)}]
    b.doc["samplers"] = [{"wrapS": 33071, "wrapT": 33071}]
    b.doc["textures"] = [{"source": 0, "sampler": 0}]
    b.doc["materials"] = [
        {"name": "Velvet", "normalTexture": {"index": 0}, "alphaMode": "MASK",
         "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
         "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [1, 1, 1]},
                        "KHR_materials_iridescence": {"iridescenceFactor": 1},
                        "KHR_materials_anisotropy": {"anisotropyStrength": 0.5}}},
        {"name": "Lacquer", "extensions": {
            "KHR_materials_clearcoat": {"clearcoatFactor": 1, "clearcoatNormalTexture": {"index": 0}},
            "KHR_materials_specular": {"specularTexture": {"index": 0},
                                       "specularColorTexture": {"index": 0}}}}]
    attrs = triangle(b)
    attrs["COLOR_0"] = b.floats([1, 0, 0, 0, 1, 0, 0, 0, 1], "VEC3")
    b.doc["meshes"] = [{"name": "Tri", "primitives": [{"attributes": attrs, "material": 0},
                                                      {"attributes": triangle(b), "mode": 1},
                                                      {"attributes": triangle(b), "material": 1}]}]
    b.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "Ranged", "type": "point", "intensity": 100, "range": 5}]}}
    b.doc["cameras"] = [{"name": "Nowhere", "type": "perspective",
                         "perspective": {"yfov": 0.5, "znear": 0.1}}]
    b.doc["nodes"] = [{"name": "Geometry", "mesh": 0},
                      {"name": "Light", "translation": [0, 0, 2],
                       "extensions": {"KHR_lights_punctual": {"light": 0}}}]
    b.doc["scenes"] = [{"nodes": [0, 1]}]
    write("warnings.gltf", b.finish())


def transmission():
    """KHR_materials_transmission surfaces as solids or thin walls: a closed glass box and an open
    glass pane without KHR_materials_volume (the box is solid glass, worth a warning; the pane a
    thin wall), a box split into two primitives of one material (closed together: solid), and an
    open pane with KHR_materials_volume of thicknessFactor 0 (the specification's thin wall: its
    attenuation has no inside to act in)."""
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_materials_transmission", "KHR_materials_volume"]
    glass = {"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "roughnessFactor": 0},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}}
    thin_volume = {"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "roughnessFactor": 0},
                   "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                                  "KHR_materials_volume": {"thicknessFactor": 0, "attenuationDistance": 1,
                                                           "attenuationColor": [0.5, 0.5, 0.5]}}}
    b.doc["materials"] = [dict(glass, name="BoxGlass"), dict(glass, name="PaneGlass"),
                          dict(glass, name="SplitGlass"), dict(thin_volume, name="ThinVolumePane")]
    bp, bn, bi = box_mesh()
    box = mesh_primitive(b, bp, bn, bi, 0)
    pane = mesh_primitive(b, [[0, 0, 2], [1, 0, 2], [1, 1, 2], [0, 1, 2]], [[0, 0, 1]] * 4,
                          QUAD_INDICES, 1)
    moved = [[x + 3, y, z] for x, y, z in bp]
    # The second half ends with a triangle of a repeated corner (no area), which must not open it.
    halves = [mesh_primitive(b, moved, bn, bi[:18], 2),
              mesh_primitive(b, moved, bn, bi[18:] + [bi[18], bi[18], bi[19]], 2)]
    thin_pane = mesh_primitive(b, [[0, 0, 4], [1, 0, 4], [1, 1, 4], [0, 1, 4]], [[0, 0, 1]] * 4,
                               QUAD_INDICES, 3)
    b.doc["meshes"] = [{"name": "GlassBox", "primitives": [box]},
                       {"name": "GlassPane", "primitives": [pane]},
                       {"name": "SplitBox", "primitives": halves},
                       {"name": "ThinVolumePane", "primitives": [thin_pane]}]
    b.doc["nodes"] = [{"mesh": 0}, {"mesh": 1}, {"mesh": 2}, {"mesh": 3}]
    b.doc["scenes"] = [{"nodes": [0, 1, 2, 3]}]
    write("transmission.gltf", b.finish())


def blender_lights():
    """What Blender's glTF exporter (io_scene_gltf2, lighting mode "Standard") writes for a point
    lamp of 1000 W and a sun of 3 W/m^2: intensity = W / (4 pi) * 683 cd and 3 * 683 lx, next to a
    quad emitting with strength 2 (emissiveFactor 1 x KHR_materials_emissive_strength 2, written
    unchanged). The quad faces +Z and lights nothing the test measures; the floor is pure
    Lambertian (KHR_materials_specular 0, no specular layer) so that its radiance is rho E / pi."""
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                               "KHR_materials_specular"]
    b.doc["materials"] = [
        {"name": "White", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1],
                                                    "metallicFactor": 0},
         "extensions": {"KHR_materials_specular": {"specularFactor": 0}}},
        {"name": "Emitter", "emissiveFactor": [1, 1, 1],
         "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2}}},
    ]
    floor = mesh_primitive(b, [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]], [[0, 1, 0]] * 4,
                           [0, 2, 1, 0, 3, 2], 0)
    emitter = mesh_primitive(b, [[1, 0.5, 0], [2, 0.5, 0], [2, 1.5, 0], [1, 1.5, 0]],
                             [[0, 0, 1]] * 4, QUAD_INDICES, 1)
    b.doc["meshes"] = [{"name": "Floor", "primitives": [floor]},
                       {"name": "Emitter", "primitives": [emitter]}]
    b.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "Point", "type": "point", "color": [1, 1, 1],
         "intensity": 1000 / (4 * math.pi) * 683},
        {"name": "Sun", "type": "directional", "color": [1, 1, 1], "intensity": 3 * 683}]}}
    b.doc["nodes"] = [
        {"name": "Floor", "mesh": 0},
        {"name": "Emitter", "mesh": 1},
        {"name": "Point", "translation": [-1, 2, 0],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        # Pointing straight down (-Y).
        {"name": "Sun", "rotation": [-math.sqrt(0.5), 0, 0, math.sqrt(0.5)],
         "extensions": {"KHR_lights_punctual": {"light": 1}}},
    ]
    b.doc["scenes"] = [{"nodes": [0, 1, 2, 3]}]
    write("blender_lights.gltf", b.finish())


def point_light_over_floor(name, mirror_reflectance, add_primitives):
    """A point light of 683 cd 1 above a wide grey floor (material 0), a mirror material
    (material 1) and the primitives `add_primitives(b)` returns, seen by one camera."""
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    b.doc["materials"] = [
        {"name": "Floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
                                                    "metallicFactor": 0}},
        {"name": "Mirror", "pbrMetallicRoughness": {"baseColorFactor": [mirror_reflectance] * 3 + [1],
                                                     "metallicFactor": 1, "roughnessFactor": 0}}]
    floor = mesh_primitive(b, [[-10, 0, -10], [10, 0, -10], [10, 0, 10], [-10, 0, 10]],
                           [[0, 1, 0]] * 4, [0, 2, 1, 0, 3, 2], 0)
    b.doc["meshes"] = [{"name": "Room", "primitives": [floor] + add_primitives(b)}]
    b.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "Bulb", "type": "point", "intensity": 683}]}}
    b.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}]
    b.doc["nodes"] = [{"mesh": 0}, {"translation": [0.3, 1, 0],
                                    "extensions": {"KHR_lights_punctual": {"light": 0}}},
                      {"camera": 0, "translation": [0, 1.5, 4]}]
    b.doc["scenes"] = [{"nodes": [0, 1, 2]}]
    write(name, b.finish())


def sparse_caustics(tile=0.3):
    """A point light over a wide floor beside a tilted 2 x 2 mirror that sends its light straight
    up, where a small diffuse tile (`tile` wide, facing down, 5 above the mirror) catches about 1
    in 4,700 of the light's photons: the caustic map cannot fill within the emission cap (1,000 per
    requested photon), though its light is worth tracing (over 1e-4 of the global map's). The
    render must report it as a warning. (The light lies inside the mirror's bounding sphere, so
    photons for the caustic map leave by the light's own distribution.)"""
    def mirror_and_tile(b):
        # The mirror: 2 x 2, centred 1 beside the light at (1.3, 1, 0), facing (-1, 1, 0) / sqrt(2):
        # light arriving along +x leaves along +y.
        c, e = 0.7071, 0.7071
        mirror = mesh_primitive(b, [[1.3 - e, 1 - e, -1], [1.3 + e, 1 + e, -1], [1.3 + e, 1 + e, 1],
                                    [1.3 - e, 1 - e, 1]], [[-c, c, 0]] * 4, [0, 2, 1, 0, 3, 2], 1)
        h = tile / 2
        ceiling = mesh_primitive(b, [[1.3 - h, 6, -h], [1.3 + h, 6, -h], [1.3 + h, 6, h],
                                     [1.3 - h, 6, h]], [[0, -1, 0]] * 4, [0, 1, 2, 0, 2, 3], 0)
        return [mirror, ceiling]
    point_light_over_floor("sparse_caustics.gltf", 1, mirror_and_tile)


def faint_caustics(half_side=0.5, reflectance=0.001):
    """A point light over a wide floor and a wide mirror of low reflectance above it: the
    caustic is a thousandth of the light where it lands, so the caustic map is dropped, which the
    plan must say."""
    def mirror(b):
        # A square mirror 1 above the light, facing down.
        h = half_side
        return [mesh_primitive(b, [[-h, 2, -h], [h, 2, -h], [h, 2, h], [-h, 2, h]], [[0, -1, 0]] * 4,
                               [0, 1, 2, 0, 2, 3], 1)]
    point_light_over_floor("faint_caustics.gltf", reflectance, mirror)


def shelf():
    """Six boxes of one mesh and material on their own nodes (turned, scaled, two under a moved
    parent) on a floor under a point light: gltfpack -mi turns them into one node with
    EXT_mesh_gpu_instancing (tests/scene/gltf_compression_test.cpp)."""
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    b.doc["materials"] = [
        {"name": "Floor", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1],
                                                    "metallicFactor": 0}},
        {"name": "Orange", "pbrMetallicRoughness": {"baseColorFactor": [0.85, 0.45, 0.1, 1],
                                                     "metallicFactor": 0, "roughnessFactor": 0.6}},
    ]
    floor, wall = floor_and_wall(b)
    bp, bn, bi = box_mesh()
    b.doc["meshes"] = [{"name": "Floor", "primitives": [floor, wall]},
                       {"name": "Box", "primitives": [mesh_primitive(b, bp, bn, bi, 1)]}]
    light_node, camera_node = bulb_and_view(b)

    def turn(angle):  # about +y
        return [0, math.sin(angle / 2), 0, math.cos(angle / 2)]
    boxes = [
        {"name": "Box0", "mesh": 1, "translation": [-2.0, 0.25, 0], "scale": [0.5, 0.5, 0.5]},
        {"name": "Box1", "mesh": 1, "translation": [-1.0, 0.3, 0.4], "rotation": turn(0.4),
         "scale": [0.6, 0.6, 0.6]},
        {"name": "Box2", "mesh": 1, "translation": [0.0, 0.5, -0.5], "rotation": turn(-0.7),
         "scale": [0.5, 1.0, 0.5]},
        # Equal x and z scales under the turn: with three different ones, gltfpack's instance
        # (its own decomposition of the matrix) came out turned by 1.085 rad and scaled by
        # (0.646, 0.4, 0.763).
        {"name": "Box3", "mesh": 1, "translation": [1.1, 0.2, 0.2], "rotation": turn(1.1),
         "scale": [0.7, 0.4, 0.7]},
        {"name": "Box4", "mesh": 1, "translation": [-0.5, 0, 0], "rotation": turn(0.2),
         "scale": [0.3, 0.3, 0.3]},
        {"name": "Box5", "mesh": 1, "translation": [0.5, 0, 0], "scale": [0.35, 0.35, 0.35]},
    ]
    b.doc["nodes"] = [
        {"name": "FloorNode", "mesh": 0},
        boxes[0], boxes[1], boxes[2], boxes[3],
        # Two more on a lifted, turned board: their parent's transform applies too.
        {"name": "Board", "translation": [1.8, 0.15, 1.2], "rotation": turn(-0.5),
         "children": [6, 7]},
        boxes[4], boxes[5],
        light_node, camera_node,
    ]
    b.doc["scenes"] = [{"nodes": [0, 1, 2, 3, 4, 5, 8, 9]}]
    b.doc["scene"] = 0
    write("compression/shelf.gltf", b.finish())
    gltfpack = shutil.which("gltfpack")
    if not gltfpack:
        print("gltfpack not found (Debian package gltfpack): the instanced copy not rewritten")
        return
    subprocess.run([gltfpack, "-i", os.path.join(HERE, "compression", "shelf.gltf"),
                    "-o", os.path.join(HERE, "compression", "shelf_instanced.glb"), "-mi", "-noq"],
                   check=True, stdout=subprocess.DEVNULL)


def instancing():
    """EXT_mesh_gpu_instancing written by hand: three instances of a triangle under a moved node,
    rotations as normalized SHORT quaternions, a custom _ID attribute (ignored, with a warning);
    instancing_flat.gltf places the same three triangles by nodes alone; broken/ holds two whose
    attributes disagree on the instance count (a placing one, the custom one)."""
    translations = [[0, 0, 0], [2, 0, 0], [0, 3, -1]]
    angles = [0.0, math.pi / 2, -math.pi / 3]  # about +z
    scales = [[1, 1, 1], [0.5, 0.5, 0.5], [1, 2, 1]]

    def quaternion(angle):
        return [0, 0, math.sin(angle / 2), math.cos(angle / 2)]

    def build(instanced, rotation_count=3, id_count=3):
        b = Builder()
        b.doc["meshes"] = [{"name": "Tri", "primitives": [{"attributes": triangle(b)}]}]
        parent = {"name": "Parent", "translation": [1, 1, 0], "scale": [2, 2, 2]}
        if instanced:
            b.doc["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
            b.doc["extensionsRequired"] = ["EXT_mesh_gpu_instancing"]
            t = b.floats([c for v in translations for c in v], "VEC3")
            shorts = [round(c * 32767) for a in angles[:rotation_count] for c in quaternion(a)]
            r = b.accessor(b.view(struct.pack("<%dh" % len(shorts), *shorts)), 5122, rotation_count,
                           "VEC4", normalized=True)
            s = b.floats([c for v in scales for c in v], "VEC3")
            ids = b.floats(list(range(id_count)), "SCALAR")
            parent["mesh"] = 0
            parent["extensions"] = {"EXT_mesh_gpu_instancing": {"attributes": {
                "TRANSLATION": t, "ROTATION": r, "SCALE": s, "_ID": ids}}}
            b.doc["nodes"] = [parent]
        else:
            parent["children"] = [1, 2, 3]
            b.doc["nodes"] = [parent] + [
                {"name": "Instance%d" % i, "mesh": 0, "translation": translations[i],
                 "rotation": quaternion(angles[i]), "scale": scales[i]} for i in range(3)]
        b.doc["scenes"] = [{"nodes": [0]}]
        b.doc["scene"] = 0
        return b.finish()
    write("instancing.gltf", build(True))
    write("instancing_flat.gltf", build(False))
    write("broken/instancing_count_mismatch.gltf", build(True, rotation_count=2))
    write("broken/instancing_id_count_mismatch.gltf", build(True, id_count=2))


def morph_and_skin():
    """Morph targets and a skin with closed-form results (gltf_deformation_test.cpp).

    morph.gltf: a quad with two targets, one of them sparse (moving vertices 2 and 3 up by 1, their
    normals by -0.5 in y), the other moving all four by +x; mesh weights [0.5, 0.25] on node
    Shared, and node Own's weights [1, 0] instead (it is also moved by +5 in x).
    skin.gltf: a strip of three rows bound to joints J0 (bottom row), J0 and J1 half and half
    (middle row) and J1 (top row), and a vertex of no weight; J1 is turned 90 degrees about z
    where the file puts it, a translation of the skinned node (which the skin ignores) and the
    root's translation of 10 in x, which the joints carry. broken/ holds four that are refused."""
    def morph(weights_count=2):
        b = Builder()
        pos = b.floats(QUAD_POSITIONS, "VEC3")
        nrm = b.floats([0, 0, 1] * 4, "VEC3")
        idx = b.indices(QUAD_INDICES, U16)
        sparse_indices = b.view(struct.pack("<2H", 2, 3))
        sparse_values = b.view(struct.pack("<6f", 0, 0, 1, 0, 0, 1))
        up = b.accessor(None, FLOAT, 4, "VEC3", sparse={
            "count": 2, "indices": {"bufferView": sparse_indices, "componentType": U16},
            "values": {"bufferView": sparse_values}})
        del b.doc["accessors"][up]["bufferView"]
        tilt = b.floats([0, 0, 0, 0, 0, 0, 0, -0.5, 0, 0, -0.5, 0], "VEC3")
        right = b.floats([1, 0, 0] * 4, "VEC3")
        b.doc["meshes"] = [{"name": "Quad", "weights": [0.5, 0.25][:weights_count], "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx,
            "targets": [{"POSITION": up, "NORMAL": tilt}, {"POSITION": right}]}]}]
        b.doc["nodes"] = [{"name": "Shared", "mesh": 0},
                          {"name": "Own", "mesh": 0, "weights": [1, 0], "translation": [5, 0, 0]}]
        b.doc["scenes"] = [{"nodes": [0, 1]}]
        return b.finish()
    write("morph.gltf", morph())
    write("broken/morph_weights_count.gltf", morph(weights_count=1))

    def skin(joint=1, bind_matrices=2, weights=True, two_sets=False):
        b = Builder()
        # Three rows of two vertices in the bind pose (x = 10, 10.5; y = 0, 1, 2), and one more.
        positions = [10, 0, 0, 10.5, 0, 0, 10, 1, 0, 10.5, 1, 0, 10, 2, 0, 10.5, 2, 0, 0, 3, 0]
        pos = b.floats(positions, "VEC3")
        nrm = b.floats([1, 0, 0] * 7, "VEC3")
        idx = b.indices([0, 1, 3, 0, 3, 2, 2, 3, 5, 2, 5, 4, 4, 5, 6], U16)
        joints = [0, 0, 0, 0] * 2 + [0, joint, 0, 0] * 2 + [joint, 0, 0, 0] * 2 + [0, 0, 0, 0]
        j = b.accessor(b.view(struct.pack("<28B", *joints)), U8, 7, "VEC4")
        w = b.floats([1, 0, 0, 0] * 2 + [0.5, 0.5, 0, 0] * 2 + [1, 0, 0, 0] * 2 + [0, 0, 0, 0], "VEC4")
        attributes = {"POSITION": pos, "NORMAL": nrm, "JOINTS_0": j}
        if weights:
            attributes["WEIGHTS_0"] = w
        if two_sets:
            # The middle row's second joint from the second set: the same influences.
            attributes["JOINTS_0"] = b.accessor(b.view(struct.pack("<28B", *[0 if k % 4 else joints[k] for k in
                                                                             range(28)])), U8, 7, "VEC4")
            attributes["WEIGHTS_0"] = b.floats([1, 0, 0, 0] * 2 + [0.5, 0, 0, 0] * 2 + [1, 0, 0, 0] * 2 +
                                               [0, 0, 0, 0], "VEC4")
            attributes["JOINTS_1"] = b.accessor(b.view(struct.pack("<28B", *([0] * 8 + [1, 0, 0, 0] * 2 +
                                                                             [0] * 12))), U8, 7, "VEC4")
            attributes["WEIGHTS_1"] = b.floats([0] * 8 + [0.5, 0, 0, 0] * 2 + [0] * 12, "VEC4")
        b.doc["meshes"] = [{"name": "Strip", "primitives": [{"attributes": attributes, "indices": idx}]}]
        # Inverse bind matrices (column-major): J0 bound at (10, 0, 0), J1 at (10, 1, 0).
        ibm = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -10, 0, 0, 1,
               1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -10, -1, 0, 1][:16 * bind_matrices]
        inverse_bind = b.floats(ibm, "MAT4")
        b.doc["skins"] = [{"name": "Rig", "joints": [1, 2], "inverseBindMatrices": inverse_bind}]
        quarter = [0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)]
        b.doc["nodes"] = [{"name": "Root", "translation": [10, 0, 0], "children": [1, 3]},
                          {"name": "J0", "children": [2]},
                          {"name": "J1", "translation": [0, 1, 0], "rotation": quarter},
                          {"name": "Skinned", "mesh": 0, "skin": 0, "translation": [100, 0, 0]}]
        b.doc["scenes"] = [{"nodes": [0]}]
        if two_sets:
            # The mesh placed once more by a node without a skin: drawn unskinned, with a warning.
            b.doc["nodes"].append({"name": "Unskinned", "mesh": 0, "translation": [0, 0, 5]})
            b.doc["scenes"] = [{"nodes": [0, 4]}]
        return b.finish()
    write("skin.gltf", skin())
    write("skin_two_sets.gltf", skin(two_sets=True))
    write("broken/skin_joint_out_of_range.gltf", skin(joint=2))
    write("broken/skin_inverse_bind_count.gltf", skin(bind_matrices=1))
    write("broken/skin_joints_without_weights.gltf", skin(weights=False))

    # A normal-mapped quad without NORMAL (flat: unwelded for its tangents), lifted by a morph
    # target of quantized displacements (normalized SHORT, KHR_mesh_quantization) at weight 1,
    # then turned 90 degrees about z and raised by 3 in y by its one joint.
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_mesh_quantization"]
    b.doc["extensionsRequired"] = ["KHR_mesh_quantization"]
    b.doc["images"] = [{"uri": png_data_uri(png(1, 1, [[(128, 128, 255)]]))}]
    b.doc["textures"] = [{"source": 0}]
    b.doc["materials"] = [{"name": "Bumpy", "normalTexture": {"index": 0}}]
    pos = b.floats(QUAD_POSITIONS, "VEC3")
    uv = b.floats(QUAD_UVS, "VEC2")
    idx = b.indices(QUAD_INDICES, U16)
    lift = b.accessor(b.view(struct.pack("<12h", 0, 0, 0, 0, 0, 0, 0, 0, 32767, 0, 0, 32767)), 5122, 4, "VEC3",
                      normalized=True)
    j = b.accessor(b.view(bytes(16)), U8, 4, "VEC4")
    w = b.floats([1, 0, 0, 0] * 4, "VEC4")
    b.doc["meshes"] = [{"name": "FlatQuad", "weights": [1], "primitives": [{
        "attributes": {"POSITION": pos, "TEXCOORD_0": uv, "JOINTS_0": j, "WEIGHTS_0": w}, "indices": idx,
        "material": 0, "targets": [{"POSITION": lift}]}]}]
    b.doc["skins"] = [{"joints": [1]}]
    b.doc["nodes"] = [{"name": "Quad", "mesh": 0, "skin": 0},
                      {"name": "Joint", "translation": [0, 3, 0],
                       "rotation": [0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)]}]
    b.doc["scenes"] = [{"nodes": [0, 1]}]
    write("morph_skin_flat.gltf", b.finish())

    # A normal-mapped triangle with TANGENT, bound to a joint that mirrors x: the tangent turns
    # with it and its bitangent sign flips.
    b = Builder()
    b.doc["images"] = [{"uri": png_data_uri(png(1, 1, [[(128, 128, 255)]]))}]
    b.doc["textures"] = [{"source": 0}]
    b.doc["materials"] = [{"name": "Bumpy", "normalTexture": {"index": 0}}]
    attrs = triangle(b)
    attrs["TEXCOORD_0"] = b.floats([0, 0, 1, 0, 0, 1], "VEC2")
    attrs["TANGENT"] = b.floats([1, 0, 0, 1] * 3, "VEC4")
    attrs["JOINTS_0"] = b.accessor(b.view(bytes(12)), U8, 3, "VEC4")
    attrs["WEIGHTS_0"] = b.floats([1, 0, 0, 0] * 3, "VEC4")
    b.doc["meshes"] = [{"name": "Tri", "primitives": [{"attributes": attrs, "material": 0}]}]
    b.doc["skins"] = [{"joints": [1]}]
    b.doc["nodes"] = [{"name": "Mirrored", "mesh": 0, "skin": 0}, {"name": "Mirror", "scale": [-1, 1, 1]}]
    b.doc["scenes"] = [{"nodes": [0, 1]}]
    write("skin_mirrored.gltf", b.finish())


def main():
    os.makedirs(os.path.join(HERE, "broken"), exist_ok=True)
    write("indexed_u8.gltf", quad_indexed(U8).finish())
    write("indexed_u16.gltf", quad_indexed(U16).finish())
    write("indexed_u32.gltf", quad_indexed(U32).finish())
    write("non_indexed.gltf", quad_non_indexed().finish())
    strip_and_fan()
    hierarchy()
    negative_scale()
    flat_normals()
    camera()
    lights()
    materials()
    textures()
    material_textures()
    sparse()
    broken()
    camera_indexing()
    quantized()
    warnings_file()
    transmission()
    blender_lights()
    sparse_caustics()
    faint_caustics()
    room()
    shelf()
    instancing()
    morph_and_skin()


if __name__ == "__main__":
    main()

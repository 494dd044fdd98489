"""Renders a glTF file in Blender's Cycles, as another renderer's reference for photond
(bench/cycles_compare.py runs it; this file runs inside Blender):

    blender -b --factory-startup -noaudio -P bench/cycles_render.py -- SCENE.gltf OUT.exr CAMERA.json \
        [--size 256] [--spp 1024] [--seed 1] [--sky 1.0] [--threads 2]

CAMERA.json holds photond's camera in glTF coordinates: {"look_from": [x, y, z], "look_at":
[x, y, z], "up": [x, y, z], "vfov_deg": v}; with {"auto": true} the camera frames the scene's
bounds from +Z (as glTF viewers do) and the file is rewritten with the camera chosen, for photond.
The world is a uniform environment of radiance `--sky` (0: none), photond's default sky. The EXR
holds linear scene radiance (32-bit float, no view transform, no denoising, no clamping), with a
box pixel filter of one pixel as photond's.

Blender's glTF importer (io_import_scene_gltf2) makes the materials (Principled BSDF) and the
lights (KHR_lights_punctual's candela and lux to watts by 683 lm/W, as photond converts them).
"""
import json
import math
import sys

import bpy
import numpy
from mathutils import Vector

# Debian 12's Blender 3.4 importer still uses numpy.bool, which its numpy 1.24 no longer has.
if not hasattr(numpy, "bool"):
    numpy.bool = bool


def script_arguments(usage, positional, options):
    """The arguments after Blender's `--`: `positional` of them, then `--name value` pairs for
    the keys of `options` (the defaults, whose types the values take)."""
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) < positional:
        sys.exit("usage: " + usage)
    options = dict(options)
    rest = argv[positional:]
    for name, value in zip(rest[0::2], rest[1::2]):
        key = name.lstrip("-")
        if key not in options:
            sys.exit(f"unknown option {name}")
        options[key] = type(options[key])(value)
    return argv[:positional], options


def parse_arguments():
    (scene, out, camera), options = script_arguments(
        "blender -b -P cycles_render.py -- SCENE.gltf OUT.exr CAMERA.json [options]", 3,
        {"size": 256, "spp": 1024, "seed": 1, "sky": 1.0, "threads": 2})
    return scene, out, camera, options


def to_blender(v):
    """glTF's +Y up to Blender's +Z up, as the importer converts positions."""
    return Vector((v[0], -v[2], v[1]))


def to_gltf(v):
    return [v[0], v[2], -v[1]]


def scene_bounds():
    lo = Vector((math.inf,) * 3)
    hi = Vector((-math.inf,) * 3)
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH":
            continue
        for corner in obj.bound_box:
            p = obj.matrix_world @ Vector(corner)
            lo = Vector(map(min, lo, p))
            hi = Vector(map(max, hi, p))
    return lo, hi


def configure_cycles(scene, options, out_path):
    """Cycles as the reference: `spp` samples without adaptive sampling, denoising or clamping,
    `bounces` (default 64; 0: direct light only) bounces of every kind, a box pixel filter of one pixel (photond's), `size` x `size`
    pixels, linear radiance into a 32-bit float EXR at `out_path`."""
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = options["spp"]
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.seed = options["seed"]
    bounces = options.get("bounces", 64)
    cycles.max_bounces = bounces
    cycles.diffuse_bounces = bounces
    cycles.glossy_bounces = bounces
    cycles.transmission_bounces = bounces
    cycles.transparent_max_bounces = 64  # alpha-masked texels are seen through, not bounced off
    cycles.volume_bounces = min(bounces, 16)
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.caustics_reflective = True
    cycles.caustics_refractive = True
    cycles.filter_type = "BOX"
    cycles.filter_width = 1.0
    cycles.pixel_filter_type = "BOX"
    scene.render.filter_size = 1.0
    scene.render.threads_mode = "FIXED"
    scene.render.threads = options["threads"]
    scene.render.resolution_x = options["size"]
    scene.render.resolution_y = options["size"]
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    scene.render.filepath = out_path


def main():
    scene_path, out_path, camera_path, options = parse_arguments()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=scene_path)
    scene = bpy.context.scene
    # KHR_lights_punctual's lights are points (and a sun a direction); new Blender lights have a
    # radius of 0.25 m (a sun 0.5 degrees across), which reaches through a lamp's shade.
    for light in bpy.data.lights:
        if light.type in ("POINT", "SPOT"):
            light.shadow_soft_size = 0.0
        elif light.type == "SUN":
            light.angle = 0.0

    with open(camera_path) as f:
        camera = json.load(f)
    if camera.get("auto"):
        lo, hi = scene_bounds()
        centre = to_gltf((lo + hi) / 2)
        radius = (hi - lo).length / 2
        vfov = 40.0
        distance = 1.1 * radius / math.sin(math.radians(vfov) / 2)
        camera = {"look_from": [centre[0], centre[1], centre[2] + distance], "look_at": centre,
                  "up": [0, 1, 0], "vfov_deg": vfov}
        with open(camera_path, "w") as f:
            json.dump(camera, f)
    if camera.get("up", [0, 1, 0]) != [0, 1, 0]:
        sys.exit("only up = [0, 1, 0] is supported")

    data = bpy.data.cameras.new("photond camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(camera["vfov_deg"])
    data.clip_start = 1e-4
    data.clip_end = 1e6
    obj = bpy.data.objects.new("photond camera", data)
    scene.collection.objects.link(obj)
    eye = to_blender(camera["look_from"])
    obj.location = eye
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = (to_blender(camera["look_at"]) - eye).to_track_quat("-Z", "Y")
    scene.camera = obj

    world = bpy.data.worlds.new("photond sky")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = options["sky"]
    scene.world = world

    configure_cycles(scene, options, out_path)
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main()

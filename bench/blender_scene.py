"""Builds a scene in Blender, exports it with Blender's own glTF exporter and renders the original
in Cycles: glTF content written by another tool, with that tool's reference image
(bench/blender_authored.py runs it; this file runs inside Blender):

    blender -b --factory-startup -noaudio -P bench/blender_scene.py -- NAME OUT_DIR \
        [--size 256] [--spp 1024] [--seed 1] [--threads 2] [--materials gltf|principled] [--bounces 64]

Writes OUT_DIR/NAME/NAME.gltf (with its .bin and PNG textures), OUT_DIR/NAME.cycles-MATERIALS.exr
(the Cycles render of the scene as built, not of the exported file: with `gltf`, the default,
its materials rebuilt as the glTF BRDF in Cycles' closures, gltf_materials_in_cycles; with
`principled`, as the exporter read them; with --bounces 0, direct light alone, into
NAME.cycles-MATERIALS-direct.exr) and OUT_DIR/NAME.world.json (the
world's uniform radiance, which glTF cannot carry). Scenes (all sizes in metres):

- window-room: a room lit by a sun (3 W/m^2) and a sky (uniform, bluish) through a window and by
  a 60 W point light; a checkered floor (base-colour texture), a wall with a tangent-space normal
  map (ridges), a leaf-shaped alpha-masked quad (alpha clip), a rough copper sphere and a glossy plastic one.
- lamp-room: a closed room lit by a 100 W point light, a 150 W spot light (60 degree cone, hard
  edge) and an emissive ceiling panel (strength 4); no sky.

The exporter writes the lights photometrically (KHR_lights_punctual: a point or spot light of P W
as P / (4 pi) x 683 cd, a sun of E W/m^2 as E x 683 lux; blender/exp/gltf2_blender_gather_lights.py
of its io_scene_gltf2) and emission strength as KHR_materials_emissive_strength.
"""
import json
import math
import os
import sys

import bpy
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cycles_render import configure_cycles, script_arguments  # noqa: E402


def parse_arguments():
    (name, out_dir), options = script_arguments(
        "blender -b -P blender_scene.py -- NAME OUT_DIR [options]", 2,
        {"size": 256, "spp": 1024, "seed": 1, "threads": 2, "materials": "gltf", "bounces": 64})
    if options["materials"] not in ("gltf", "principled"):
        sys.exit("--materials is gltf or principled")
    return name, out_dir, options


# ---- Textures: generated, saved as PNG files that the exporter copies beside the glTF ----------

def save_image(name, size, texel, directory, non_color=False):
    """An RGBA image of size x size from texel(u, v) -> (r, g, b, a) (display values for colour)."""
    image = bpy.data.images.new(name, size, size, alpha=True)
    pixels = []
    for j in range(size):
        for i in range(size):
            pixels.extend(texel((i + 0.5) / size, (j + 0.5) / size))
    image.pixels = pixels
    image.filepath_raw = os.path.join(directory, name + ".png")
    image.file_format = "PNG"
    image.save()
    if non_color:
        image.colorspace_settings.name = "Non-Color"
    return image


def checker(u, v):
    on = (int(u * 8) + int(v * 8)) % 2 == 0
    return (0.85, 0.82, 0.75, 1.0) if on else (0.25, 0.22, 0.2, 1.0)


# The normal map's steepest slope. Cycles bends a shading normal back towards the surface where
# the view's mirror direction would fall below it (ensure_valid_reflection in its normal-map
# node); photond takes the map's normals as they are. The two agree on moderate slopes like this
# one (-2.3 % on the ridged wall's brightest blocks, direct light); at 45 degrees Cycles' wall
# was 16 % brighter there.
RIDGE_SLOPE_DEG = 20.0


def ridges(u, v):
    """A tangent-space normal map of sinusoidal ridges along v, slopes up to RIDGE_SLOPE_DEG."""
    slope = math.tan(math.radians(RIDGE_SLOPE_DEG)) * math.cos(2 * math.pi * 6 * u)
    n = Vector((-slope, 0.0, 1.0)).normalized()
    return (0.5 * n.x + 0.5, 0.5 * n.y + 0.5, 0.5 * n.z + 0.5, 1.0)


def leaves(u, v):
    """Opaque discs on transparent ground: alpha exactly 0 or 1 away from the edges."""
    centres = [(0.3, 0.3, 0.22), (0.7, 0.35, 0.18), (0.5, 0.72, 0.24)]
    inside = any((u - x) ** 2 + (v - y) ** 2 < r * r for x, y, r in centres)
    return (0.2, 0.6, 0.15, 1.0 if inside else 0.0)


# ---- Objects -----------------------------------------------------------------------------------

def material(name, base=(0.8, 0.8, 0.8), roughness=0.5, metallic=0.0, emission=None, strength=1.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    if emission:
        bsdf.inputs["Emission"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = strength
    return m


def image_node(m, image):
    node = m.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    node.interpolation = "Linear"
    return node


def textured(m, image):
    bsdf = m.node_tree.nodes["Principled BSDF"]
    m.node_tree.links.new(image_node(m, image).outputs["Color"], bsdf.inputs["Base Color"])
    return m


def normal_mapped(m, image):
    bsdf = m.node_tree.nodes["Principled BSDF"]
    normal_map = m.node_tree.nodes.new("ShaderNodeNormalMap")
    m.node_tree.links.new(image_node(m, image).outputs["Color"], normal_map.inputs["Color"])
    m.node_tree.links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])
    return m


def alpha_clipped(m, image):
    bsdf = m.node_tree.nodes["Principled BSDF"]
    node = image_node(m, image)
    m.node_tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    m.node_tree.links.new(node.outputs["Alpha"], bsdf.inputs["Alpha"])
    m.blend_method = "CLIP"  # the exporter's alphaMode MASK
    m.alpha_threshold = 0.5
    return m


def quad(name, centre, size, rotation, mat):
    """A rectangle of size (width, height) in its local XY plane (normal +Z before rotation)."""
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=centre, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = name
    obj.scale = (size[0], size[1], 1.0)
    obj.data.materials.append(mat)
    return obj


def sphere(name, centre, radius, mat):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=radius, location=centre)
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(mat)
    return obj


def box(name, centre, size, mat):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=centre)
    obj = bpy.context.active_object
    obj.name = name
    obj.scale = size
    obj.data.materials.append(mat)
    return obj


def light(kind, name, location, watts, direction=None, **settings):
    data = bpy.data.lights.new(name, kind)
    data.energy = watts
    # glTF's punctual lights are points and directions: no radius, no angle.
    if kind in ("POINT", "SPOT"):
        data.shadow_soft_size = 0.0
    if kind == "SUN":
        data.angle = 0.0
    for key, value in settings.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    if direction is not None:  # a light shines along its local -Z
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Vector(direction).normalized().to_track_quat("-Z", "Y")
    bpy.context.scene.collection.objects.link(obj)
    return obj


def camera(location, target, vfov_deg):
    data = bpy.data.cameras.new("Camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(vfov_deg)
    data.clip_start = 0.01
    obj = bpy.data.objects.new("Camera", data)
    obj.location = location
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y")
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.scene.camera = obj


def room(floor, ceiling, wall, back_wall=None, window=None):
    """Floor, ceiling and four walls of the box [-2, 2] x [-2, 2] x [0, 3], facing inwards. With
    `window` = (y0, y1, z0, z1), the wall at x = -2 has that opening."""
    quad("Floor", (0, 0, 0), (4, 4), (0, 0, 0), floor)
    quad("Ceiling", (0, 0, 3), (4, 4), (math.pi, 0, 0), ceiling)
    quad("BackWall", (0, 2, 1.5), (4, 3), (math.pi / 2, 0, 0), back_wall or wall)
    quad("FrontWall", (0, -2, 1.5), (4, 3), (-math.pi / 2, 0, 0), wall)
    # The side walls' quads are turned about Y: their first extent is along z, the second along y.
    quad("RightWall", (2, 0, 1.5), (3, 4), (0, -math.pi / 2, 0), wall)
    side = (0, math.pi / 2, 0)
    if window is None:
        quad("LeftWall", (-2, 0, 1.5), (3, 4), side, wall)
        return
    y0, y1, z0, z1 = window
    # Around the opening: below, above, and its two sides.
    quad("LeftWallBelow", (-2, 0, z0 / 2), (z0, 4), side, wall)
    quad("LeftWallAbove", (-2, 0, (z1 + 3) / 2), (3 - z1, 4), side, wall)
    quad("LeftWallFront", (-2, (y0 - 2) / 2, (z0 + z1) / 2), (z1 - z0, y0 + 2), side, wall)
    quad("LeftWallBack", (-2, (y1 + 2) / 2, (z0 + z1) / 2), (z1 - z0, 2 - y1), side, wall)


def window_room(directory):
    floor = textured(material("CheckerFloor", roughness=0.6), save_image("checker", 256, checker, directory))
    white = material("WhitePaint", (0.75, 0.75, 0.72), roughness=0.8)
    ridged = normal_mapped(material("RidgedWall", (0.7, 0.68, 0.6), roughness=0.7),
                           save_image("ridges", 256, ridges, directory, non_color=True))
    room(floor, white, white, back_wall=ridged, window=(-1.0, 1.0, 1.0, 2.2))
    leaf = alpha_clipped(material("Leaves", roughness=0.6), save_image("leaves", 256, leaves, directory))
    quad("LeafPanel", (-0.8, 0.9, 1.0), (1.2, 1.2), (math.pi / 2, 0, math.pi / 6), leaf)
    sphere("CopperSphere", (0.4, 0.6, 0.45), 0.45, material("Copper", (0.95, 0.64, 0.54), 0.35, 1.0))
    sphere("BlueSphere", (1.2, -0.3, 0.35), 0.35, material("BluePlastic", (0.1, 0.2, 0.7), 0.2))
    light("SUN", "Sun", (-4, 0, 5), 3.0, direction=(0.75, 0.15, -0.65))
    light("POINT", "CeilingBulb", (1.0, 1.0, 2.6), 60.0)
    camera((1.8, -1.8, 1.6), (-0.6, 0.7, 0.8), 60.0)
    return (0.5, 0.65, 0.9)


def lamp_room(directory):
    floor = textured(material("CheckerFloor", roughness=0.6), save_image("checker", 256, checker, directory))
    white = material("WhitePaint", (0.75, 0.75, 0.72), roughness=0.8)
    room(floor, white, white)
    box("Crate", (0.3, 0.5, 0.4), (0.8, 0.8, 0.8), material("Crate", (0.6, 0.35, 0.2), 0.7))
    panel = material("Panel", (0.0, 0.0, 0.0), 1.0, emission=(1.0, 0.9, 0.8), strength=4.0)
    quad("Panel", (-1.0, -0.5, 2.99), (0.6, 0.6), (math.pi, 0, 0), panel)
    light("POINT", "Bulb", (1.2, -1.0, 2.2), 100.0)
    light("SPOT", "Spot", (-1.5, 1.5, 2.8), 150.0, direction=(0.6, -0.4, -1.0),
          spot_size=math.radians(60), spot_blend=0.0)
    camera((1.8, -1.8, 1.6), (-0.6, 0.7, 0.8), 60.0)
    return (0.0, 0.0, 0.0)


def gltf_materials_in_cycles():
    """Rebuilds every material, after the export, as the glTF 2.0 BRDF in Cycles' own closures,
    with the Fresnel coupling at the view angle: a Lambertian diffuse and a GGX lobe (alpha =
    roughness^2, single scattering) mixed by the dielectric Fresnel of IOR 1.5 at N.V, a GGX metal
    tinted by the base colour, mixed by metallic; emission added; alpha over a transparent
    closure. The Principled BSDF that the exporter reads is Disney's: its diffuse is not
    Lambertian (brighter at grazing angles for rough surfaces) and its specular layer adds to the
    diffuse instead of taking its share: several percent more albedo, which a closed room's
    interreflections multiply. These closures take most of that difference out; what remains of
    it is the coupling (photond's energy-conserving layer reflects about 2 % more than this one
    off a rough white paint: README, "Against another renderer")."""
    for m in bpy.data.materials:
        if not m.use_nodes or "Principled BSDF" not in m.node_tree.nodes:
            continue
        tree = m.node_tree
        bsdf = tree.nodes["Principled BSDF"]
        output = tree.nodes["Material Output"]

        def source(name):
            """The socket feeding input `name`, or None with its value in a constant."""
            socket = bsdf.inputs[name]
            return socket.links[0].from_socket if socket.is_linked else None

        def feed(target, name):
            linked = source(name)
            if linked is not None:
                tree.links.new(linked, target)
            else:
                target.default_value = bsdf.inputs[name].default_value

        normal = source("Normal")
        diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
        feed(diffuse.inputs["Color"], "Base Color")
        diffuse.inputs["Roughness"].default_value = 0.0
        specular = tree.nodes.new("ShaderNodeBsdfGlossy")
        specular.distribution = "GGX"
        specular.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        feed(specular.inputs["Roughness"], "Roughness")
        metal = tree.nodes.new("ShaderNodeBsdfGlossy")
        metal.distribution = "GGX"
        feed(metal.inputs["Color"], "Base Color")
        feed(metal.inputs["Roughness"], "Roughness")
        fresnel = tree.nodes.new("ShaderNodeFresnel")
        fresnel.inputs["IOR"].default_value = 1.5
        if normal is not None:
            for node in (diffuse, specular, metal, fresnel):
                tree.links.new(normal, node.inputs["Normal"])
        dielectric = tree.nodes.new("ShaderNodeMixShader")
        tree.links.new(fresnel.outputs["Fac"], dielectric.inputs["Fac"])
        tree.links.new(diffuse.outputs["BSDF"], dielectric.inputs[1])
        tree.links.new(specular.outputs["BSDF"], dielectric.inputs[2])
        surface = tree.nodes.new("ShaderNodeMixShader")
        feed(surface.inputs["Fac"], "Metallic")
        tree.links.new(dielectric.outputs["Shader"], surface.inputs[1])
        tree.links.new(metal.outputs["BSDF"], surface.inputs[2])
        shader = surface.outputs["Shader"]
        strength = bsdf.inputs["Emission Strength"].default_value
        if strength > 0.0 and any(bsdf.inputs["Emission"].default_value[:3]):
            emission = tree.nodes.new("ShaderNodeEmission")
            feed(emission.inputs["Color"], "Emission")
            emission.inputs["Strength"].default_value = strength
            add = tree.nodes.new("ShaderNodeAddShader")
            tree.links.new(shader, add.inputs[0])
            tree.links.new(emission.outputs["Emission"], add.inputs[1])
            shader = add.outputs["Shader"]
        alpha = source("Alpha")
        if alpha is not None:
            # alphaMode MASK: a texel is there or not (the cutoff), as photond reads it.
            cutoff = tree.nodes.new("ShaderNodeMath")
            cutoff.operation = "GREATER_THAN"
            tree.links.new(alpha, cutoff.inputs[0])
            cutoff.inputs[1].default_value = m.alpha_threshold
            transparent = tree.nodes.new("ShaderNodeBsdfTransparent")
            masked = tree.nodes.new("ShaderNodeMixShader")
            tree.links.new(cutoff.outputs["Value"], masked.inputs["Fac"])
            tree.links.new(transparent.outputs["BSDF"], masked.inputs[1])
            tree.links.new(shader, masked.inputs[2])
            shader = masked.outputs["Shader"]
        tree.links.new(shader, output.inputs["Surface"])


SCENES = {"window-room": window_room, "lamp-room": lamp_room}


def main():
    name, out_dir, options = parse_arguments()
    if name not in SCENES:
        sys.exit(f"unknown scene {name} (known: {', '.join(SCENES)})")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x = options["size"]
    scene.render.resolution_y = options["size"]
    directory = os.path.join(os.path.abspath(out_dir), name)
    os.makedirs(directory, exist_ok=True)
    sky = SCENES[name](directory)

    world = bpy.data.worlds.new("Sky")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*sky, 1.0)
    background.inputs["Strength"].default_value = 1.0
    scene.world = world
    with open(os.path.join(out_dir, name + ".world.json"), "w") as f:
        json.dump({"color": list(sky)}, f)

    bpy.ops.export_scene.gltf(filepath=os.path.join(directory, name + ".gltf"), export_format="GLTF_SEPARATE",
                              export_cameras=True, export_lights=True, export_yup=True)
    if options["materials"] == "gltf":
        gltf_materials_in_cycles()
    suffix = "-direct" if options["bounces"] == 0 else ""
    configure_cycles(scene, options, os.path.join(os.path.abspath(out_dir), f"{name}.cycles-{options['materials']}{suffix}.exr"))
    bpy.ops.render.render(write_still=True)


main()

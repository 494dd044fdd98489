import bpy, math, sys, mathutils
argv = sys.argv[sys.argv.index("--") + 1:]
out_dir = argv[0]
bpy.ops.wm.read_factory_settings(use_empty=True)
# A cylinder along Z, subdivided, skinned to two bones.
bpy.ops.mesh.primitive_cylinder_add(vertices=12, radius=0.2, depth=2.0, location=(0, 0, 1.0))
cyl = bpy.context.active_object
cyl.name = "Arm"
bpy.ops.object.shade_smooth()
bpy.ops.object.mode_set(mode='EDIT')
bpy.ops.mesh.select_all(action='SELECT')
bpy.ops.mesh.subdivide(number_cuts=5)
bpy.ops.object.mode_set(mode='OBJECT')
mat = bpy.data.materials.new("Red"); mat.use_nodes = True
mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.1, 0.1, 1)
cyl.data.materials.append(mat)
bpy.ops.object.armature_add(location=(0, 0, 0))
arm = bpy.context.active_object
arm.name = "Rig"
bpy.ops.object.mode_set(mode='EDIT')
b1 = arm.data.edit_bones[0]; b1.name = "Lower"; b1.head = (0, 0, 0); b1.tail = (0, 0, 1)
b2 = arm.data.edit_bones.new("Upper"); b2.head = (0, 0, 1); b2.tail = (0, 0, 2); b2.parent = b1
bpy.ops.object.mode_set(mode='OBJECT')
cyl.select_set(True); arm.select_set(True); bpy.context.view_layer.objects.active = arm
bpy.ops.object.parent_set(type='ARMATURE_AUTO')
# Pose: bend the upper bone.
bpy.ops.object.mode_set(mode='POSE')
arm.pose.bones["Upper"].rotation_mode = 'XYZ'
arm.pose.bones["Upper"].rotation_euler = (math.radians(60), 0, 0)
arm.pose.bones["Lower"].rotation_mode = 'XYZ'
arm.pose.bones["Lower"].rotation_euler = (0, math.radians(-20), 0)
bpy.ops.object.mode_set(mode='OBJECT')
# Move the rig so that node transforms matter.
arm.location = (0.5, -0.3, 0.0)
arm.rotation_euler = (0, 0, math.radians(30))
# A second mesh with a shape key at 0.5.
bpy.ops.mesh.primitive_uv_sphere_add(segments=12, ring_count=6, radius=0.4, location=(1.5, 0, 0.4))
sph = bpy.context.active_object; sph.name = "Blob"
bpy.ops.object.shade_smooth()
sph.shape_key_add(name="Basis")
key = sph.shape_key_add(name="Stretch")
for v in key.data:
    v.co.z = v.co.z * 2.0 + 0.1
key.value = 0.5
mat2 = bpy.data.materials.new("Blue"); mat2.use_nodes = True
mat2.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.1, 0.2, 0.8, 1)
sph.data.materials.append(mat2)
bpy.ops.object.camera_add(location=(5.0, -6.0, 3.0))
cam = bpy.context.active_object
direction = mathutils.Vector((0.8, 0.0, 0.9)) - cam.location
cam.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()
bpy.ops.export_scene.gltf(filepath=out_dir + "/skinned.gltf", export_format='GLTF_SEPARATE',
                          export_skins=True, export_morph=True, export_apply=False, export_animations=False, export_cameras=True, export_current_frame=True)
# The reference: the same scene with the shape key mixed into the mesh and the armature applied
# by the exporter.
bpy.ops.object.select_all(action='DESELECT')
bpy.context.view_layer.objects.active = sph
sph.select_set(True)
bpy.ops.object.shape_key_remove(all=True, apply_mix=True)
bpy.ops.export_scene.gltf(filepath=out_dir + "/baked.gltf", export_format='GLTF_SEPARATE',
                          export_skins=False, export_morph=False, export_apply=True, export_animations=False, export_cameras=True)

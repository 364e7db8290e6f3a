# Renders an exported texel (vtex export → .vdb) in Blender's Cycles with a Principled Volume and
# compares its transmittance, pixel by pixel, with the alpha of `vtex render` of the same view.
# Run by bench/blender_transmittance.sh:
#   blender -b --factory-startup --python bench/blender_transmittance.py -- \
#       texel.vdb vtex.exr OUT_DIR CAMX,CAMY,CAMZ LOOKX,LOOKY,LOOKZ FOV_Y_DEGREES SIZE SAMPLES
# Plain Python (Debian's Blender has no numpy). Prints one JSON line and writes OUT_DIR/blender.exr.
import json
import math
import os
import sys

import bpy
from mathutils import Vector

args = sys.argv[sys.argv.index("--") + 1:]
vdb_path, vtex_exr, out_dir = args[0], args[1], args[2]
camera_position = Vector([float(c) for c in args[3].split(",")])
look_at = Vector([float(c) for c in args[4].split(",")])
fov_y = math.radians(float(args[5]))
size = int(args[6])
samples = int(args[7])

# An empty scene: no light is needed, only the alpha (film transparent) is compared.
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = samples
scene.cycles.use_denoising = False
scene.cycles.use_adaptive_sampling = False
scene.cycles.pixel_filter_type = "BOX"  # vtex averages its strata over the pixel: a box
scene.cycles.filter_width = 1.0
scene.cycles.volume_step_rate = 0.25   # four steps a voxel: the ray march's own error out of the way
scene.cycles.volume_max_steps = 4096
scene.cycles.max_bounces = 0           # transmittance only: no scattering needed for alpha
scene.render.film_transparent = True
scene.render.resolution_x = size
scene.render.resolution_y = size
scene.render.resolution_percentage = 100
scene.view_settings.view_transform = "Standard"
scene.world = bpy.data.worlds.new("black")

# The camera of the vtex scene: same position, direction, vertical field of view, square image.
cam_data = bpy.data.cameras.new("camera")
cam_data.sensor_fit = "VERTICAL"
cam_data.angle_y = fov_y
cam_data.clip_start = 0.01
cam_data.clip_end = 1000
cam = bpy.data.objects.new("camera", cam_data)
cam.location = camera_position
cam.rotation_mode = "QUATERNION"
cam.rotation_quaternion = (look_at - camera_position).to_track_quat("-Z", "Y")
scene.collection.objects.link(cam)
scene.camera = cam

# The exported density, extinction per world unit: Principled Volume's density attribute as is.
volume = bpy.data.volumes.new("texel")
volume.filepath = vdb_path
volume.render.precision = "FULL"  # Cycles converts to half floats by default
obj = bpy.data.objects.new("texel", volume)
scene.collection.objects.link(obj)
material = bpy.data.materials.new("texel")
material.use_nodes = True
nodes = material.node_tree.nodes
nodes.clear()
principled = nodes.new("ShaderNodeVolumePrincipled")
principled.inputs["Density"].default_value = 1.0
# Cycles' Principled Volume: scattering density·colour, absorption density·(1 − colour)·(1 −
# absorption colour), so with a black absorption colour the extinction is the density whatever the
# colour. A black colour makes it a pure absorber: the transmittance is integrated along the march
# instead of sampled through scattering events, so alpha carries no sampling noise.
principled.inputs["Color"].default_value = (0, 0, 0, 1)
principled.inputs["Absorption Color"].default_value = (0, 0, 0, 1)
output = nodes.new("ShaderNodeOutputMaterial")
material.node_tree.links.new(principled.outputs["Volume"], output.inputs["Volume"])
obj.data.materials.append(material)

scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_mode = "RGBA"
scene.render.image_settings.color_depth = "32"
blender_exr = os.path.join(out_dir, "blender.exr")
scene.render.filepath = blender_exr
bpy.ops.render.render(write_still=True)


def alphas(path):
    image = bpy.data.images.load(path)
    image.colorspace_settings.name = "Non-Color"
    assert tuple(image.size) == (size, size), (path, tuple(image.size))
    pixels = list(image.pixels[:])
    return pixels[3::4]  # rows bottom to top in both images


blender_alpha = alphas(blender_exr)
vtex_alpha = alphas(vtex_exr)


# vtex draws the cell's floor (z = 0 over [0,1]²) opaque; Blender's copy has no floor. Pixels whose
# centre ray reaches the floor are left out of the comparison.
def sees_floor(px, py):
    forward = (look_at - camera_position).normalized()
    right = forward.cross(Vector((0, 0, 1))).normalized()
    up = right.cross(forward)
    half = math.tan(fov_y / 2)
    x = (2 * (px + 0.5) / size - 1) * half
    y = (2 * (py + 0.5) / size - 1) * half  # py counts rows bottom to top
    d = forward + x * right + y * up
    if d.z >= 0:
        return False
    t = -camera_position.z / d.z
    p = camera_position + t * d
    return 0 <= p.x <= 1 and 0 <= p.y <= 1


# Optical depth −ln T, with vtex's march cut-off (it stops at T = 1e-4).
def depth(t):
    return -math.log(max(t, 1e-4))


diffs = []
blender_t = []
vtex_t = []
for i in range(size * size):
    px, py = i % size, i // size
    if sees_floor(px, py):
        continue
    if blender_alpha[i] < 1e-3 and vtex_alpha[i] < 1e-3:
        continue  # beside the texel in both
    blender_t.append(1 - blender_alpha[i])
    vtex_t.append(1 - vtex_alpha[i])
    diffs.append(blender_t[-1] - vtex_t[-1])

n = len(diffs)
mean_b = sum(blender_t) / n
mean_v = sum(vtex_t) / n
depth_b = sum(map(depth, blender_t)) / n
depth_v = sum(map(depth, vtex_t)) / n
rmse = math.sqrt(sum(d * d for d in diffs) / n)
mean_abs = sum(abs(d) for d in diffs) / n
# 4×4 blocks (about two voxels): what differs at the scale of a voxel (Cycles interpolates the
# grid trilinearly, vtex's voxels are constant) averages out, a systematic shift does not.
blocks = []
for by in range(0, size, 4):
    for bx in range(0, size, 4):
        db = []
        for py in range(by, by + 4):
            for px in range(bx, bx + 4):
                i = py * size + px
                if sees_floor(px, py) or (blender_alpha[i] < 1e-3 and vtex_alpha[i] < 1e-3):
                    continue
                db.append(vtex_alpha[i] - blender_alpha[i])
        if len(db) == 16:
            blocks.append(sum(db) / 16)
block_rmse = math.sqrt(sum(b * b for b in blocks) / len(blocks)) if blocks else float("nan")
print("VTEX_BLENDER " + json.dumps({
    "pixels": n, "mean_transmittance_blender": round(mean_b, 5), "mean_transmittance_vtex": round(mean_v, 5),
    "mean_difference": round(mean_b - mean_v, 5),
    "mean_optical_depth_blender": round(depth_b, 4), "mean_optical_depth_vtex": round(depth_v, 4), "mean_abs_difference": round(mean_abs, 5),
    "rmse": round(rmse, 5), "block4_rmse": round(block_rmse, 5), "max_abs_difference": round(max(map(abs, diffs)), 5),
}))

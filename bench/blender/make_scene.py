# Builds one test scene in Blender, exports it as glTF the way a user would (default settings,
# lights and cameras ticked) and renders it with Cycles to a linear EXR.
# Run by bench/blender/roundtrip:  blender -b --factory-startup -P make_scene.py -- SCENE OUTDIR
# Scenes: point, spot, sun (a matte plane under one light), emissive (an emitting plane), cornell
# (a box of matte walls under a point light, 4 bounces, rendered by Cycles with Lambertian materials
# after the export), textured (a plane with an image texture under the sun), masked (a leaf-like
# card with an alpha-masked image texture over a plane, under the sun: cut-outs and their shadows).
import math
import sys

import bpy

SIZE = 64
SAMPLES = 4096


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False  # every pixel gets all its samples
    scene.cycles.max_bounces = 4
    scene.cycles.diffuse_bounces = 4
    scene.cycles.glossy_bounces = 4
    scene.cycles.transmission_bounces = 0
    scene.cycles.volume_bounces = 0
    scene.cycles.transparent_max_bounces = 0
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.cycles.pixel_filter_type = "BOX"  # the reference integrates each pixel with a box filter
    scene.render.resolution_x = scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    world = bpy.data.worlds.new("black")
    world.use_nodes = False
    world.color = (0.0, 0.0, 0.0)
    scene.world = world
    return scene


def matte(name, colour, roughness=1.0, emission=None):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    bsdf = material.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = 0.0
    if emission is not None:
        bsdf.inputs["Emission"].default_value = (*emission[0], 1.0)
        bsdf.inputs["Emission Strength"].default_value = emission[1]
    return material


def checker_image(name, out, cells, colours, alphas=(1.0, 1.0)):
    """A `cells` x `cells` checker of two colours (and alphas), saved as PNG beside the export."""
    image = bpy.data.images.new(name, cells, cells, alpha=True)
    pixels = []
    for y in range(cells):
        for x in range(cells):
            k = (x + y) % 2
            pixels += [*colours[k], alphas[k]]
    image.pixels = pixels
    image.filepath_raw = f"{out}/{name}.png"
    image.file_format = "PNG"
    image.save()
    return image


def textured(name, image, masked=False):
    """A rough dielectric whose base colour (and, when masked, alpha: alphaMode MASK) is `image`."""
    material = matte(name, (1.0, 1.0, 1.0))
    nodes, links = material.node_tree.nodes, material.node_tree.links
    texture = nodes.new("ShaderNodeTexImage")
    texture.image = image
    texture.interpolation = "Closest"  # cells with sharp edges in both renderers
    bsdf = nodes["Principled BSDF"]
    links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    if masked:
        links.new(texture.outputs["Alpha"], bsdf.inputs["Alpha"])
        material.blend_method = "CLIP"
        material.alpha_threshold = 0.5
    return material


def plane(name, size, location, rotation, material):
    bpy.ops.mesh.primitive_plane_add(size=size, location=location, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = name
    obj.data.materials.append(material)
    return obj


def camera(scene, location, rotation, fov_deg):
    data = bpy.data.cameras.new("camera")
    data.angle = math.radians(fov_deg)
    data.sensor_fit = "VERTICAL"
    obj = bpy.data.objects.new("camera", data)
    obj.location = location
    obj.rotation_euler = rotation
    scene.collection.objects.link(obj)
    scene.camera = obj


def light(scene, kind, energy, location, rotation=(0.0, 0.0, 0.0), **settings):
    data = bpy.data.lights.new(kind.lower(), type=kind)
    data.energy = energy
    for key, value in settings.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new(kind.lower(), data)
    obj.location = location
    obj.rotation_euler = rotation
    scene.collection.objects.link(obj)


def build(name, scene, out):
    grey = matte("grey", (0.8, 0.8, 0.8))
    if name in ("point", "spot", "sun"):
        plane("floor", 4.0, (0, 0, 0), (0, 0, 0), grey)
        camera(scene, (0, 0, 3), (0, 0, 0), 60)
        if name == "point":
            light(scene, "POINT", 100.0, (0.3, 0.2, 1.5), shadow_soft_size=0.0)
        elif name == "spot":
            light(scene, "SPOT", 100.0, (0, 0, 1.5), spot_size=math.radians(90), spot_blend=0.2,
                  shadow_soft_size=0.0)
        else:
            light(scene, "SUN", 3.0, (0, 0, 5), (math.radians(30), 0, 0), angle=0.0)
    elif name == "emissive":
        plane("panel", 4.0, (0, 0, 0), (0, 0, 0), matte("glow", (0.0, 0.0, 0.0), emission=((1.0, 0.9, 0.8), 2.0)))
        camera(scene, (0, 0, 3), (0, 0, 0), 60)
    elif name == "cornell":
        white, red, green = matte("white", (0.73, 0.73, 0.73)), matte("red", (0.65, 0.05, 0.05)), \
            matte("green", (0.12, 0.45, 0.15))
        half = math.pi / 2
        plane("floor", 2.0, (0, 0, 0), (0, 0, 0), white)
        plane("ceiling", 2.0, (0, 0, 2), (math.pi, 0, 0), white)
        plane("back", 2.0, (0, 1, 1), (half, 0, 0), white)
        plane("left", 2.0, (-1, 0, 1), (0, half, 0), red)
        plane("right", 2.0, (1, 0, 1), (0, -half, 0), green)
        light(scene, "POINT", 40.0, (0, 0, 1.8), shadow_soft_size=0.0)
        camera(scene, (0, -3.4, 1), (half, 0, 0), 40)
    elif name == "textured":
        image = checker_image("cells", out, 4, ((0.8, 0.3, 0.1), (0.1, 0.4, 0.7)))
        plane("floor", 4.0, (0, 0, 0), (0, 0, 0), textured("cells", image))
        camera(scene, (0, 0, 3), (0, 0, 0), 60)
        light(scene, "SUN", 3.0, (0, 0, 5), (math.radians(30), 0, 0), angle=0.0)
    elif name == "masked":
        scene.cycles.transparent_max_bounces = 8  # cut-outs are Cycles' transparency
        image = checker_image("leaf", out, 4, ((0.2, 0.6, 0.1), (0.2, 0.6, 0.1)), alphas=(1.0, 0.0))
        plane("floor", 4.0, (0, 0, 0), (0, 0, 0), grey)
        plane("card", 1.2, (0.2, 0.1, 0.8), (0, 0, math.radians(20)), textured("leaf", image, masked=True))
        camera(scene, (0, 0, 3), (0, 0, 0), 60)
        light(scene, "SUN", 3.0, (0, 0, 5), (math.radians(30), 0, 0), angle=0.0)
    else:
        raise SystemExit(f"unknown scene {name}")


def lambertian_materials():
    """Every material's Principled BSDF replaced by a Diffuse BSDF of its base colour: the Lambertian
    render a box of glTF default materials is compared with (Cycles' Principled diffuse adds
    retro-reflection at roughness 1, which glTF's BRDF does not have)."""
    for material in bpy.data.materials:
        nodes, links = material.node_tree.nodes, material.node_tree.links
        colour = nodes["Principled BSDF"].inputs["Base Color"].default_value[:]
        diffuse = nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = colour
        diffuse.inputs["Roughness"].default_value = 0.0
        links.new(diffuse.outputs["BSDF"], nodes["Material Output"].inputs["Surface"])


def main():
    argv = sys.argv[sys.argv.index("--") + 1:]
    name, out = argv[0], argv[1]
    scene = reset()
    build(name, scene, out)
    bpy.ops.export_scene.gltf(filepath=f"{out}/{name}.glb", export_format="GLB", export_lights=True,
                              export_cameras=True)
    if name == "cornell":
        lambertian_materials()
    scene.render.filepath = f"{out}/{name}-cycles.exr"
    bpy.ops.render.render(write_still=True)


main()

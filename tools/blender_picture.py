"""Render a scene file in Blender (Cycles, on the CPU) through the add-on, framed as ``render`` frames it.

    .venv-blender/bin/python tools/blender_picture.py SCENE.toml -o OUT.png [--size 800x450] [--samples 16]
        [--time 0] [--blend OUT.blend]

The scene is imported with File > Import > axialdeform (one Geometry Nodes object a layer, the terrain),
the camera is the library's (``scene_camera``: the scene's elevation, azimuth and fov), the sun comes
from the scene's light and the world is its background colour.  ``--blend`` also saves the .blend.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


#: the nodes of the fields (the bend's maths): drawn as one box
FIELD_NODES = ("ShaderNodeMath", "ShaderNodeVectorMath", "ShaderNodeSeparateXYZ", "ShaderNodeCombineXYZ",
               "GeometryNodeInputNamedAttribute", "GeometryNodeIndexSwitch", "ShaderNodeVectorRotate",
               "GeometryNodeInputSceneTime", "GeometryNodeInputPosition", "FunctionNodeEulerToRotation",
               "FunctionNodeBooleanMath", "GeometryNodeIsViewport")


def draw_group(group, out: str) -> None:
    """A drawing of a node group as Blender holds it (nodes, links): the geometry flow node by node, left to
    right, and the field nodes that compute the bend as one box with their count by kind."""
    from collections import Counter

    from PIL import Image, ImageDraw

    flow = [nd for nd in group.nodes if nd.bl_idname not in FIELD_NODES]
    fields = Counter(nd.bl_idname.replace("ShaderNode", "").replace("GeometryNode", "").replace("FunctionNode", "")
                     for nd in group.nodes if nd.bl_idname in FIELD_NODES)
    depth = {nd.name: 0 for nd in flow}
    for _ in range(len(flow)):  # longest path from the group input, over geometry links
        for link in group.links:
            a, b = link.from_node.name, link.to_node.name
            if a in depth and b in depth and link.from_socket.type in ("GEOMETRY", "OBJECT"):
                depth[b] = max(depth[b], depth[a] + 1)
    columns: dict = {}
    for nd in flow:
        columns.setdefault(depth[nd.name], []).append(nd)
    box_w, box_h, gap_x, gap_y = 170, 44, 40, 22
    width = (max(columns) + 1) * (box_w + gap_x) + gap_x
    height = max(len(c) for c in columns.values()) * (box_h + gap_y) + 190
    img = Image.new("RGB", (width, height), (40, 40, 40))
    d = ImageDraw.Draw(img)
    at = {}
    for col, nodes in columns.items():
        for row, nd in enumerate(sorted(nodes, key=lambda n: n.location.y, reverse=True)):
            x, y = gap_x + col * (box_w + gap_x), 20 + row * (box_h + gap_y)
            at[nd.name] = (x, y)
    lane = max(y for _, y in at.values()) + box_h + 10  # a link that skips columns runs below the boxes
    for link in group.links:
        if link.from_node.name in at and link.to_node.name in at:
            (x0, y0), (x1, y1) = at[link.from_node.name], at[link.to_node.name]
            a, b = (x0 + box_w, y0 + box_h // 2), (x1, y1 + box_h // 2)
            if x1 - x0 > box_w + gap_x:
                path = [a, (a[0] + gap_x // 3, a[1]), (a[0] + gap_x // 3, lane), (b[0] - gap_x // 3, lane),
                        (b[0] - gap_x // 3, b[1]), b]
            else:
                path = [a, b]
            d.line(path, fill=(0, 214, 163), width=2)
    for nd in flow:
        x, y = at[nd.name]
        d.rectangle([x, y, x + box_w, y + box_h], fill=(70, 70, 70), outline=(200, 200, 200))
        d.text((x + 6, y + 6), nd.bl_label if nd.bl_idname != "NodeGroupInput" else "Group Input", fill=(240, 240, 240))
        extra = nd.inputs["Name"].default_value if "Name" in nd.inputs else ""
        d.text((x + 6, y + 24), extra, fill=(180, 180, 180))
    y = height - 130
    d.rectangle([gap_x, y, width - gap_x, height - 14], fill=(55, 55, 90), outline=(150, 150, 230))
    d.text((gap_x + 8, y + 8), f"the bend, the wind and the normals: {sum(fields.values())} field nodes into "
           "Set Position and Set Mesh Normal", fill=(240, 240, 240))
    kinds = ", ".join(f"{k} {v}" for k, v in fields.most_common())
    for i in range(0, len(kinds), 150):
        d.text((gap_x + 8, y + 30 + 14 * (i // 150)), kinds[i:i + 150], fill=(200, 200, 230))
    img.save(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", help="a scene file (.toml)")
    parser.add_argument("-o", "--out", required=True, help="the PNG to write")
    parser.add_argument("--size", default="800x450", help="WIDTHxHEIGHT (default 800x450)")
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples a pixel (default 16)")
    parser.add_argument("--time", type=float, default=0.0, help="the scene's time in seconds: the wind's (default 0)")
    parser.add_argument("--blend", default=None, help="also save the .blend here (default: none)")
    parser.add_argument("--nodes", default=None,
                        help="also draw the first layer's node group here, a PNG (default: none)")
    args = parser.parse_args()
    # isort: off
    import bpy  # first: it makes addon_utils importable
    import addon_utils
    # isort: on
    from mathutils import Matrix, Vector

    import axialdeform as ad
    from axialdeform.gl.scene import scene_camera

    sys.path.insert(0, str(ROOT / "blender"))
    from axialdeform_blender.layers import UP_TO_Z_UP

    w, h = (int(v) for v in args.size.split("x"))
    scene_file = ad.Scene.load(args.scene)
    cam_spec = scene_camera(scene_file, w / h)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("axialdeform_blender", default_set=True)
    bpy.ops.import_scene.axialdeform(filepath=str(Path(args.scene).resolve()))
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 100, 1.0
    scene.frame_set(int(round(args.time * 100)))
    turn = Matrix(UP_TO_Z_UP[scene_file.up]).to_3x3()
    eye, target = turn @ Vector(cam_spec.eye), turn @ Vector(cam_spec.target)
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(cam)
    cam.location = eye
    cam.rotation_euler = (target - eye).to_track_quat("-Z", "Y").to_euler()
    cam.data.sensor_fit, cam.data.angle_y = "VERTICAL", np.radians(cam_spec.fovy)
    cam.data.clip_start, cam.data.clip_end = cam_spec.near, cam_spec.far
    scene.camera = cam
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    scene.collection.objects.link(sun)
    sun.data.energy = 3.0
    light = turn @ Vector(scene_file.look.light_dir)
    sun.rotation_euler = light.to_track_quat("Z", "Y").to_euler()  # the sun shines along -light
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    srgb = np.asarray(scene_file.background, dtype=float)
    linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (*linear, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.8
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples = "CPU", args.samples
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
    scene.view_settings.view_transform = "Standard"
    scene.render.filepath = str(Path(args.out).resolve())
    scene.render.image_settings.file_format = "PNG"
    bpy.ops.render.render(write_still=True)
    if args.nodes:
        layer = next(o for o in bpy.data.objects if "axialdeform" in o.keys())
        draw_group(layer.modifiers["axialdeform"].node_group, args.nodes)
    if args.blend:
        bpy.ops.wm.save_as_mainfile(filepath=str(Path(args.blend).resolve()))
    print(args.out)


if __name__ == "__main__":
    main()

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


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", help="a scene file (.toml)")
    parser.add_argument("-o", "--out", required=True, help="the PNG to write")
    parser.add_argument("--size", default="800x450", help="WIDTHxHEIGHT (default 800x450)")
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples a pixel (default 16)")
    parser.add_argument("--time", type=float, default=0.0, help="the scene's time in seconds: the wind's (default 0)")
    parser.add_argument("--blend", default=None, help="also save the .blend here (default: none)")
    args = parser.parse_args()
    import bpy  # first: it makes addon_utils importable
    import addon_utils
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
    if args.blend:
        bpy.ops.wm.save_as_mainfile(filepath=str(Path(args.blend).resolve()))
    print(args.out)


if __name__ == "__main__":
    main()

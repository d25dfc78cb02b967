"""What the Blender tests ask of Blender, run by the Python that has ``bpy`` (``.venv-blender``):
``python bl_checks.py COMMAND ...``; each command writes what it measured to ``--out``.

evaluate IN OUT.npz [--mesh MESH] [--time T --wind X,Y,Z,STRENGTH,GUST,FREQ,WAVELENGTH]
    import IN with the add-on; every layer's Geometry-Nodes-evaluated vertices, corner normals and
    corner vertices (``pos{i}``, ``nrm{i}``, ``corner{i}``) and the import's seconds.
edit IN OUTDIR
    import IN, edit its first layer as an artist would (delete instance 1, move instance 0, a new bend
    for instance 2, a new rotation for instance 3), export with Blender's glTF exporter
    (``gltf.glb``) and the add-on's operator (``ours.glb``), Vary with seed 5 (``varied.glb``).
through IN OUT.glb
    import IN and export it again with the add-on's operator, nothing changed.
render IN OUT.png --eye X,Y,Z --target X,Y,Z --fov DEG --size W,H
    import IN, render it with Cycles on the CPU (transparent film) from that camera (file coordinates).
block FILE.py
    run FILE.py (a docs block) with the add-on enabled, in the current folder.
install ZIP --glb IN --out OUT.glb
    install the add-on's zip as an extension (into $BLENDER_USER_RESOURCES), enable it, import IN with it and
    export OUT.glb with Blender's glTF exporter; prints what was installed as JSON.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import bpy
import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def _enable():
    import addon_utils

    sys.path.insert(0, str(ROOT / "blender"))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("axialdeform_blender", default_set=True)


def _layers():
    return sorted((o for o in bpy.data.objects if "axialdeform" in o.keys()), key=lambda o: o.name)


def _set_wind(obj, values):
    mod = obj.modifiers["axialdeform"]
    names = ("Wind Direction", "Wind Strength", "Gustiness", "Frequency", "Wavelength")
    ident = {i.name: i.identifier for i in mod.node_group.interface.items_tree if getattr(i, "in_out", "") == "INPUT"}
    x, y, z, strength, gust, freq, wavelength = values
    for name, value in zip(names, ((x, y, z), strength, gust, freq, wavelength)):
        mod[ident[name]] = value


def evaluate(args):
    _enable()
    start = time.perf_counter()
    try:
        result = bpy.ops.import_scene.axialdeform(filepath=args.input, mesh_path=args.mesh or "")
    except RuntimeError as exc:  # an operator that reports an error raises in background mode
        result = {"CANCELLED"}
        print("ERROR", exc)
    print("RESULT", sorted(result))
    seconds = time.perf_counter() - start
    out = {"seconds": np.array(seconds)}
    scene = bpy.context.scene
    if args.time is not None:
        scene.render.fps, scene.render.fps_base = 1000, 1.0
        scene.frame_set(int(round(args.time * 1000)))
    for i, obj in enumerate(_layers()):
        if args.wind:
            _set_wind(obj, [float(v) for v in args.wind.split(",")])
            obj.update_tag()
        dg = bpy.context.evaluated_depsgraph_get()
        dg.update()
        me = obj.evaluated_get(dg).to_mesh()
        v = np.empty(len(me.vertices) * 3, np.float32)
        me.vertices.foreach_get("co", v)
        n = np.empty(len(me.loops) * 3, np.float32)
        me.corner_normals.foreach_get("vector", n)
        c = np.empty(len(me.loops), np.int32)
        me.loops.foreach_get("vertex_index", c)
        out[f"pos{i}"], out[f"nrm{i}"], out[f"corner{i}"] = v.reshape(-1, 3), n.reshape(-1, 3), c
        out[f"instances{i}"] = np.array(len(obj.data.vertices))
    np.savez(args.out, **out)


def edit(args):
    import bmesh

    _enable()
    bpy.ops.import_scene.axialdeform(filepath=args.input)
    obj = _layers()[0]
    me = obj.data
    attrs = me.attributes
    attrs["axial_d5"].data[2].vector = (0.3, -0.2)  # a new bend, typed into the spreadsheet
    attrs["axial_angles"].data[3].vector = (0.1, 1.2, -0.3)  # a new rotation
    me.vertices[0].co.x += 1.5  # moved
    select = np.zeros(len(me.vertices), dtype=bool)
    select[5] = True
    me.vertices.foreach_set("select", select)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.axialdeform_rotate(angle=0.7, axis="Y")  # turned about the up axis
    bm = bmesh.new()
    bm.from_mesh(me)
    bm.verts.ensure_lookup_table()
    bm.verts.remove(bm.verts[1])  # deleted
    bm.to_mesh(me)
    bm.free()
    me.update()
    outdir = Path(args.out)
    bpy.ops.export_scene.gltf(filepath=str(outdir / "gltf.glb"), export_format="GLB")
    bpy.ops.export_scene.axialdeform(filepath=str(outdir / "ours.glb"))
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.axialdeform_vary(seed=5, bend=(0.2, 0.3, 0.3, 0.3))
    bpy.ops.export_scene.axialdeform(filepath=str(outdir / "varied.glb"))


def through(args):
    _enable()
    bpy.ops.import_scene.axialdeform(filepath=args.input)
    bpy.ops.export_scene.axialdeform(filepath=args.out)


def render(args):
    from mathutils import Matrix, Vector

    _enable()
    bpy.ops.import_scene.axialdeform(filepath=args.input)
    scene = bpy.context.scene
    turn = Matrix(((1, 0, 0), (0, 0, -1), (0, 1, 0)))  # the file's +Y up to Blender's +Z
    eye = turn @ Vector([float(v) for v in args.eye.split(",")])
    target = turn @ Vector([float(v) for v in args.target.split(",")])
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(cam)
    cam.location = eye
    cam.rotation_euler = (target - eye).to_track_quat("-Z", "Y").to_euler()
    w, h = (int(v) for v in args.size.split(","))
    cam.data.sensor_fit = "VERTICAL"
    cam.data.angle_y = np.radians(float(args.fov))
    cam.data.clip_start, cam.data.clip_end = 0.01, 1000.0
    scene.camera = cam
    light = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    scene.collection.objects.link(light)
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 16
    scene.cycles.use_denoising = False
    scene.render.film_transparent = True
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    scene.render.filepath = args.out
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    bpy.ops.render.render(write_still=True)


def block(args):
    _enable()
    code = Path(args.input).read_text(encoding="utf-8")
    exec(compile(code, args.input, "exec"), {"__name__": "__main__"})  # noqa: S102  (the docs' own block)
    print("LAYERS", json.dumps([[o.name, len(o.data.vertices)] for o in _layers()]))


def install(args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.extensions.package_install_files(filepath=args.input, repo="user_default", enable_on_install=True)
    names = [m for m in bpy.context.preferences.addons.keys() if "axialdeform" in m]
    bpy.ops.import_scene.axialdeform(filepath=args.glb)
    bpy.ops.export_scene.gltf(filepath=args.out, export_format="GLB")
    print("INSTALLED " + json.dumps({"addons": names, "layers": [o.name for o in _layers()]}))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("command", choices=("evaluate", "edit", "through", "render", "block", "install"))
    parser.add_argument("input")
    parser.add_argument("--out", default=None)
    parser.add_argument("--time", type=float, default=None)
    parser.add_argument("--glb", default=None)
    parser.add_argument("--mesh", default=None)
    parser.add_argument("--wind", default=None)
    parser.add_argument("--eye", default="0,1,4")
    parser.add_argument("--target", default="0,0,0")
    parser.add_argument("--fov", default="40")
    parser.add_argument("--size", default="160,120")
    args = parser.parse_args()
    {"evaluate": evaluate, "edit": edit, "through": through, "render": render, "block": block, "install": install}[args.command](args)


if __name__ == "__main__":
    main()

"""How long Blender takes to import N instances as one object and to bend them all (Geometry Nodes).

    .venv-blender/bin/python tools/blender_bench.py [--count 100000] [--repeats 3]

Writes an instanced GLB of stones (58 vertices) and of the ten-axis tree with the library (in this
Python: ``pip install -e .`` beside bpy), then in Blender (``bpy``): the import operator's seconds (the
file read, the base mesh, the points and their attributes, the node group), the viewport's first
evaluation (rigid instances: above 20 000 instances the viewport does not bend until asked), and the
bent evaluation (every vertex of every instance, what a render or an export of the geometry does).
Medians of ``--repeats``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=100_000, help="stones (58 vertices each; default 100000)")
    parser.add_argument("--trees", type=int, default=10_000,
                        help="trees (of about 1 000 vertices each; default 10000)")
    parser.add_argument("--repeats", type=int, default=3, help="runs per figure, the median reported (default 3)")
    args = parser.parse_args()
    # isort: off
    import bpy  # first: it makes addon_utils importable
    import addon_utils
    # isort: on

    import axialdeform as ad

    sys.path.insert(0, str(ROOT / "blender"))
    cases = {"stones": (ad.load_mesh("stone"), ad.Variation(bend=0.2, scale=(0.5, 1.5), tint=0.3), args.count),
             "trees (10 axes)": (ad.load_mesh("tree", axes="parts"), ad.Variation(bend=(0.1, 0.3)), args.trees)}
    print("| model | instances | vertices bent | import (s) | viewport, rigid (s) | bent, every vertex (s) |")
    print("|---|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (mesh, variation, count) in cases.items():
            glb = ad.export_glb(Path(tmp) / "in.glb", mesh, ad.random_params(mesh, count, seed=1,
                                                                              variation=variation), layout="instanced")
            times = {"import": [], "rigid": [], "bent": []}
            for _ in range(args.repeats):
                bpy.ops.wm.read_factory_settings(use_empty=True)
                addon_utils.enable("axialdeform_blender", default_set=True)
                start = time.perf_counter()
                bpy.ops.import_scene.axialdeform(filepath=str(glb))
                times["import"].append(time.perf_counter() - start)
                obj = next(o for o in bpy.data.objects if "axialdeform" in o.keys())
                start = time.perf_counter()
                dg = bpy.context.evaluated_depsgraph_get()
                obj.evaluated_get(dg)
                times["rigid"].append(time.perf_counter() - start)
                mod = obj.modifiers["axialdeform"]
                ident = {i.name: i.identifier for i in mod.node_group.interface.items_tree
                         if getattr(i, "in_out", "") == "INPUT"}
                mod[ident["Bend in Viewport"]] = True
                obj.update_tag()
                start = time.perf_counter()
                dg = bpy.context.evaluated_depsgraph_get()
                dg.update()
                me = obj.evaluated_get(dg).to_mesh()
                times["bent"].append(time.perf_counter() - start)
                verts = len(me.vertices)
            med = {k: statistics.median(v) for k, v in times.items()}
            print(f"| {name} | {count:,} | {verts:,} | {med['import']:.2f} | {med['rigid']:.2f} | {med['bent']:.2f} |")


if __name__ == "__main__":
    main()

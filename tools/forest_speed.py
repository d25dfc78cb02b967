"""The forest's cost, measured in one run.

    python tools/forest_speed.py [--trees 2000] [--rounds 15] [--size 800x600]

The trees of ``examples/forest/forest.toml`` (the bundled tree, ten axes),
drawn three ways in turn (A B C A B C ..., medians; tools/frame_timing.py):

* ``tree, 10 axes`` -- the forest: trunk, branches and twigs each bend;
* ``tree, 1 axis``  -- the same mesh and trees with ONE axis (the trunk's
  numbers only: every branch rides the trunk's bend);
* ``no bend``       -- plain instancing: the same rigid placement, no bend
  (``AxialRenderer(bend=False)``, the benchmark's "all the same").

Bytes per tree: the record (float32 and quantized) against one baked tree
(positions + normals, float32, the mesh's vertices).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import axialdeform as ad
from axialdeform.core.io.params import encode_binary
from axialdeform.core.record import split_record
from axialdeform.gl.renderer import AxialRenderer
from axialdeform.gl.scene import scene_camera

sys.path.insert(0, str(Path(__file__).resolve().parent))
from frame_timing import alternate  # noqa: E402 - tools/ is not a package

SCENE = Path(__file__).resolve().parent.parent / "examples" / "forest" / "forest.toml"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trees", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--size", default="800x600")
    args = ap.parse_args(argv)
    w, h = (int(x) for x in args.size.split("x"))
    scene = ad.Scene.load(SCENE, scale_counts=args.trees / 2000)
    layer = scene.layers[0]
    tree, params = layer.mesh, layer.params
    k = tree.axis_count
    standard, _ = split_record(params, k)
    one_axis = ad.load_mesh("tree")  # the same mesh, one axis (auto: y, over the whole tree)
    quantized = encode_binary(params, quantize=True)
    per_tree = {"record, float32": 4 * params.shape[1],
                "record, quantized": (len(quantized) - 100 - 8 * params.shape[1]) / len(params),
                "one baked tree (positions + normals)": 24 * tree.vertex_count}
    ctx = ad.create_context()
    try:
        cam = scene_camera(scene, w / h)
        view, proj = cam.view(), cam.projection(w / h)
        target = ad.Offscreen(ctx, (w, h), samples=0)
        with AxialRenderer(ctx, tree, params) as many, AxialRenderer(ctx, one_axis, standard) as one, \
                AxialRenderer(ctx, one_axis, standard, options=ad.RenderOptions(bend=False)) as rigid:
            times, _ = alternate(ctx, target, {f"tree, {k} axes": many, "tree, 1 axis": one, "no bend": rigid},
                                 view, proj, args.rounds)
        target.release()
        renderer = ctx.info.get("GL_RENDERER", "?")
    finally:
        ctx.release()
    print(f"{len(params)} trees of {tree.vertex_count} vertices ({k} axes), {w}x{h}, {args.rounds} rounds, "
          f"GL_RENDERER {renderer}")
    for name, b in per_tree.items():
        print(f"  bytes per tree, {name}: {b:.1f}")
    base = statistics.median(times[f"tree, {k} axes"])
    for name, t in times.items():
        med = statistics.median(t)
        print(f"  frame, {name}: median {1000 * med:.1f} ms (min {1000 * min(t):.1f}), "
              f"forest / this = {base / med:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

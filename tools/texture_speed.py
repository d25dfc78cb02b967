"""What textures cost on this machine: the same textured model drawn with its
textures and without them (the same file loaded with ``textures=False``: the
same vertices, parts, blending and draw calls, base colours only), frames
alternating in one process so load from elsewhere hits both alike.

    python3 tools/texture_speed.py [MESH] [--count 100] [--size 800x600] [--rounds 15]

MESH defaults to ``tests/data/meshes/assets/AlphaBlendModeTest.glb``.
Prints the median frame time of each, the median of the per-round ratios
textured / untextured with its quartiles (the goal on a software rasteriser:
at most 2), and the anisotropy the renderer asked for.  A measurement, not a
test: nothing is asserted about time.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

import numpy as np

import axialdeform as ad
from axialdeform.core.camera import frame_instances
from axialdeform.gl.context import texture_anisotropy
from axialdeform.gl.image import parse_size

from frame_timing import alternate

ROOT = Path(__file__).resolve().parent.parent
DEFAULT = ROOT / "tests" / "data" / "meshes" / "assets" / "AlphaBlendModeTest.glb"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh", nargs="?", default=str(DEFAULT))
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--size", default="800x600")
    ap.add_argument("--rounds", type=int, default=15)
    args = ap.parse_args()
    size = parse_size(args.size)
    textured = ad.load_mesh(args.mesh)
    plain = ad.load_mesh(args.mesh, textures=False)
    assert textured.fingerprint == plain.fingerprint
    params = ad.random_params(textured, args.count, seed=1, placement="disc")
    cam = frame_instances(textured, params, size[0] / size[1])
    view, proj = cam.view(), cam.projection(size[0] / size[1])
    ctx = ad.create_context()
    with ad.AxialRenderer(ctx, textured, params) as a, ad.AxialRenderer(ctx, plain, params) as b, \
            ad.Offscreen(ctx, size) as target:
        times, _ = alternate(ctx, target, {"textured": a, "untextured": b}, view, proj, args.rounds)
    ratios = np.asarray(times["textured"]) / np.asarray(times["untextured"])
    print(f"{Path(args.mesh).name}: {args.count} instances, {size[0]}x{size[1]}, {args.rounds} rounds, "
          f"anisotropy {texture_anisotropy(ctx):g} ({ctx.info['GL_RENDERER']})")
    for name, t in times.items():
        print(f"  {name:<10} median {statistics.median(t) * 1e3:8.1f} ms a frame")
    print(f"  textured / untextured: median of per-round ratios {np.median(ratios):.2f} "
          f"(quartiles {np.quantile(ratios, 0.25):.2f} .. {np.quantile(ratios, 0.75):.2f}; goal <= 2 on software)")
    ctx.release()


if __name__ == "__main__":
    main()

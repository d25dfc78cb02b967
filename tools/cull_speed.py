"""What back-face culling saves: the same stones drawn with and without it,
frames alternating in one process (so load from elsewhere hits both alike).

    python3 tools/cull_speed.py [--count 10000] [--size 800x600] [--rounds 30]

Prints the median frame time of each and the median of the per-round ratios
(culled / two-sided) with its quartiles, and the share of pixels that differ.
It is a measurement, not a test: nothing is asserted about time.
"""

from __future__ import annotations

import argparse
import statistics

import numpy as np

import axialdeform as ad
from axialdeform.core.camera import frame_instances
from axialdeform.gl.image import parse_size

from frame_timing import alternate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=10000)
    ap.add_argument("--size", default="800x600")
    ap.add_argument("--rounds", type=int, default=30)
    args = ap.parse_args()
    size = parse_size(args.size)
    ctx = ad.create_context()
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, args.count, seed=2003, variation=ad.Variation(bend=0.12), spacing=1.15 * mesh.axis.length)
    cam = frame_instances(mesh, params, size[0] / size[1])
    view, proj = cam.view(), cam.projection(size[0] / size[1])
    with ad.Offscreen(ctx, size, samples=0) as target, \
            ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(cull_back_faces=True)) as culled, \
            ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(cull_back_faces=False)) as two_sided:
        times, pictures = alternate(ctx, target, {True: culled, False: two_sided}, view, proj, args.rounds)
    ratios = np.array(times[True]) / np.array(times[False])
    differ = (np.abs(pictures[True].astype(int) - pictures[False]).max(axis=2) > 2).mean()
    print(f"{args.count} stones, {size[0]}x{size[1]}, {args.rounds} rounds, {ctx.info['GL_RENDERER']}")
    print(f"two-sided {statistics.median(times[False]) * 1e3:.1f} ms, culled {statistics.median(times[True]) * 1e3:.1f} ms")
    print(f"culled / two-sided: median of per-round ratios {np.median(ratios):.3f} "
          f"[quartiles {np.quantile(ratios, 0.25):.3f} .. {np.quantile(ratios, 0.75):.3f}]")
    print(f"pixels that differ by more than 2 of 255: {100 * differ:.4f} %")
    ctx.release()


if __name__ == "__main__":
    main()

"""How long ``axialdeform.scatter`` takes: 100 000 instances with spacing on a
100 000-triangle terrain (goal: under 2 s).  Not a test: a measurement.

    python tools/scatter_speed.py [--count 100000] [--min-distance 0.4] [--repeat 5]

The terrain is a 225 x 225 height map (100 352 triangles) 200 x 200 units
wide and up to 20 high; D = 0.4 puts 100 000 instances at about 0.4 per D²
(the greedy packing limit is about 0.7 per D²).  Prints each run's wall time
(``time.perf_counter``) and the median; checks the spacing once.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.spatial import cKDTree

import axialdeform as ad
from axialdeform.core.surface import surface_from_heights


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--count", type=int, default=100_000)
    p.add_argument("--min-distance", type=float, default=0.4)
    p.add_argument("--grid", type=int, default=225, help="height-map side in pixels (2 (g-1)² triangles)")
    p.add_argument("--repeat", type=int, default=5)
    args = p.parse_args()

    x = np.linspace(0.0, 1.0, args.grid)
    gx, gz = np.meshgrid(x, x)
    heights = 0.5 + 0.25 * np.sin(6 * gx) * np.cos(5 * gz) + 0.1 * np.sin(23 * gx + 17 * gz)
    surface = surface_from_heights(heights, height_scale=20.0, extent=200.0)
    mesh = ad.load_mesh("stone")
    print(f"terrain: {len(surface.mesh.faces)} triangles, {surface.mesh.area:.0f} units² ; "
          f"{args.count} instances at spacing {args.min_distance}")
    times = []
    for i in range(args.repeat):
        t0 = time.perf_counter()
        placement = ad.core.Placement(min_distance=args.min_distance, anchor="origin", align_to_normal=0.5)
        params = ad.scatter(surface, mesh, args.count, placement=placement, seed=i, variation=ad.Variation(scale=(0.8, 1.2)))
        times.append(time.perf_counter() - t0)
        print(f"run {i}: {times[-1]:.3f} s ({len(params)} instances)")
    p3 = params[:, 10:13].astype(np.float64)
    nearest = cKDTree(p3).query(p3, k=2)[0][:, 1].min()
    print(f"median {statistics.median(times):.3f} s, best {min(times):.3f} s; nearest pair {nearest:.4f} "
          f"(>= {args.min_distance}: {nearest >= args.min_distance * (1 - 1e-6)})")


if __name__ == "__main__":
    main()

"""How fast scenery is learned and grown (docs/learn.md, "Measured").

    python3 tools/learn_speed.py [--repeats 5]

1. Learning from about 10 000 objects (an inhomogeneous Poisson pattern and a clumped one on the synthetic
   hills of the tests): seconds, wall clock.
2. Growing a layer in clumps against the same layer on the jittered grid, on the GPU of this machine's
   OpenGL context (the compute path where it has one): 64 tiles of 64 x 64 slots, both recipes' tiles made in
   turn, the median ratio of their times over ``--repeats`` rounds.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import axialdeform as ad  # noqa: E402
from axialdeform.core import learn as L  # noqa: E402
from axialdeform.core.generate import Generate  # noqa: E402
from axialdeform.gl.generate import TileGenerator  # noqa: E402

from helpers import processes as P  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=5, help="rounds of the GPU comparison (default: %(default)s)")
    args = p.parse_args(argv)
    _, g = P.ground()
    rng = np.random.default_rng(0)
    for name, xz in (("inhomogeneous Poisson", P.inhomogeneous(rng, g, {"slope": 0.05, "altitude": -0.08}, 0.75)),
                     ("clumps", P.matern_cluster(rng, 0.05, 3.0, 8.5))):
        t = time.perf_counter()
        lay = L.learn_layers(L.Example(xz, P.window()), g)[0]
        print(f"learn, {name}: {len(xz)} objects in {time.perf_counter() - t:.2f} s ({lay.spacing.pattern})")
    ctx = ad.create_context()
    stone = ad.load_mesh("stone")
    grid = Generate(rate=16.0, tile=16.0, min_distance=0.05, bend=0.1, scale=(0.5, 1.0))
    clumps = Generate(rate=16.0, tile=16.0, bend=0.1, scale=(0.5, 1.0), clump_cells=8, clump_radius=1.5)
    tiles = np.stack(np.meshgrid(np.arange(8), np.arange(8)), -1).reshape(-1, 2)
    gens = [TileGenerator(ctx, r, stone) for r in (grid, clumps)]
    buf = ctx.buffer(reserve=gens[0].buffer().size * len(tiles))
    times = [[], []]
    for _ in range(args.repeats + 1):  # the first round warms up
        for k, gen in enumerate(gens):
            ctx.finish()
            t = time.perf_counter()
            gen.run_tiles(tiles, buf)
            ctx.finish()
            times[k].append(time.perf_counter() - t)
    a, b = (np.array(t[1:]) for t in times)
    print(f"grow 64 tiles of {gens[0].count} slots ({'compute' if gens[0].compute is not None else 'transform feedback'}): "
          f"grid {np.median(a) * 1e3:.1f} ms, clumps {np.median(b) * 1e3:.1f} ms, clumps / grid {np.median(b / a):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

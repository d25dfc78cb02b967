"""Float32 precision against world distance, on real meshes: how far from
the origin (in axis lengths L) an instance can be placed before its shape
loses detail.

    python3 tools/precision.py [--meshes stone leaf PATH...]

For each mesh and each distance k*L (k = 1, 10, 100, ... 1e6) a few bent,
rotated instances are placed at distance k*L; their world positions are
computed in float64 (the reference, ``deform_local`` + rotation + position
in float64), by the CPU engine (float64 maths, float32 result) and by the
GPU (``capture``: float32 throughout).  Printed: the largest vertex error
of each engine as a fraction of L, one JSON line per mesh and distance.
Feeds docs/reliability.md ("safe ranges") and ``SAFE_DISTANCE_L``.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=["stone", "leaf"])
    ap.add_argument("--instances", type=int, default=8)
    args = ap.parse_args(argv)
    import axialdeform as ad
    from axialdeform.core.deform import deform_local, rotation_matrices
    from axialdeform.core.params import ANGLES, OFFSETS, POSITION

    ctx = ad.create_context()
    try:
        for name in args.meshes:
            mesh = ad.load_mesh(name)
            L = mesh.axis.length
            base = ad.random_params(mesh, args.instances, 7, variation=ad.Variation(bend=0.1))
            direction = np.array([1.0, 0.6, 0.8]) / np.linalg.norm([1.0, 0.6, 0.8])
            for k in (1, 10, 100, 1e3, 1e4, 1e5, 1e6):
                p = base.astype(np.float64).copy()
                p[:, POSITION] = direction * k * L + np.arange(args.instances)[:, None] * 1.1 * L
                p32 = p.astype(np.float32)
                q = p32.astype(np.float64)  # the float32 parameters are the input of every engine
                moved, _ = deform_local(mesh.axis, mesh.positions, mesh.normals, q[:, OFFSETS].reshape(-1, 5, 2))
                ref = np.einsum("nij,nvj->nvi", rotation_matrices(q[:, ANGLES]), moved) + q[:, None, POSITION]
                cpu, _ = ad.bake(mesh, p32, "cpu")
                gpu, _ = ad.bake(mesh, p32, "gpu", ctx=ctx)
                print(json.dumps({"mesh": name, "L": round(L, 6), "distance_L": k,
                                  "cpu_error_L": float(np.abs(cpu - ref).max() / L),
                                  "gpu_error_L": float(np.abs(gpu - ref).max() / L)}))
    finally:
        ctx.release()
    return 0


if __name__ == "__main__":
    sys.exit(main())

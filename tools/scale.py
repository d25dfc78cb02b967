"""How long one frame of a million instances takes: one renderer, ONE draw call.

    python3 tools/scale.py [--count 1000000] [--mesh tetra|stone|leaf] [--size 256x256]
                           [--frames 3] [--out docs/benchmarks/scale.json]

For the float32 (64 bytes an instance) and the quantized (32 bytes) instance
buffer it records: the time to create the renderer (upload), the median
frame time (render + glFinish via reading the image back), the GPU bytes of
the instance buffer, and the share of pixels drawn (not empty).  The figures
go to ``--out`` as JSON (written atomically) and to stdout.  It is a
measurement, not a test: nothing is asserted about time.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np
import pyrr

import axialdeform as ad
from axialdeform.core.io.atomic import atomic_write_text
from axialdeform.core.mesh import area_weighted_normals
from axialdeform.gl.image import parse_size

TETRA_V = np.array([(0, 0, 0), (1, 0, 0), (0.3, 0.8, 0), (0.3, 0.3, 0.7)], dtype=np.float64) * (2, 1, 1)
TETRA_F = np.array([(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)])


def grid_params(mesh, n: int, seed: int = 1) -> tuple[np.ndarray, float]:
    """n instances on a cubic grid 1.5 L apart with random bends/angles; returns (params, grid extent)."""
    side = int(np.ceil(n ** (1 / 3)))
    L = mesh.axis.length
    rng = np.random.default_rng(seed)
    idx = np.arange(n)
    grid = np.stack([idx // (side * side), (idx // side) % side, idx % side], -1) * 1.5 * L
    p = np.zeros((n, 16), np.float32)
    p[:, :10] = rng.normal(scale=0.08 * L, size=(n, 10))
    p[:, 10:13] = grid
    p[:, 13:16] = rng.uniform(0, 2 * np.pi, (n, 3))
    return p, side * 1.5 * L


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=1_000_000)
    ap.add_argument("--mesh", default="tetra", help="tetra (4 triangles), stone, leaf or a mesh file")
    ap.add_argument("--size", default="256x256")
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--out", default="docs/benchmarks/scale.json")
    args = ap.parse_args(argv)
    w, h = parse_size(args.size)
    if args.mesh == "tetra":
        mesh = ad.BaseMesh(TETRA_V, area_weighted_normals(TETRA_V, TETRA_F), TETRA_F, name="tetra")
    else:
        mesh = ad.load_mesh(args.mesh)
    params, extent = grid_params(mesh, args.count)
    centre = np.full(3, extent / 2)
    view = pyrr.matrix44.create_look_at(centre + extent * np.array([1.4, 1.0, 1.7]), centre, (0, 1, 0))
    proj = pyrr.matrix44.create_perspective_projection(45, w / h, extent * 0.05, extent * 10)
    ctx = ad.create_context()
    rows = []
    try:
        for quantized in (False, True):
            t0 = time.perf_counter()
            with ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(quantized=quantized)) as r, \
                    ad.Offscreen(ctx, (w, h), samples=0) as target:
                created = time.perf_counter() - t0
                times = []
                for _ in range(args.frames):
                    target.use()
                    t0 = time.perf_counter()
                    r.render(view, proj)
                    image = target.read()  # waits for the frame to finish
                    times.append(time.perf_counter() - t0)
                drawn = float(np.any(np.abs(image.astype(int) - np.round(np.array([0.93, 0.94, 0.96]) * 255)) > 2,
                                     axis=-1).mean())
                rows.append({
                    "instances": args.count, "mesh": mesh.name, "triangles_per_instance": int(len(mesh.faces)),
                    "quantized": quantized, "bytes_per_instance": r.instances.buffer.size // args.count,
                    "instance_buffer_bytes": r.instances.buffer.size, "draw_calls": 1,
                    "create_s": round(created, 3), "frame_s_median": round(float(np.median(times)), 3),
                    "frame_s_all": [round(t, 3) for t in times], "image": f"{w}x{h}", "pixels_drawn": round(drawn, 3),
                })
                print(json.dumps(rows[-1]))
        info = {"renderer": ctx.info.get("GL_RENDERER"), "python": platform.python_version(), "machine": platform.machine()}
    finally:
        ctx.release()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out, json.dumps({"system": info, "rows": rows}, indent=2) + "\n")
    print(f"wrote {out}")
    return 0 if all(r["pixels_drawn"] > 0.01 for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())

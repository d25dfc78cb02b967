"""How long a big mesh takes: trimesh's parse alone, ``load_mesh``, and the
first solid frame (renderer + one draw into 64x64), with wireframe edges
never built for solid drawing.

    python3 tools/big_mesh.py [--faces 10000000] [--format ply]
    python3 tools/big_mesh.py --faces 1000000 --lod    # LOD instead: its time and peak RSS

Generates a closed torus of about ``--faces`` triangles (binary PLY, or OBJ
text) in a temporary folder, then times each step once and prints a JSON
line.  A measurement, not a test: the figures go to docs/reliability.md.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np


def torus(faces: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed torus grid: (n, 3) float32 positions and (m, 3) int64 faces, m ~= ``faces``."""
    nu = int(np.sqrt(faces / 2 * 1.25))
    nv = max(3, int(faces / 2 / nu))
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv, indexing="ij")
    r = 1.0 + 0.3 * np.cos(v)
    pos = np.stack([r * np.cos(u), 0.3 * np.sin(v), r * np.sin(u)], axis=-1).reshape(-1, 3).astype(np.float32)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a = i * nv + j
    b = ((i + 1) % nu) * nv + j
    c = ((i + 1) % nu) * nv + (j + 1) % nv
    d = i * nv + (j + 1) % nv
    f = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    return pos, f


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--faces", type=int, default=10_000_000)
    ap.add_argument("--format", choices=("ply", "obj"), default="ply")
    ap.add_argument("--lod", action="store_true", help="instead: time build_lod_levels after load_mesh and print "
                    "the peak RSS after each (run it in a fresh process: the peak is the process's)")
    args = ap.parse_args(argv)
    import trimesh

    import axialdeform as ad

    pos, faces = torus(args.faces)
    out = {"faces": int(len(faces)), "vertices": int(len(pos)), "format": args.format}
    with tempfile.TemporaryDirectory(prefix="bigmesh-") as tmp:
        path = os.path.join(tmp, f"big.{args.format}")
        trimesh.Trimesh(pos, faces, process=False).export(path)
        out["file_mb"] = round(os.path.getsize(path) / 2**20, 1)
        t = time.perf_counter()
        trimesh.load(path, process=False)
        out["trimesh_parse_s"] = round(time.perf_counter() - t, 2)
        t = time.perf_counter()
        mesh = ad.load_mesh(path)
        out["load_mesh_s"] = round(time.perf_counter() - t, 2)
        if args.lod:
            import resource

            from axialdeform.core.lod import build_lod_levels

            del pos, faces
            out["peak_rss_after_load_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
            t = time.perf_counter()
            levels = build_lod_levels(mesh)
            out["build_lod_levels_s"] = round(time.perf_counter() - t, 2)
            out["peak_rss_after_lod_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
            out["level_triangles"] = [len(level.faces) for level in levels]
            print(json.dumps(out))
            return 0
    params = ad.random_params(mesh, 1, 0)
    ctx = ad.create_context()
    t = time.perf_counter()
    with ad.AxialRenderer(ctx, mesh, params) as r, ad.Offscreen(ctx, (64, 64)) as target:
        target.use()
        cam = ad.frame_instances(mesh, params, 1.0)
        r.render(cam.view(), cam.projection(1.0), "solid")
        target.read()
        out["first_solid_frame_s"] = round(time.perf_counter() - t, 2)
        out["edges_built_for_solid"] = "edges" in mesh.__dict__
        t = time.perf_counter()
        r.render(cam.view(), cam.projection(1.0), "wireframe")
        target.read()
        out["first_wireframe_frame_s"] = round(time.perf_counter() - t, 2)
    ctx.release()
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())

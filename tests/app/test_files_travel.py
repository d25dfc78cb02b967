"""A parameter file written on one machine reads on every other: the axis frame's and the tree's digests
hash their numbers rounded far above float noise (core/axis.py, stable_bytes), not the last bits a BLAS
kernel computed.  Here two OpenBLAS kernels stand for two machines (before, a tree's file was refused)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
AXES = ROOT / "examples" / "forest" / "tree-axes.toml"

WRITE = """
import sys, axialdeform as ad
from axialdeform.core.io.mesh import with_axes
kind, out = sys.argv[1], sys.argv[2]
if kind == "tree":
    mesh = with_axes(ad.load_mesh("tree"), sys.argv[3])
else:
    mesh = ad.load_mesh("leaf", axis="oriented")
ad.write_params(out, ad.random_params(mesh, 5, seed=3), mesh)
"""
READ = WRITE.split("ad.write_params")[0] + "print(len(ad.read_params(out, mesh)))\n"


def run(script, *args, kernel=None):
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE")}
    if kernel:
        env["OPENBLAS_CORETYPE"] = kernel
    return subprocess.run([sys.executable, "-c", script, *map(str, args)], capture_output=True, text=True, env=env,
                          timeout=120)


@pytest.mark.parametrize("kind", ["tree", "oriented"])
@pytest.mark.parametrize("writer, reader", [(None, "Sandybridge"), ("Sandybridge", None), ("Prescott", "Haswell")])
def test_a_file_reads_under_another_blas_kernel(tmp_path, kind, writer, reader):
    out = tmp_path / f"{kind}.adp"
    w = run(WRITE, kind, out, AXES, kernel=writer)
    assert w.returncode == 0, w.stderr[-1500:]
    r = run(READ, kind, out, AXES, kernel=reader)
    assert r.returncode == 0 and r.stdout.strip() == "5", r.stderr[-1500:]

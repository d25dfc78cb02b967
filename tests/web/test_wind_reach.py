"""The npm module's wind reach (js/src/core/wind.js, windReach) is the Python library's (core/bounds.py,
wind_reach): for a tree, the longest chain of axis lengths a vertex sums (axis, parent, ..., root), not
the sum of every axis's length (which the module used: a looser bound that disagreed with Python's)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

import axialdeform as ad
from axialdeform.core.bounds import wind_reach

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("kind", ["stone", "tree"])
def test_the_modules_wind_reach_is_pythons(kind):
    mesh = ad.load_mesh("tree", axes=str(ROOT / "examples" / "forest" / "tree-axes.toml")) if kind == "tree" \
        else ad.load_mesh("stone")
    wind = ad.Wind(strength=0.3, gustiness=0.5)
    tree = getattr(mesh, "tree", None)
    lengths = [a.length for a in tree.axes] if tree is not None else [mesh.axis.length]
    parents = [int(p) for p in tree.parents] if tree is not None else None
    script = (f"import {{ windReach }} from '{(ROOT / 'js' / 'src' / 'core' / 'wind.js').as_uri()}';"
              f"console.log(JSON.stringify(windReach({{strength: 0.3, gustiness: 0.5}}, {json.dumps(lengths)}, "
              f"{json.dumps(parents)})));")
    r = subprocess.run(["node", "--input-type=module", "-e", script], capture_output=True, text=True, timeout=60,
                       cwd=ROOT / "js")
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    assert got == pytest.approx(wind_reach(mesh, wind), rel=1e-12)
    if tree is not None:
        assert got < 0.3 * 1.5 * sum(lengths)  # tighter than the sum the module used before

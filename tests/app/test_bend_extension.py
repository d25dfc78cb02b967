"""The AXIALDEFORM_bend glTF extension (docs/gltf/AXIALDEFORM_bend): every instanced export
carries it, it validates against its JSON schema, the Khronos validator reports 0 errors, and
it holds what a loader needs (the axis, a tree's axes, the numbers per instance)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import jsonschema
import numpy as np
import pygltflib
import pytest

import axialdeform as ad
from axialdeform.core.io.gltf import BEND_EXTENSION, INSTANCING

from conftest import validate_gltf

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "docs" / "gltf" / "AXIALDEFORM_bend" / "schema" / "node.AXIALDEFORM_bend.schema.json")
                    .read_text())
TREE_AXES = ROOT / "examples" / "forest" / "tree-axes.toml"


def cli(*args):
    r = subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r


CASES = {
    "stone16": ("stone", [], []),
    "framed19": ("stone", ["--axis", "oriented"], ["--twist", 0.5, "--taper", 0.2, "--scale", "0.8:1.2"]),
    "leaves22": ("leafcard", [], ["--tint", 0.3]),
    "tree": ("tree", ["--axes", TREE_AXES], []),
}


def bend_objects(glb: Path) -> list[dict]:
    g = pygltflib.GLTF2().load(str(glb))
    assert BEND_EXTENSION in g.extensionsUsed and BEND_EXTENSION not in (g.extensionsRequired or [])
    return [(n, n.extensions[BEND_EXTENSION]) for n in g.nodes if BEND_EXTENSION in (n.extensions or {})]


@pytest.mark.parametrize("case", CASES)
def test_every_instanced_export_carries_a_valid_extension(tmp_path, case):
    mesh, axis, opts = CASES[case]
    adp, glb = tmp_path / "p.adp", tmp_path / "p.glb"
    cli("random", mesh, *axis, "-n", 7, "--seed", 1, *opts, "-o", adp)
    cli("export", mesh, adp, *axis, "--instanced", "-o", glb)
    [(node, ext)] = bend_objects(glb)
    jsonschema.validate(ext, SCHEMA)
    assert INSTANCING in node.extensions  # always beside the instancing
    base = ad.load_mesh(mesh, **({axis[0].lstrip("-"): str(axis[1])} if axis else {}))
    params = ad.read_params(adp, mesh=base)
    assert ext["numbersPerInstance"] == params.shape[1]
    a = base.axis
    assert np.allclose(ext["axis"]["frame"], a.matrix) and ext["axis"]["lo"] == a.lo and ext["axis"]["length"] == a.length
    assert ext["axis"]["center"] == list(a.line) and ext["fingerprint"] == base.fingerprint.hex()
    if base.tree is not None:
        assert ext["axes"]["count"] == base.tree.count == 10 and ext["axes"]["parents"] == list(base.tree.parents)
    else:
        assert "axes" not in ext
    [report] = validate_gltf(glb)
    assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]


def test_a_scene_file_export_has_the_extension_on_every_layer(tmp_path):
    glb = tmp_path / "scene.glb"
    cli("export", ROOT / "examples" / "forest" / "forest.toml", "--instanced", "-o", glb)
    found = bend_objects(glb)
    assert found and all(jsonschema.validate(ext, SCHEMA) is None for _n, ext in found)
    assert validate_gltf(glb)[0]["issues"]["numErrors"] == 0


def test_the_schema_refuses_what_a_loader_could_not_use():
    good = {"numbersPerInstance": 16, "axis": {"frame": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "lo": -1.0, "length": 2.0,
                                               "center": [0.0, 0.0]}}
    jsonschema.validate(good, SCHEMA)
    for bad in ({**good, "numbersPerInstance": 3}, {**good, "axis": {**good["axis"], "length": 0}},
                {**good, "axis": {**good["axis"], "frame": [[1, 0, 0]]}}, {"axis": good["axis"]},
                {**good, "fingerprint": "xyz"}):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(bad, SCHEMA)

"""A GLB of a few KB in the generated form cannot ask for unbounded work: the Python reader and the npm
plugin (three's GLTFLoader in node) refuse the same files in one line, before anything is allocated,
and read the same good file (docs/generate.md, "Bounds"; js/src/core/limits.js)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pygltflib
import pytest

import axialdeform as ad
from axialdeform.core.errors import GltfError
from axialdeform.core.generate import MAX_BEND, MAX_SLOTS, MAX_TILE_SLOTS, WORLD_CELLS, generate_tiles, tiles_around
from axialdeform.core.io.gltf import read_instanced_glb
from axialdeform.core.io.gltf_generate import MAX_MAP_TEXELS, read_generated_glb

ROOT = Path(__file__).resolve().parents[2]

SCENE = """
[[layer]]
name = "stones"
mesh = "stone"
[layer.generate]
rate = 1.0
tile = 8.0
min_distance = 0.3
seed = 4
scale = [0.5, 1.0]
lift = [0.0, 0.1]
yaw = [0.1, 1.2]
extent = [-8, -8, 8, 8]
reach = 24.0
"""

# (where, key, value): a recipe key, a generator number, or a map's shape -- each one the plugin used to
# load and draw as something else, freeze on, or fail inside three with
HOSTILE = [("recipe", "rate", 1e12), ("recipe", "tile", 1e5), ("recipe", "reach", 2000.0), ("recipe", "reach", 1e9),
           ("recipe", "reach", 1e308), ("recipe", "tile", 1e-6), ("recipe", "tile", 1e-3), ("recipe", "bend", 1e30),
           ("uniforms", "jitter", 1e30), ("uniforms", "scale", [-5.0, 0.0]), ("uniforms", "cell", "abc"),
           ("uniforms", "m", 100000), ("uniforms", "lift", [3e38, 3.4e38]), ("uniforms", "has_heights", True),
           ("uniforms", "h_size", [4000, 4000]), ("uniforms", "bend", 1e30), ("uniforms", "seed", 5),
           ("uniforms", "tint", 0.5), ("uniforms", "choice", [0.0, 7.0]), ("uniforms", "align", -1.0),
           ("recipe", "yaw", [1.0, 0.0]), ("uniforms", "yaw", [0.1, 1.3])]
OK = ("good", "whole", "older")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("genform")
    (folder / "s.toml").write_text(SCENE)
    glb = folder / "good.glb"
    scene = ad.Scene.load(folder / "s.toml")
    subprocess.run([sys.executable, "-m", "axialdeform", "export", str(folder / "s.toml"), "--generated", "-o", str(glb)],
                   check=True, capture_output=True)
    out = {"good": glb}
    # the same file with its whole numbers written as 4.0, 16.0 (JSON's; JavaScript reads both as integers)
    g = pygltflib.GLTF2().load(str(glb))
    node = next(n for n in g.nodes if n.extensions and "AXIALDEFORM_bend" in n.extensions)
    gen = node.extensions["AXIALDEFORM_bend"]["generate"]
    gen["recipe"]["seed"] = float(gen["recipe"]["seed"])
    gen["uniforms"].update(seed=float(gen["uniforms"]["seed"]), m=float(gen["uniforms"]["m"]))
    g.save_binary(str(folder / "whole.glb"))
    out["whole"] = folder / "whole.glb"
    # a file of the form's first version: no yaw in the recipe or the numbers (a key added since: its default)
    g = pygltflib.GLTF2().load(str(glb))
    gen = next(n for n in g.nodes if n.extensions and "AXIALDEFORM_bend" in n.extensions).extensions["AXIALDEFORM_bend"]["generate"]
    del gen["recipe"]["yaw"], gen["uniforms"]["yaw"]
    g.save_binary(str(folder / "older.glb"))
    out["older"] = folder / "older.glb"
    for i, (where, key, value) in enumerate(HOSTILE):
        g = pygltflib.GLTF2().load(str(glb))
        node = next(n for n in g.nodes if n.extensions and "AXIALDEFORM_bend" in n.extensions)
        node.extensions["AXIALDEFORM_bend"]["generate"][where][key] = value
        path = folder / f"bad{i:02d}_{key}.glb"
        g.save_binary(str(path))
        out[(where, key, json.dumps(value))] = path
    return scene, out


def test_the_bounds_are_one_table_in_both_languages():
    text = (ROOT / "js" / "src" / "core" / "limits.js").read_text()
    for name, value in (("MAX_TILE_SLOTS", MAX_TILE_SLOTS), ("MAX_SLOTS", MAX_SLOTS), ("WORLD_CELLS", WORLD_CELLS),
                        ("MAX_BEND", MAX_BEND), ("MAX_MAP_TEXELS", MAX_MAP_TEXELS)):
        line = next(x for x in text.splitlines() if x.startswith(f"export const {name} = "))
        assert eval(line.split("= ", 1)[1].rstrip(";")) == value, name  # noqa: S307 (our own constant)


def test_python_reads_the_generated_node_as_its_recipe(files):
    scene, out = files
    layer = scene.layers[0]
    node = read_generated_glb(out["good"])
    want = layer.generate.generate
    assert node.generate == want and node.reach == layer.generate.reach
    tiles = tiles_around(want, 3.0, -5.0, 20.0)
    np.testing.assert_array_equal(generate_tiles(node.generate, node.mesh, tiles, node.maps),
                                  generate_tiles(want, layer.mesh, tiles, layer.generate.maps))
    with pytest.raises(GltfError, match="is a generated layer .*read_generated_glb"):
        read_instanced_glb(out["good"])
    assert len(read_instanced_glb(out["good"], fallback=True)[1]) > 0


def test_python_refuses_every_hostile_file_in_one_line(files):
    _, out = files
    assert read_generated_glb(out["whole"]).generate == read_generated_glb(out["good"]).generate
    assert read_generated_glb(out["good"]).generate.yaw == (0.1, 1.2)
    assert read_generated_glb(out["older"]).generate.yaw == (0.0, 2.0 * np.pi)
    for key, path in out.items():
        if key in OK:
            continue
        with pytest.raises(GltfError) as info:
            read_generated_glb(path)
        msg = str(info.value)
        assert "\n" not in msg and len(msg) < 400 and key[1] in msg, (key, msg)


def test_the_plugin_gives_the_same_verdicts(files):
    _, out = files
    listing = "\n".join(str(p) for p in out.values()) + "\n"
    r = subprocess.run(["node", str(ROOT / "tools" / "fuzz_plugin.mjs"), str(ROOT / "js" / "src")], input=listing,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    verdicts = {v["file"]: v for v in map(json.loads, r.stdout.splitlines()) if "verdict" in v}
    assert len(verdicts) == len(out)
    for key, path in out.items():
        v = verdicts[path.name]
        if key in OK:
            assert v["verdict"] == "ok", v
        else:
            assert v["verdict"] == "refused" and "generate" in v["detail"], (key, v)

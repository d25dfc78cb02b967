"""Generated layers, the numpy reference (core/generate.py): a tile's instances are a pure function
of the recipe, the seed, the tile and the index; the guaranteed spacing holds across tiles."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

import axialdeform as ad
from axialdeform.core.errors import AxialDeformError, ParamError
from axialdeform.core.generate import Generate, anchor_weights, generate_tile, generate_tiles, tile_size, tiles_around

STONE = ad.load_mesh("stone")
RECIPE = Generate(rate=4.0, tile=8.0, min_distance=0.35, seed=11, bend=0.15)


def test_a_tile_is_made_again_identically_in_any_order():
    a = generate_tiles(RECIPE, STONE, [(0, 0), (-2, 3), (5, -1)])
    b = np.concatenate([generate_tile(RECIPE, STONE, *t)[0] for t in [(0, 0), (-2, 3), (5, -1)]])
    assert a.tobytes() == b.tobytes()
    far = generate_tile(RECIPE, STONE, -2, 3)[0]
    assert far.tobytes() == a[256:512].tobytes()  # made alone, later: the same bytes
    assert not np.array_equal(generate_tile(RECIPE, STONE, 0, 0)[0], generate_tile(RECIPE, STONE, 0, 1)[0])
    other = Generate(rate=4.0, tile=8.0, min_distance=0.35, seed=12, bend=0.15)
    assert not np.array_equal(generate_tile(other, STONE, 0, 0)[0], generate_tile(RECIPE, STONE, 0, 0)[0])


def test_the_guaranteed_distance_holds_within_and_across_tiles():
    tiles = [(x, z) for x in range(-2, 2) for z in range(-2, 2)]
    p = generate_tiles(RECIPE, STONE, tiles)
    d, _ = cKDTree(p[:, [10, 12]]).query(p[:, [10, 12]], k=2)
    assert d[:, 1].min() >= RECIPE.min_distance * (1 - 1e-6), d[:, 1].min()
    # and without it (jitter over the whole cell) instances come closer: the check can fail
    loose = Generate(rate=4.0, tile=8.0, min_distance=0.0, seed=11, bend=0.15)
    q = generate_tiles(loose, STONE, tiles)
    assert cKDTree(q[:, [10, 12]]).query(q[:, [10, 12]], k=2)[0][:, 1].min() < RECIPE.min_distance
    # every instance lies in its own tile
    m, c = tile_size(RECIPE)
    for k, (tx, tz) in enumerate(tiles):
        part = p[k * m * m:(k + 1) * m * m]
        assert (part[:, 10] >= tx * 8.0).all() and (part[:, 10] < (tx + 1) * 8.0).all()
        assert (part[:, 12] >= tz * 8.0).all() and (part[:, 12] < (tz + 1) * 8.0).all()


def test_the_rate_the_fields_and_the_ground():
    m, c = tile_size(RECIPE)
    assert m * m / RECIPE.tile ** 2 == pytest.approx(RECIPE.rate, rel=0.3)
    g = Generate(rate=2.0, tile=10.0, seed=3, bend=0.1, scale=(0.5, 2.0), twist=0.4, taper=0.3)
    p, kept = generate_tile(g, STONE, 1, 1)
    assert p.shape[1] == 19 and kept.all()
    assert p[:, 16].min() >= 0.5 and p[:, 16].max() <= 2.0 and p[:, 16].std() > 0.2
    assert np.abs(p[:, 17]).max() <= 0.4 and p[:, 18].min() >= 0 and p[:, 18].max() < 0.3
    # the offsets hold the anchor (a lying stone's middle) still: D(t_a) = 0, and a blade's root: d1 = 0
    d = p[:, :10].reshape(-1, 5, 2)
    assert np.abs(np.einsum("k,nkc->nc", anchor_weights(STONE), d)).max() < 1e-6
    assert np.abs(d).max() <= 4 * 0.1 * STONE.axis.length + 1e-6 and np.abs(d).max() > 0.1 * STONE.axis.length
    grass = ad.load_mesh(str(Path(__file__).resolve().parents[2] / "examples" / "landscape" / "grass.obj"))
    assert np.array_equal(anchor_weights(grass), [1, 0, 0, 0, 0])
    assert np.abs(generate_tile(g, grass, 0, 0)[0][:, 0:2]).max() == 0
    assert (p[:, 14] >= 0).all() and (p[:, 14] < 2 * math.pi).all() and p[:, [13, 15]].max() == 0
    # each stands on the ground: its lowest bent point near y = 0 (the bend moves it by its offsets)
    pos, _ = ad.deform(STONE, p)
    low = pos[:, :, 1].min(axis=1)
    assert np.abs(low).max() <= 2 * 0.1 * STONE.axis.length * 2.0 + 1e-5


def test_tiles_around_a_point_nearest_first():
    t = tiles_around(RECIPE, 4.0, 4.0, 9.0)
    assert tuple(t[0]) == (0, 0)
    assert {tuple(x) for x in t} >= {(-1, -1), (1, 1), (-1, 1), (1, -1)}
    assert all(max(abs(x), abs(z)) <= 2 for x, z in t)


@pytest.mark.parametrize("field,value,expected", [
    ("rate", 0, "rate: expected a finite number > 0"),
    ("tile", float("nan"), "tile: expected a finite number > 0"),
    ("seed", -1, "seed: expected an integer 0 .. 4294967295"),
    ("min_distance", 0.6, "min_distance: expected less than the cell side"),
    ("taper", 1.0, "taper: expected a number in [0, 1)"),
    ("scale", (2.0, 1.0), "scale: expected [lo, hi] with 0 < lo <= hi"),
])
def test_bad_recipes_name_the_field(field, value, expected):
    kw = dict(rate=4.0, tile=8.0, min_distance=0.1, seed=1)
    kw[field] = value
    with pytest.raises(AxialDeformError, match="generate: " + expected.replace("[", r"\[").replace("]", r"\]")
                       .replace("(", r"\(").replace(")", r"\)")):
        Generate(**kw)


SCENE = """[[layer]]
name = "stones"
mesh = "stone"

[layer.generate]
rate = 1.5
tile = 8.0
min_distance = 0.5
seed = 3
bend = 0.15
scale = [0.6, 1.2]
extent = [-10, -10, 10, 10]
"""


def test_a_scene_file_layer_is_generated_over_its_extent(tmp_path):
    path = tmp_path / "gen.toml"
    path.write_text(SCENE)
    scene = ad.Scene.load(path)
    layer = scene.layers[0]
    recipe = Generate(rate=1.5, tile=8.0, min_distance=0.5, seed=3, bend=0.15, scale=(0.6, 1.2))
    from axialdeform.core.generate import generate_extent

    assert layer.params.tobytes() == generate_extent(recipe, STONE, (-10, -10, 10, 10)).tobytes()
    assert 400 < len(layer.params) < 800 and layer.params.shape[1] == 19
    assert (layer.params[:, 10] >= -10).all() and (layer.params[:, 10] < 10).all()
    assert layer.generate.extent == (-10.0, -10.0, 10.0, 10.0)


@pytest.mark.parametrize("change,message", [
    (("rate = 1.5", "rate = -1"), r"gen.toml:6: key 'rate': expected a finite number > 0, found -1"),
    (("extent = [-10, -10, 10, 10]\n", ""), r"gen.toml:\d+: key 'generate'.*needs an extent"),
    (("seed = 3", "seed = 3\ncolour = 1"), r"key 'colour': unknown key in layer 1 generate"),
    (("min_distance = 0.5", "min_distance = 2.0"), r"gen.toml:8: key 'min_distance': expected less than the cell side"),
    (("extent = [-10, -10, 10, 10]", "extent = [10, -10, -10, 10]"), r"key 'extent': expected finite \[x0, z0, x1, z1\] with x1 > x0"),
    (("seed = 3", "seed = 3\naltitude = [0, 2]"), r"gen.toml:10: key 'altitude': altitude and slope bands need the scene's height-map"),
    (("seed = 3", "seed = 3\nslope = [10, 100]"), r"gen.toml:10: key 'slope': expected \[lo, hi\] with lo <= hi in degrees, 0..90"),
    (("seed = 3", "seed = 3\ntint = 1.5"), r"gen.toml:10: key 'tint': expected an amount in \[0, 1\]"),
    (("seed = 3", 'seed = 3\nanchor = "top"'), r"gen.toml:10: key 'anchor': expected one of bottom, center, origin"),
    (("seed = 3", "seed = 3\nlift = [1, 0]"), r"gen.toml:10: key 'lift': expected \[lo, hi\] with lo <= hi"),
    (("seed = 3", "seed = 3\ntint_color = [1, 2, 0]"), r"gen.toml:10: key 'tint_color': expected three linear RGB"),
    (("seed = 3", 'seed = 3\ndensity = "nowhere.png"'), r"gen.toml:10: key 'density'.*nowhere.png"),
    (("[[layer]]", f'[terrain]\nmesh = "{(Path(ad.__file__).parent / "meshes" / "stone.obj").as_posix()}"\n[[layer]]'),
     r"key 'generate': a generated layer stands on a height-map terrain"),
])
def test_bad_generate_recipes_name_the_file_line_and_key(tmp_path, change, message):
    path = tmp_path / "gen.toml"
    path.write_text(SCENE.replace(*change))
    with pytest.raises(AxialDeformError, match=message):
        ad.Scene.load(path)


def test_view_walks_a_generated_scene_and_refuses_a_bad_walk(tmp_path):
    import subprocess
    import sys

    path = tmp_path / "gen.toml"
    path.write_text(SCENE)
    shot = tmp_path / "far.png"
    run = [sys.executable, "-m", "axialdeform", "view", str(path), "--headless", "--size", "160x120"]
    r = subprocess.run([*run, "--frames", "4", "--walk", "40,0", "--screenshot", str(shot)], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert shot.stat().st_size > 1000
    r = subprocess.run([*run, "--walk", "1"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "--walk: expected DX,DZ (two finite numbers), found '1'" in r.stderr
    assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_info_describes_a_scene_file_and_its_generated_layers(tmp_path):
    import subprocess
    import sys

    path = tmp_path / "gen.toml"
    path.write_text(SCENE)
    r = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(path)], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    n = len(ad.Scene.load(path).layers[0].params)
    assert f"(1 layers, {n} instances)" in r.stdout
    assert f"layer:     stones: stone, {n} instances (generated: rate 1.5, tiles of 8, min_distance 0.5, seed 3, " \
           "extent [-10.0, -10.0, 10.0, 10.0], reach 24)" in r.stdout, r.stdout
    path.write_text(SCENE.replace("seed = 3", 'seed = 3\ntint = 0.3\nlift = [0, 1]\nanchor = "center"'))
    r = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(path)], capture_output=True, text=True, timeout=300)
    assert "reach 24, lift [0.0, 1.0], anchor center, tint 0.3)" in r.stdout, r.stdout
    r = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(path), "--axes", "parts"], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 2 and "is a scene file" in r.stderr and "Traceback" not in r.stderr


def test_several_meshes_in_one_layer_share_its_grid_by_weights(tmp_path):
    """mesh = [a, b] with weights: one generated layer a mesh, named NAME-1, NAME-2; each instance of the
    recipe is one mesh's (disjoint shares of u20), about in proportion to the weights."""
    from axialdeform.core.generate import generate_tile

    grass = Path(__file__).resolve().parents[2] / "examples" / "landscape" / "grass.obj"
    (tmp_path / "grass.obj").write_bytes(grass.read_bytes())
    path = tmp_path / "mix.toml"
    path.write_text(SCENE.replace('mesh = "stone"', 'mesh = ["stone", "grass.obj"]').replace("seed = 3", "seed = 3\nweights = [3, 1]"))
    scene = ad.Scene.load(path)
    assert [layer.name for layer in scene.layers] == ["stones-1", "stones-2"]
    a, b = (layer.generate.generate for layer in scene.layers)
    assert a.choice == (0.0, 0.75) and b.choice == (0.75, 1.0)
    ka = generate_tile(a, scene.layers[0].mesh, 0, 0)[1]
    kb = generate_tile(b, scene.layers[1].mesh, 0, 0)[1]
    assert not (ka & kb).any() and (ka | kb).all() and 0.6 < ka.mean() < 0.9
    # the same cells' places: one grid
    pa = generate_tile(a, scene.layers[0].mesh, 0, 0)[0]
    pb = generate_tile(b, scene.layers[1].mesh, 0, 0)[0]
    assert np.array_equal(pa[:, [10, 12]], pb[:, [10, 12]])
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.replace("seed = 3", "seed = 3\nweights = [3, 1]"))
    with pytest.raises(AxialDeformError, match=r"bad.toml:\d+: key 'weights': weights pick among several meshes"):
        ad.Scene.load(bad)
    bad.write_text(SCENE.replace('mesh = "stone"', 'mesh = ["stone", "grass.obj"]').replace("seed = 3", "seed = 3\nweights = [3]"))
    with pytest.raises(AxialDeformError, match=r"key 'weights': expected 2 finite positive"):
        ad.Scene.load(bad)


def test_anchor_and_lift_place_the_instance_as_scatter_does():
    """anchor = center sinks a stone to its middle, origin puts the mesh's origin on the ground; lift raises
    each by its own amount in [lo, hi]; the anchor stays where it is put whatever the bend."""
    from axialdeform.core.generate import generate_tile
    from axialdeform.core.mesh import anchor_point

    base = Generate(rate=2.0, tile=8.0, seed=4, bend=0.2)
    bottom = generate_tile(base, STONE, 0, 0)[0]
    for anchor in ("center", "origin"):
        p = generate_tile(Generate(rate=2.0, tile=8.0, seed=4, bend=0.2, anchor=anchor), STONE, 0, 0)[0]
        a = anchor_point(STONE, anchor, 1)
        assert np.allclose(p[:, 11], -a[1]) and np.allclose(p[:, [10, 12]], bottom[:, [10, 12]])
        # the anchor's place on the axis: the offsets there vanish (D(t_a) = 0)
        from axialdeform.core.deform import bernstein

        t = STONE.axis.parameter(a[None, :])[0]
        at = np.einsum("q,nqc->nc", bernstein(np.array(t)), p[:, :10].reshape(-1, 5, 2))
        assert np.abs(at).max() < 1e-6
    lifted = generate_tile(Generate(rate=2.0, tile=8.0, seed=4, bend=0.2, lift=(0.5, 1.5)), STONE, 0, 0)[0]
    up = lifted[:, 11] - bottom[:, 11]
    assert (up >= 0.5 - 1e-6).all() and (up <= 1.5 + 1e-6).all() and np.ptp(up) > 0.5


def test_the_recipe_struct_is_the_one_list_of_a_recipes_numbers(stone):
    """glsl/generate.glsl's AxialRecipe declares a recipe's numbers once: generate.vert's uniforms, the npm
    module's table (RECIPE_FIELDS) and WebGPU's uniform nodes are written from it by js/build.mjs, and the
    numbers the Python library computes (recipe_uniforms) are exactly its fields."""
    import re

    from axialdeform.core.generate import recipe_uniforms

    glsl = Path(__file__).resolve().parents[2] / "glsl"
    body = re.search(r"struct AxialRecipe \{(.*?)\};", (glsl / "generate.glsl").read_text(), re.S).group(1)
    fields = re.findall(r"^\s*\w+\s+(\w+);", body, re.M)
    assert len(fields) >= 28
    assert sorted(recipe_uniforms(Generate(rate=1.0, tile=4.0), stone)) == sorted(fields)
    assert len(set(fields)) == len(fields)
    vert = (glsl / "generate.vert").read_text()
    assert [m for m in re.findall(r"^uniform \w+ u_(\w+);", vert, re.M) if m in fields] == fields


def test_yaw_draws_the_turn_in_its_range_and_its_default_is_the_whole_turn(stone):
    """``yaw = [lo, hi]``: ry = lo + (hi - lo) u2; the default [0, 2 pi] gives the records of a recipe without it
    bit for bit (f32(0) + f32(2 pi) u2 == f32(2 pi) u2)."""
    base = Generate(rate=2.0, tile=8.0, seed=3, bend=0.1)
    p, _ = generate_tile(base, stone, 1, -2)
    q, _ = generate_tile(Generate(rate=2.0, tile=8.0, seed=3, bend=0.1, yaw=(0.25, 0.75)), stone, 1, -2)
    assert (p[:, 14] >= 0).all() and p[:, 14].max() > 6.0
    assert (q[:, 14] >= 0.25).all() and (q[:, 14] <= 0.75).all() and np.ptp(q[:, 14]) > 0.4
    u2 = p[:, 14] / np.float32(2.0 * np.pi)
    assert np.allclose(q[:, 14], np.float32(0.25) + np.float32(0.5) * u2, atol=1e-6)
    assert np.array_equal(np.delete(p, 14, axis=1), np.delete(q, 14, axis=1))
    with pytest.raises(ParamError, match=r"generate: yaw: expected \[lo, hi\] with lo <= hi"):
        Generate(rate=1.0, yaw=(1.0, 0.0))


def test_a_clump_s_core_holds_the_share_of_its_instances_within_its_radius(stone):
    """``clump_core`` and ``clump_core_radius``: an instance with u25 < clump_core stands within the core's radius of
    its parent (R sqrt(u22) with R the core's), every other as without a core, bit for bit; a core wider than the
    clump is refused."""
    kw = dict(rate=4.0, tile=8.0, seed=9, bend=0.1, clump_cells=3, clump_radius=2.0)
    plain, _ = generate_tile(Generate(**kw), stone, 2, -1)
    small, _ = generate_tile(Generate(**{**kw, "clump_radius": 0.5}), stone, 2, -1)
    none, _ = generate_tile(Generate(**kw, clump_core=0.0, clump_core_radius=0.5), stone, 2, -1)
    every, _ = generate_tile(Generate(**kw, clump_core=1.0, clump_core_radius=0.5), stone, 2, -1)
    some, _ = generate_tile(Generate(**kw, clump_core=0.3, clump_core_radius=0.5), stone, 2, -1)
    assert np.array_equal(none, plain) and np.array_equal(every, small)
    cored = np.all(some == small, axis=1)
    assert np.all(cored | np.all(some == plain, axis=1))  # each instance one or the other, bit for bit
    assert cored.mean() == pytest.approx(0.3, abs=0.05)  # u25 < 0.3 for 144 instances
    with pytest.raises(ParamError, match=r"generate: clump_core_radius: expected at most clump_radius, 2 \(the core lies "
                                         r"within the clump\), found 2\.5"):
        Generate(**kw, clump_core=0.3, clump_core_radius=2.5)
    with pytest.raises(ParamError, match=r"generate: clump_core: expected an amount in \[0, 1\], found 1\.5"):
        Generate(**kw, clump_core=1.5, clump_core_radius=0.5)

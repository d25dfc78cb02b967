"""A generated layer's size is known and bounded before anything is made; the world ends where float32
still keeps the cell grid; the numbers generated are held to a parameter file's rules (docs/generate.md,
"Bounds")."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.errors import AxialDeformError, ParamError
from axialdeform.core.generate import (
    MAX_SLOTS,
    Generate,
    check_reach,
    generate_extent,
    generate_tiles,
    tile_size,
    tiles_around,
    tiles_in,
    world_edge,
)
from axialdeform.core.io.mesh import with_axes
from axialdeform.core.wind import Wind

ROOT = Path(__file__).resolve().parents[2]


def test_a_tile_of_more_cells_than_the_bound_is_refused_before_it_is_made():
    with pytest.raises(ParamError, match=r"rate: .*at most 1048576 cells"):
        Generate(rate=1e12)
    with pytest.raises(ParamError, match=r"rate: .*at most 1048576 cells"):
        Generate(rate=4e6, tile=16)
    with pytest.raises(ParamError, match=r"tile: .*at most 1048576 cells"):
        Generate(rate=1.0, tile=1e10)
    Generate(rate=4e6, tile=0.5)  # the same rate in small tiles: 1e6 cells a tile


def test_amplitudes_and_heights_are_bounded():
    with pytest.raises(ParamError, match="bend: expected at most 100"):
        Generate(rate=1, bend=1e30)
    with pytest.raises(ParamError, match="bend: expected at most 100"):
        Generate(rate=1, bend=(0.03, 1e30))
    with pytest.raises(ParamError, match="lift: .*world's edge"):
        Generate(rate=1, lift=(3e38, 3.4e38))
    with pytest.raises(ParamError, match="scale: "):
        Generate(rate=1, scale=(1.0, 1e30))
    with pytest.raises(ParamError, match="wind strength: expected at most 100"):
        Wind(strength=1e308)


def test_slots_are_counted_before_an_array_is_made(monkeypatch):
    g = Generate(rate=4.0, tile=16)  # 1 024 cells a tile
    with pytest.raises(ParamError, match=r"reach: .* expected at most 4194304 .*AXIALDEFORM_MAX_SLOTS"):
        check_reach(g, 2000.0)
    with pytest.raises(ParamError, match="the extent: .*AXIALDEFORM_MAX_SLOTS"):
        tiles_in(g, (-2100, -2100, 2100, 2100))
    monkeypatch.setenv("AXIALDEFORM_MAX_SLOTS", "1000")
    with pytest.raises(ParamError, match="at most 1000"):
        tiles_in(g, (0, 0, 1, 1))
    monkeypatch.setenv("AXIALDEFORM_MAX_SLOTS", str(100 * MAX_SLOTS))
    assert check_reach(g, 2000.0) > MAX_SLOTS
    monkeypatch.setenv("AXIALDEFORM_MAX_SLOTS", "lots")
    with pytest.raises(ParamError, match="AXIALDEFORM_MAX_SLOTS: expected a whole number"):
        check_reach(g, 10.0)


def test_a_tree_counts_its_axes():
    mesh = with_axes(ad.load_mesh("tree"), ROOT / "examples" / "forest" / "tree-axes.toml")
    g = Generate(rate=1.0, tile=16)
    k = mesh.tree.count
    n = math.ceil(math.sqrt(1.5 * MAX_SLOTS / k / 256))
    reach = (n - 1) * 8.0  # (2 reach / 16 + 1)^2 tiles of 256 slots: fits as one axis, not as K
    assert check_reach(g, reach) * k > MAX_SLOTS
    with pytest.raises(ParamError, match=rf"x {k} axes slots"):
        check_reach(g, reach, mesh.axis_count)


def test_the_world_ends_where_float32_keeps_the_grid():
    g = Generate(rate=1.0, tile=8.0, min_distance=0.5, seed=4)
    E = world_edge(g)
    assert E == 65536 * tile_size(g)[1]
    # the last tiles inside the world's corner: the guaranteed distance holds to c / 128
    corner = tiles_around(g, E - 1, E - 1, 12.0)
    assert len(corner) and ((corner.max(axis=0) + 1) * g.tile <= E).all()
    p = generate_tiles(g, ad.load_mesh("stone"), corner)
    xz = p[:, [10, 12]].astype(np.float64)
    d = np.hypot(*(xz[:, None, :] - xz[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 0.5 - tile_size(g)[1] / 128
    # beyond it nothing is made, however far (no error, no stacked instances)
    for far in (E + 50.0, 1e7, 1e8, 1e30):
        assert len(tiles_around(g, far, far, 24.0)) == 0
    with pytest.raises(ParamError, match="extent: expected the ground within the world's edge"):
        tiles_in(g, (1e7, 1e7, 1e7 + 10, 1e7 + 10))
    with pytest.raises(ParamError, match="extent: expected finite"):
        tiles_in(g, (-1e300 * 1e10, 0, 1, 1))
    with pytest.raises(ParamError, match="reach: expected a distance"):
        check_reach(g, 1e9)


def test_a_trees_extent_is_cut_by_its_positions():
    mesh = with_axes(ad.load_mesh("tree"), ROOT / "examples" / "forest" / "tree-axes.toml")
    k = mesh.tree.count
    assert k > 1
    g = Generate(rate=0.5, tile=16.0, seed=5)
    extent = (0.0, 0.0, 6.0, 6.0)
    every = generate_tiles(g, mesh, tiles_in(g, extent))
    p = generate_extent(g, mesh, extent)
    pos = p[:, 10 * k:10 * k + 3]
    assert len(every) > len(p) > 0
    assert ((pos[:, 0] >= 0) & (pos[:, 0] < 6) & (pos[:, 2] >= 0) & (pos[:, 2] < 6)).all()
    want = every[:, 10 * k], every[:, 10 * k + 2]
    assert len(p) == int(((want[0] >= 0) & (want[0] < 6) & (want[1] >= 0) & (want[1] < 6)).sum())


SCENE = """[[layer]]
name = "stones"
mesh = "stone"
[layer.generate]
rate = 1.0
tile = 8.0
extent = [-6, -6, 6, 6]
{extra}
"""


@pytest.mark.parametrize("extra, line, key", [
    ("bend = 1e30", 8, "bend"), ("bend = [0.03, 1e30]", 8, "bend"), ("lift = [3e38, 3.4e38]", 8, "lift"),
    ("reach = 1e9", 8, "reach"), ("reach = 1e308", 8, "reach"), ("min_distance = 0.1", 6, "tile"),
])
def test_a_scene_files_recipe_is_refused_on_the_keys_line(tmp_path, extra, line, key):
    path = tmp_path / "s.toml"
    path.write_text(SCENE.format(extra=extra).replace("tile = 8.0", "tile = 1e10" if key == "tile" else "tile = 8.0"))
    with pytest.raises(AxialDeformError) as info:
        ad.Scene.load(path)
    msg = str(info.value)
    assert f"s.toml:{line}: key '{key}'" in msg and "\n" not in msg


def test_a_scene_files_extent_past_the_world_is_refused(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SCENE.format(extra="").replace("[-6, -6, 6, 6]", "[-1e300, -6, 6, 6]"))
    with pytest.raises(AxialDeformError, match=r"s.toml:7: key 'extent': expected the ground within"):
        ad.Scene.load(path)


def test_huge_weights_split_the_instances_by_halves(tmp_path):
    path = tmp_path / "w.toml"
    path.write_text(SCENE.format(extra="weights = [1e308, 1e308]").replace('mesh = "stone"', 'mesh = ["stone", "leaf"]'))
    scene = ad.Scene.load(path)
    counts = [len(layer.params) for layer in scene.layers]
    assert len(counts) == 2 and min(counts) > 0.3 * sum(counts)


def test_a_layer_in_clumps_is_as_dense_along_its_extents_edges_as_inside():
    """In clumps an instance stands up to ``Generate.spread`` beyond its tile, so the instances standing in an
    extent come from the tiles within that distance of it too: without them the layer thins out along its edges
    (at an edge on a tile boundary, to about half: the rim's density was 0.87 of the inside's here)."""
    mesh = ad.load_mesh("stone")
    rim = inner = 0
    for seed in range(30):
        g = Generate(rate=1.0, tile=16.0, clump_cells=8, clump_radius=3.0, seed=seed)
        p = generate_extent(g, mesh, (0.0, 0.0, 64.0, 64.0))  # its edges on tile boundaries
        d = np.minimum.reduce([p[:, 10], 64 - p[:, 10], p[:, 12], 64 - p[:, 12]])
        rim += int(np.sum(d < 2))
        inner += int(np.sum(d >= 8))
    ratio = (rim / (64 ** 2 - 60 ** 2)) / (inner / 48 ** 2)
    assert abs(ratio - 1) < 0.08, ratio
    assert len(tiles_in(g, (0.0, 0.0, 64.0, 64.0))) == 36  # 4 x 4 tiles meet it, one more on each side within 11

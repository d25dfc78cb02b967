"""Height and density maps are bounded by pixels as textures are, checked from the image's header before a
pixel is decoded (a 21 KB PNG of a 4000 x 4000 flat height map is refused in one line); a user who wants a
larger height map read anyway allows a lower resolution (docs/scenes.md)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import axialdeform as ad
from axialdeform.core.errors import AxialDeformError
from axialdeform.core.surface import MAX_HEIGHTMAP_PIXELS, load_density, load_surface


def flat(path, side, level=128):
    Image.fromarray(np.full((side, side), level, np.uint8)).save(path, optimize=True)
    return path


def test_a_small_file_of_a_huge_height_map_is_refused_before_decoding(tmp_path):
    png = flat(tmp_path / "flat4000.png", 4000)
    assert png.stat().st_size < 64_000 and 4000 * 4000 > MAX_HEIGHTMAP_PIXELS
    r = subprocess.run([sys.executable, "-m", "axialdeform", "scatter", str(png), "stone", "-n", "5", "-o",
                        str(tmp_path / "p.adp")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "4000x4000" in r.stderr and "AXIALDEFORM_MAX_HEIGHTMAP_PIXELS" in r.stderr and "resample" in r.stderr


def test_a_scenes_terrain_is_bounded_and_resampled_when_allowed(tmp_path, monkeypatch):
    monkeypatch.setenv("AXIALDEFORM_MAX_HEIGHTMAP_PIXELS", "10000")
    side = 300
    levels = np.tile(np.linspace(0, 255, side).astype(np.uint8), (side, 1))  # a ramp along x
    Image.fromarray(levels).save(tmp_path / "ramp.png")
    scene = tmp_path / "s.toml"
    body = '\nname = "s"\nmesh = "stone"\n[layer.scatter]\ncount = 5\n'
    scene.write_text('[terrain]\nheightmap = "ramp.png"\nheight_scale = 4.0\nextent = [30.0, 30.0]\n[[layer]]' + body)
    with pytest.raises(AxialDeformError, match=r"s.toml:2: key 'heightmap': .*300x300 pixels; expected at most 10000"):
        ad.Scene.load(scene)
    scene.write_text('[terrain]\nheightmap = "ramp.png"\nheight_scale = 4.0\nextent = [30.0, 30.0]\nresample = true\n'
                     '[[layer]]' + body)
    loaded = ad.Scene.load(scene)
    rows, cols = loaded.terrain.grid
    assert rows * cols <= 10000 and rows == cols == 100
    y = np.asarray(loaded.terrain.positions).reshape(rows, cols, 3)[:, :, 1]
    assert y.min() == pytest.approx(0.0, abs=0.05) and y.max() == pytest.approx(4.0, abs=0.05)  # the levels kept
    assert np.all(np.diff(y[0]) >= -1e-6)  # still a ramp
    surface = load_surface(tmp_path / "ramp.png", resample=True)
    assert surface.grid == (100, 100)


def test_a_density_map_is_bounded(tmp_path, monkeypatch):
    flat(tmp_path / "d.png", 200)
    monkeypatch.setenv("AXIALDEFORM_MAX_DENSITY_PIXELS", "1000")
    with pytest.raises(AxialDeformError, match="200x200 pixels; expected at most 1000 .*AXIALDEFORM_MAX_DENSITY_PIXELS"):
        load_density(tmp_path / "d.png")
    monkeypatch.setenv("AXIALDEFORM_MAX_DENSITY_PIXELS", "lots")
    with pytest.raises(AxialDeformError, match="AXIALDEFORM_MAX_DENSITY_PIXELS: expected a whole number"):
        load_density(tmp_path / "d.png")

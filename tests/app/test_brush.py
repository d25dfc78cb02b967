"""The brush: paint where a generated layer grows (core/brush.py), in ``view --headless --paint``; the mask is
saved beside the scene file and read again whenever the scene loads."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.brush import Stroke, fold, mask_path, new_mask, paint
from axialdeform.core.errors import ParamError
from axialdeform.core.record import POSITION

ROOT = Path(__file__).resolve().parents[2]

SCENE = """
[terrain]
heightmap = "terrain.png"
height_scale = 6.0
extent = [40.0, 30.0]
[[layer]]
name = "stones"
mesh = "stone"
[layer.generate]
rate = 1.5
tile = 8.0
seed = 3
bend = 0.1
scale = [0.3, 0.6]
reach = 60.0
"""


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_a_dab_paints_the_pixels_within_its_radius_and_folds_into_the_density():
    mask = np.ones((20, 40), np.float32)  # over [0, 40) x [0, 20): one pixel a unit
    assert paint(mask, (0, 0, 40, 20), Stroke("s", 10.0, 10.0, 3.0, erase=True))
    cx, cz = np.meshgrid(np.arange(40) + 0.5, np.arange(20) + 0.5)
    inside = (cx - 10) ** 2 + (cz - 10) ** 2 <= 9
    assert (mask[inside] == 0).all() and (mask[~inside] == 1).all()
    assert not paint(mask, (0, 0, 40, 20), Stroke("s", 10.0, 10.0, 3.0, erase=True))  # nothing changed
    assert not paint(mask, (0, 0, 40, 20), Stroke("s", 100.0, 10.0, 3.0))  # off the ground
    density = np.full((2, 4), 0.5, np.float32)
    folded = fold(density, mask)
    assert folded.shape == mask.shape and (folded[inside] == 0).all() and (folded[~inside] == 0.5).all()
    assert fold(None, None) is None and new_mask().shape == (512, 512)
    with pytest.raises(ParamError, match="radius > 0"):
        Stroke("s", 0.0, 0.0, -1.0)


@pytest.mark.slow
def test_view_paints_saves_the_mask_and_the_scene_reads_it_again(tmp_path):
    (tmp_path / "terrain.png").write_bytes((ROOT / "examples" / "landscape" / "terrain.png").read_bytes())
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE)
    before = ad.Scene.load(scene).layers[0].params
    res = run("view", scene, "--headless", "--frames", "2", "--size", "320x240", "--paint", "stones:0,0,6:erase",
              "--paint", "stones:-12,5,3:erase")
    assert res.returncode == 0, res.stderr
    mask = mask_path(scene, "stones")
    assert mask.is_file() and f"wrote {mask}" in res.stdout
    shown = int(res.stdout.split(" instances")[0].rsplit(" ", 1)[1])
    after = ad.Scene.load(scene)
    p = after.layers[0].params[:, POSITION]
    assert after.layers[0].generate.mask == mask and mask in after.sources
    assert not (np.hypot(p[:, 0], p[:, 2]) < 6 - 0.1).any() and not (np.hypot(p[:, 0] + 12, p[:, 2] - 5) < 3 - 0.1).any()
    assert shown == len(p) < len(before)  # the viewer's GPU made what numpy makes from the saved mask
    kept = {tuple(r) for r in np.round(before[:, POSITION], 4)}
    assert {tuple(r) for r in np.round(p, 4)} <= kept  # erasing only takes away
    # painting back everywhere gives back every instance, exactly
    res = run("view", scene, "--headless", "--frames", "1", "--size", "320x240", "--paint", "stones:0,0,40")
    assert res.returncode == 0, res.stderr
    assert np.array_equal(ad.Scene.load(scene).layers[0].params, before)


@pytest.mark.parametrize("paint_arg, message", [
    ("stones:1,2", r"argument --paint: expected LAYER:X,Z,R\[:erase\] with R > 0, found 'stones:1,2'"),
    ("stones:1,2,3:rub", r"argument --paint: expected LAYER:X,Z,R\[:erase\]"),
    ("stones:1,2,-3", r"argument --paint: expected LAYER:X,Z,R\[:erase\] with R > 0"),
    ("rocks:1,2,3", r"brush: layer: expected a generated layer \(stones\), found 'rocks'"),
])
@pytest.mark.slow
def test_a_bad_stroke_is_one_line_and_exit_2(tmp_path, paint_arg, message):
    import re

    (tmp_path / "terrain.png").write_bytes((ROOT / "examples" / "landscape" / "terrain.png").read_bytes())
    (tmp_path / "s.toml").write_text(SCENE)
    res = run("view", tmp_path / "s.toml", "--headless", "--frames", "1", "--size", "160x120", f"--paint={paint_arg}")
    assert res.returncode == 2 and "Traceback" not in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and re.search(message, res.stderr), res.stderr
    assert not mask_path(tmp_path / "s.toml", "stones").exists()


@pytest.mark.slow
def test_the_brush_finds_the_ground_under_a_pixel(tmp_path):
    """The window's brush paints where the cursor points: the ground point it finds projects back to the pixel."""
    from axialdeform.core.generate_ground import ground_height
    from axialdeform.viewer import Viewer

    (tmp_path / "terrain.png").write_bytes((ROOT / "examples" / "landscape" / "terrain.png").read_bytes())
    (tmp_path / "s.toml").write_text(SCENE)
    v = Viewer.create(ad.Scene.load(tmp_path / "s.toml"), headless=True, size=(320, 240))
    try:
        v.step(1)
        view, proj = v.matrices()
        for px in ((160, 120), (60, 200), (250, 80)):
            x, z = v.brush.at(*px)
            h = ground_height(v.generate.maps, np.array([[x, z]], np.float32))[0][0]
            c = np.array([x, h, z, 1.0]) @ (np.asarray(view, np.float64) @ np.asarray(proj, np.float64))
            assert ((c[0] / c[3] + 1) / 2 * 320, (1 - c[1] / c[3]) / 2 * 240) == pytest.approx(px, abs=0.5)
        assert v.brush.at(160, 0) is None or v.brush.at(160, 0) != v.brush.at(160, 120)
        assert v.brush.stroke(Stroke("stones", *v.brush.at(160, 120), 3.0, erase=True))
        assert "" not in v._tiles  # made again on the next frame
        v.step(1)
    finally:
        v.release()
        v.wnd.destroy()

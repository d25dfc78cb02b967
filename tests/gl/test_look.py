"""The look is one value object: its defaults are written once (core/look.py),
it refuses nonsense with our error, and what it says reaches the picture."""

from __future__ import annotations

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core import look as L


def test_defaults_are_written_once_and_validated():
    look = ad.Look()
    assert look.light_dir == L.LIGHT_DIR and look.background == L.BACKGROUND and look.light_color == L.LIGHT_COLOR
    assert look.replace(fast=True).msaa == 0 and not look.replace(fast=True).draws_shadow
    assert look.replace(ground=False).draws_shadow and not look.replace(ground=False).draws_ground
    for bad, words in (({"light_dir": (1, 2)}, "look.light_dir"), ({"light_dir": (0, 0, 0)}, "non-zero"),
                       ({"ambient": 1.5}, "look.ambient"), ({"samples": -1}, "look.samples"),
                       ({"hidden_line": "x"}, "look.hidden_line"), ({"light_color": (1, float("nan"), 1)}, "finite")):
        with pytest.raises(ad.core.ArgumentError, match=words):
            ad.Look(**bad)


def test_the_look_reaches_the_picture(ctx, stone):
    params = ad.random_params(stone, 30, seed=3, spacing=2.0 * stone.axis.length)
    plain = ad.render_image(stone, params, (96, 72), ctx=ctx, look=ad.Look(fast=True)).astype(int)
    red = ad.render_image(stone, params, (96, 72), ctx=ctx, look=ad.Look(fast=True, light_color=(1.0, 0.2, 0.2)))
    back = ad.render_image(stone, params, (96, 72), ctx=ctx, look=ad.Look(fast=True, background=(0, 0, 0)))
    lit = np.abs(plain - back.astype(int)).sum(axis=2) == 0  # the instances: the same over both backgrounds
    assert lit.mean() > 0.05
    red = red.astype(int)
    # a red sun: the stones' green and blue fall, their red stays near
    assert (plain[lit][:, 1] - red[lit][:, 1]).mean() > 10
    assert abs((plain[lit][:, 0] - red[lit][:, 0]).mean()) < 5
    assert (back[~lit] == 0).all()


def test_scene_files_map_onto_the_look(tmp_path):
    ad.write_params(tmp_path / "s.adp", ad.random_params(ad.load_mesh("stone"), 3, seed=1))
    (tmp_path / "s.toml").write_text('background = [0.1, 0.2, 0.3]\n[light]\ndirection = [0, 1, 0]\nambient = 0.5\n'
                                     'color = [1, 0.5, 0.25]\nsky = [0.1, 0.1, 0.9]\n'
                                     '[[layer]]\nname = "a"\nmesh = "stone"\nparams = "s.adp"\n')
    look = ad.Scene.load(tmp_path / "s.toml").look
    assert look == ad.Look(light_dir=(0, 1, 0), ambient=0.5, light_color=(1, 0.5, 0.25), sky_color=(0.1, 0.1, 0.9),
                           background=(0.1, 0.2, 0.3))


def test_the_ground_reaches_the_edges_of_the_picture(ctx, stone):
    """Near and far enclose the ground plane: no straight cut where the picture's
    bottom (and, below the horizon, its sides) would show the background."""
    params = ad.random_params(stone, 300, seed=2003, variation=ad.Variation(bend=0.14), placement="disc", spacing=0.9 * stone.axis.length)
    cam = ad.frame_instances(stone, params, 160 / 120, elevation=30.0, azimuth=20.0)  # the demo's camera
    img = ad.render_image(stone, params, (160, 120), ctx=ctx, camera=cam, look=ad.Look(samples=0)).astype(int)
    bg = np.round(np.array(ad.Look().background) * 255)
    ground = np.abs(img - bg).sum(axis=2) > 12
    assert ground[-1].all(), "the bottom row shows the background: the ground is cut by the near plane"
    assert ground[60:, 0].all() and ground[60:, -1].all(), "the sides below the horizon show the background"

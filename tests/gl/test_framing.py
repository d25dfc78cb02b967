"""Automatic framing fills the picture and the orbit camera
is the one camera the viewer and the framing share."""

from __future__ import annotations

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.camera import OrbitCamera, frame_instances, orbit_axes


def _extent(image):
    fg = np.abs(image.astype(int) - image[0, 0].astype(int)).max(axis=2) > 8
    ys, xs = np.nonzero(fg)
    h, w = fg.shape
    edge = fg[0].any() or fg[-1].any() or fg[:, 0].any() or fg[:, -1].any()
    return (xs.max() - xs.min() + 1) / w, (ys.max() - ys.min() + 1) / h, edge


@pytest.mark.parametrize("name, count, size", [("stone", 1, (320, 240)), ("stone", 150, (320, 240)),
                                               ("leaf", 200, (200, 300)), ("leaf", 1, (240, 240)),
                                               ("stone", 3000, (200, 150))])  # 3000: framed by spheres
def test_automatic_framing_fills_80_percent_and_cuts_nothing(ctx, name, count, size):
    mesh = ad.load_mesh(name)
    params = ad.random_params(mesh, count, seed=4, variation=ad.Variation(bend=0.15))
    image = ad.render_image(mesh, params, size, ctx=ctx, look=ad.Look(ground=False))  # what differs from the background: instances
    width, height, touches = _extent(image)
    assert max(width, height) >= 0.8, (width, height)
    assert not touches  # nothing cut off at the border


def test_projected_outline_is_centred_and_inside(stone):
    params = ad.random_params(stone, 300, seed=9, variation=ad.Variation(bend=0.2))
    cam = frame_instances(stone, params, 4 / 3)
    world, _ = ad.deform(stone.axis, stone.positions, stone.normals, params)
    p = np.c_[world.reshape(-1, 3), np.ones(world.shape[0] * world.shape[1])].astype(np.float32)
    clip = p @ cam.view() @ cam.projection(4 / 3)  # pyrr layout: row vectors
    ndc = clip[:, :2] / clip[:, 3:]
    assert np.abs(ndc).max() <= 1.0
    assert np.abs(ndc).max(axis=0).max() >= 0.9
    assert np.abs(ndc.min(axis=0) + ndc.max(axis=0)).max() < 0.05  # centred


def test_orbit_camera_turns_and_zooms(stone):
    params = ad.random_params(stone, 20, seed=1)
    orbit = OrbitCamera.framing(stone, params, 1.5, azimuth=35.0, elevation=30.0)
    cam = frame_instances(stone, params, 1.5, azimuth=35.0, elevation=30.0)
    assert np.allclose(orbit.eye, cam.eye) and np.allclose(orbit.target, cam.target)
    d = orbit.distance
    orbit.orbit(10.0, 100.0)
    assert orbit.azimuth == pytest.approx(45.0) and orbit.elevation == 89.0
    orbit.zoom(0.5)
    assert orbit.distance == pytest.approx(d / 2)
    assert np.linalg.norm(orbit.eye - orbit.target) == pytest.approx(d / 2)
    to_eye, right, up = orbit_axes("z", 0.0, 90.0)
    assert np.allclose(to_eye, [0, 0, 1]) and abs(right @ up) < 1e-12
    with pytest.raises(ad.core.ArgumentError):
        OrbitCamera([0, 0, 0], 1.0, up="w")

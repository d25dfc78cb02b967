"""core/bounds.py: the one home of the instance spheres and the scene box."""

from __future__ import annotations

import numpy as np

import axialdeform as ad
from axialdeform.core.bounds import box_corners, instance_bounds, scene_box


def test_spheres_hold_every_deformed_vertex(stone):
    params = ad.random_params(stone, 40, seed=5, variation=ad.Variation(bend=0.3))
    centers, radii = instance_bounds(stone, params)
    assert centers.shape == (40, 3) and radii.shape == (40,)
    world, _ = ad.deform(stone.axis, stone.positions, stone.normals, params)
    dist = np.linalg.norm(world - centers[:, None, :], axis=2)
    assert (dist <= radii[:, None] * (1 + 1e-6)).all()
    assert (dist.max(axis=1) > 0.5 * radii).all()  # and they are not absurdly large


def test_scene_box_holds_the_spheres_and_is_tight(stone):
    params = ad.random_params(stone, 25, seed=2, variation=ad.Variation(bend=0.2))
    centers, radii = instance_bounds(stone, params)
    lo, hi = scene_box(stone, params)
    assert lo.shape == hi.shape == (3,)
    assert np.allclose(lo, (centers - radii[:, None]).min(axis=0))
    assert np.allclose(hi, (centers + radii[:, None]).max(axis=0))
    empty_lo, empty_hi = scene_box(stone, np.zeros((0, 16)))
    assert (empty_lo == -1).all() and (empty_hi == 1).all()


def test_box_corners_are_the_eight_corners():
    c = box_corners([0, 1, 2], [3, 4, 5])
    assert c.shape == (8, 3)
    assert {tuple(r) for r in c} == {(x, y, z) for x in (0, 3) for y in (1, 4) for z in (2, 5)}


def test_callers_use_the_one_home(stone, monkeypatch):
    """Framing a picture asks core.bounds for the instances' outline: the camera has no bounds
    maths of its own."""
    from axialdeform.core import bounds, camera

    calls = []

    def spy(*args, **kwargs):
        calls.append(1)
        return bounds.outline_points(*args, **kwargs)

    monkeypatch.setattr(camera, "outline_points", spy)
    camera.frame_instances(stone, ad.random_params(stone, 5, seed=1), 4 / 3)
    assert calls
    assert ad.core.instance_bounds is instance_bounds


def test_outline_points_by_budget(stone):
    from axialdeform.core.bounds import outline_points

    params = ad.random_params(stone, 30, seed=8, variation=ad.Variation(bend=0.3))
    world, _ = ad.deform(stone.axis, stone.positions, stone.normals, params)
    exact, r = outline_points(stone, params)  # 30 x 58 vertices: all of them
    assert exact.shape == (30 * stone.vertex_count, 3) and not r.any()
    assert np.abs(exact - world.reshape(-1, 3)).max() < 1e-5 * stone.axis.length
    some, r = outline_points(stone, params, budget=30 * stone.vertex_count - 1)  # the extreme vertices only
    assert 0 < len(some) < len(exact) and not r.any()
    d = np.abs(some[:, None, :] - world.reshape(-1, 3)[None]).max(axis=2).min(axis=1)
    assert d.max() < 1e-5 * stone.axis.length  # each is a deformed vertex
    centers, radii = outline_points(stone, params, budget=10)  # the instance spheres
    c2, r2 = instance_bounds(stone, params)
    assert np.array_equal(centers, c2) and np.array_equal(radii, r2)

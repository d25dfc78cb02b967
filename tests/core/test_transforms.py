"""core/transforms.py: the one home of rotations, quaternions and angles."""

from __future__ import annotations

import numpy as np

import axialdeform as ad
from axialdeform.core import deform, fit, transforms
from axialdeform.core.deform import displace
from axialdeform.core.io import gltf as export


def test_conversions_agree():
    rng = np.random.default_rng(4)
    angles = rng.uniform(-np.pi, np.pi, (200, 3))
    rot = transforms.rotation_matrices(angles)
    q = transforms.quaternions_from_angles(angles)
    assert q.shape == (200, 4) and (q[:, 3] >= 0).all()
    assert np.abs(transforms.matrices_from_quaternions(q) - rot).max() < 1e-12
    assert np.abs(transforms.rotation_matrices(transforms.angles_from_matrices(rot)) - rot).max() < 1e-12
    # a rotation vector along z by the angle rz is Rz(rz)
    w = np.zeros((200, 3))
    w[:, 2] = angles[:, 2]
    z_only = np.zeros_like(angles)
    z_only[:, 2] = angles[:, 2]
    assert np.abs(transforms.matrices_from_rotation_vectors(w) - transforms.rotation_matrices(z_only)).max() < 1e-12
    assert np.allclose(transforms.matrices_from_rotation_vectors(np.zeros((2, 3))), np.eye(3))


def test_every_caller_uses_the_one_home():
    assert deform.rotation_matrices is transforms.rotation_matrices
    assert export.quaternions_from_angles is transforms.quaternions_from_angles
    assert fit.angles_from_matrices is transforms.angles_from_matrices


def test_the_bend_is_written_once(monkeypatch):
    """The fit bends its model with core.deform.displace, the reference's own function."""
    calls = []

    def spy(*args, **kwargs):
        calls.append(1)
        return displace(*args, **kwargs)

    monkeypatch.setattr(fit, "displace", spy)
    stone = ad.load_mesh("stone")
    params = ad.random_params(stone, 2, seed=3, variation=ad.Variation(bend=0.1))
    targets, _ = ad.deform(stone.axis, stone.positions, stone.normals, params)
    result = fit.fit_params(stone, targets)
    assert calls and np.abs(result.params[:, :10] - params[:, :10]).max() < 1e-4 * stone.axis.length

"""core/transforms.py: the one home of rotations, quaternions and angles."""

from __future__ import annotations

import inspect

import numpy as np

from axialdeform.core import deform, fit, transforms
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
    for mod in (deform, export, fit):
        src = inspect.getsource(mod)
        assert "def rotation_matrices" not in src and "def _rodrigues" not in src
        assert "def quaternions_from_angles" not in src and "def angles_from_matrices" not in src
        assert "np.arctan2" not in src and "quaternion.cross" not in src


def test_the_bend_is_written_once():
    src = inspect.getsource(fit)
    assert "displace(" in src and "+= disp[..., 0]" not in src

"""Bounds of deformed instances without deforming them (pure numpy).

The one home of the bounding spheres around each instance and the box
around all of them; the camera framing, the ground plane and the viewer
call these.
"""

from __future__ import annotations

import numpy as np

from .transforms import rotation_matrices
from .params import ANGLES, OFFSETS, POSITION, as_params

__all__ = ["instance_bounds", "scene_box", "box_corners"]


def instance_bounds(mesh, params) -> tuple[np.ndarray, np.ndarray]:
    """Bounding spheres of the deformed instances, without deforming them.

    mesh : BaseMesh; params : (n, 16) float.
    Returns ``centers : (n, 3) float64`` and ``radii : (n,) float64`` (world
    units).  The bend moves no vertex further than the largest offset (the
    Bernstein weights sum to 1), and a rotation keeps distances, so each
    sphere holds its whole instance.
    """
    params = as_params(params).astype(np.float64)
    center = np.asarray(mesh.axis.center, dtype=np.float64)
    radius = float(np.linalg.norm(mesh.positions.astype(np.float64) - center, axis=1).max())
    bend = np.linalg.norm(params[:, OFFSETS].reshape(-1, 5, 2), axis=2).max(axis=1)
    centers = np.einsum("nij,j->ni", rotation_matrices(params[:, ANGLES]), center) + params[:, POSITION]
    return centers, radius + bend


def scene_box(mesh, params) -> tuple[np.ndarray, np.ndarray]:
    """The axis-aligned box around every instance's bounding sphere.

    Returns ``lo : (3,) float64`` and ``hi : (3,) float64``; with no
    instances, the box from -1 to 1.
    """
    centers, radii = instance_bounds(mesh, params)
    if len(centers) == 0:
        return np.full(3, -1.0), np.full(3, 1.0)
    return (centers - radii[:, None]).min(axis=0), (centers + radii[:, None]).max(axis=0)


def box_corners(lo, hi) -> np.ndarray:
    """The eight corners of the box ``lo``..``hi``: ``(8, 3) float64``."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    bits = (np.arange(8)[:, None] >> np.arange(3)[::-1]) & 1
    return np.where(bits == 1, hi, lo)

"""Bounds of deformed instances without deforming them (pure numpy).

The one home of the bounding spheres around each instance and the box
around all of them; the camera framing, the ground plane and the viewer
call these.
"""

from __future__ import annotations

import numpy as np

from .deform import bernstein, displace
from .transforms import rotation_matrices
from .params import ANGLES, OFFSETS, POSITION, as_params

__all__ = ["instance_bounds", "scene_box", "box_corners", "outline_points"]


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


def _support_indices(positions: np.ndarray, directions: int = 194) -> np.ndarray:
    """Indices of the vertices that lie furthest along ``directions`` spread
    evenly over the sphere (a Fibonacci lattice) and along the six axes:
    the vertices that make a mesh's outline from any side."""
    k = np.arange(directions) + 0.5
    z = 1.0 - 2.0 * k / directions
    phi = np.pi * (1.0 + 5.0**0.5) * k
    r = np.sqrt(1.0 - z * z)
    dirs = np.concatenate([np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1), np.eye(3), -np.eye(3)])
    p = np.asarray(positions, dtype=np.float64)
    return np.unique(np.argmax((p - p.mean(axis=0)) @ dirs.T, axis=0))


def outline_points(mesh, params, *, budget: int = 100_000) -> tuple[np.ndarray, np.ndarray]:
    """Points (with radii) whose spheres hold the deformed instances, as
    tightly as ``budget`` allows: what a camera must keep in view.

    mesh : BaseMesh; params : (n, 16) float; budget : the most points made.
    Returns ``points : (m, 3) float64`` and ``radii : (m,) float64``:

    * every deformed vertex (radius 0) when ``n * vertices <= budget``
      (exact);
    * else the deformed vertices that are extreme along 200 directions of
      the base mesh (radius 0; an approximation: a bent instance may reach
      a little past them, which the framing's margin covers);
    * else the instance spheres of :func:`instance_bounds` (always hold).
    """
    params = as_params(params)
    n, v = len(params), mesh.vertex_count
    if n == 0:
        return np.zeros((0, 3)), np.zeros(0)
    if n * v <= budget:
        idx = np.arange(v)
    else:
        idx = _support_indices(mesh.positions)
        if n * len(idx) > budget:
            return instance_bounds(mesh, params)
    pts = mesh.positions[idx].astype(np.float64)
    p64 = params.astype(np.float64)
    disp = np.einsum("vk,nkc->nvc", bernstein(mesh.axis.parameter(pts), 4), p64[:, OFFSETS].reshape(-1, 5, 2))
    world = displace(mesh.axis, pts, disp) @ np.swapaxes(rotation_matrices(p64[:, ANGLES]), 1, 2)
    world += p64[:, None, POSITION]
    return world.reshape(-1, 3), np.zeros(n * len(idx))

"""Levels of detail of a base mesh (pure numpy + fast-simplification + trimesh).

Every level is a quadric simplification (``fast_simplification``, the
maintained binding of Fast-Quadric-Mesh-Simplification) of the base mesh's
triangles.  All levels are deformed with the BASE mesh's control axis
(``mesh.axis``: axis, ``lo``, ``L`` computed from the full mesh), so an
instance bends the same way at every level.  Each level carries its
geometric error in model units: the symmetric Hausdorff distance between it
and the full mesh, measured from the vertices of each to the surface of the
other, both sampled densely (vertices plus 2048 surface points each; the
nearest sampled point stands in for the nearest surface point, which can only
over-estimate the error by the sampling spacing).
The renderer picks a level per instance from that error projected to pixels
(docs/culling.md).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .errors import ParamError
from .mesh import area_weighted_normals

__all__ = ["LodLevel", "build_lod_levels", "LOD_REDUCTIONS", "MIN_LOD_TRIANGLES", "check_lod_error"]

#: fraction of the triangles removed for levels 1, 2, 3 (level 0 is the full mesh)
LOD_REDUCTIONS = (0.5, 0.8, 0.93)
#: a mesh with fewer triangles is not simplified (it keeps one level, with a warning)
MIN_LOD_TRIANGLES = 48
_SAMPLE = 2048


@dataclass(frozen=True, eq=False)
class LodLevel:
    """One level of detail: positions (n, 3) float32, normals (n, 3) float32
    (unit, area-weighted), faces (m, 3) uint32, and ``error`` (model units,
    0 for the full mesh)."""

    positions: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    error: float

    @property
    def vertex_count(self) -> int:
        return len(self.positions)

    @cached_property
    def edges(self) -> np.ndarray:
        """(k, 2) uint32 unique undirected edges (for wireframe)."""
        e = np.sort(self.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        return np.unique(e, axis=0).astype(np.uint32)


def check_lod_error(pixels) -> float:
    """The allowed screen-space error in pixels: a finite number > 0, else ParamError."""
    try:
        value = float(pixels)
    except (TypeError, ValueError):
        raise ParamError(f"lod_error: expected a number of pixels > 0, found {pixels!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise ParamError(f"lod_error: expected a number of pixels > 0, found {pixels!r}")
    return value


def _surface_points(tmesh, count: int, seed: int) -> np.ndarray:
    """The vertices of a trimesh plus points sampled on its surface: (k, 3) float64."""
    import trimesh

    points, _ = trimesh.sample.sample_surface(tmesh, count, seed=seed)
    cloud = np.vstack([tmesh.vertices, points])
    if len(cloud) > 2 * count:
        cloud = cloud[np.random.default_rng(seed).choice(len(cloud), 2 * count, replace=False)]
    return cloud


def _one_sided(points: np.ndarray, targets: np.ndarray) -> float:
    """Largest distance from a point of ``points`` (k, 3) to its nearest point of ``targets`` (j, 3)."""
    worst = 0.0
    t2 = np.einsum("ij,ij->i", targets, targets)
    for a in range(0, len(points), 512):
        p = points[a:a + 512]
        d2 = np.einsum("ij,ij->i", p, p)[:, None] - 2.0 * p @ targets.T + t2[None, :]
        worst = max(worst, float(np.sqrt(max(d2.min(axis=1).max(), 0.0))))
    return worst


def build_lod_levels(mesh, reductions=LOD_REDUCTIONS) -> list[LodLevel]:
    """Level 0 (the base mesh itself) and up to ``len(reductions)`` simplified levels.

    A mesh with fewer than :data:`MIN_LOD_TRIANGLES` triangles keeps one level
    and says so (a ``UserWarning``); a level that removes less than a fifth of
    the previous level's triangles, or keeps fewer than 4, is dropped.
    """
    import fast_simplification
    import trimesh

    base = LodLevel(mesh.positions, mesh.normals, mesh.faces, 0.0)
    if len(mesh.faces) < MIN_LOD_TRIANGLES:
        warnings.warn(f"{mesh.name}: {len(mesh.faces)} triangles are too few to simplify "
                      f"(LOD needs at least {MIN_LOD_TRIANGLES}); drawing one level", UserWarning, stacklevel=2)
        return [base]
    full = trimesh.Trimesh(mesh.positions.astype(np.float64), mesh.faces.astype(np.int64), process=False)
    full_cloud = _surface_points(full, _SAMPLE, 1)
    levels = [base]
    for reduction in reductions:
        points, faces = fast_simplification.simplify(mesh.positions.astype(np.float32), mesh.faces.astype(np.int64),
                                                     target_reduction=float(reduction))
        faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        if len(faces) < 4 or len(faces) > 0.8 * len(levels[-1].faces):
            continue
        used = np.unique(faces)  # drop vertices no triangle uses
        remap = np.full(len(points), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        points = np.asarray(points, dtype=np.float64)[used]
        faces = remap[faces]
        simple = trimesh.Trimesh(points, faces, process=False)
        simple_cloud = _surface_points(simple, _SAMPLE, 2)
        error = max(_one_sided(full_cloud, simple_cloud), _one_sided(simple_cloud, full_cloud))
        levels.append(LodLevel(points.astype(np.float32), area_weighted_normals(points, faces),
                               faces.astype(np.uint32), max(error, levels[-1].error)))
    if len(levels) == 1:
        warnings.warn(f"{mesh.name}: simplification removed too few triangles; drawing one level",
                      UserWarning, stacklevel=2)
    return levels

"""What the ground is like at a point: the features a learned layer's intensity depends on (docs/learn.md).

A height-map terrain (:class:`~axialdeform.core.generate_ground.GroundMaps`' grid of world heights) gives
each point of the ground

* ``altitude``: the height (world units);
* ``slope``: the angle of the ground to level, in degrees;
* ``curvature``: the Laplacian of the height (1 / world units: > 0 in a hollow, < 0 on a ridge);
* ``eastness``, ``northness``: the downhill direction's x and z (its aspect as two numbers, 0 where level);
* ``water``: the distance (world units) to the nearest pixel of a mask (a river, a lake), when one is given.

Every feature is computed on the height map's grid (central differences, ``numpy.gradient``; the slope, the
curvature and the aspect of the heights smoothed by a Gaussian of one grid step, so an 8-bit height map's
terraces do not stripe them) and read at a point by bilinear interpolation of that grid
(``scipy.ndimage.map_coordinates``), so the same point on the same terrain always has the same features, and
a second terrain has features of the same meaning.  Pure
numpy and scipy: no GL here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .errors import ParamError
from .generate_ground import ground_height

__all__ = ["FEATURES", "GroundFeatures"]

#: every feature a ground has, in order (``water`` only with a mask)
FEATURES = ("altitude", "slope", "curvature", "eastness", "northness", "water")


@dataclass(frozen=True, eq=False)
class GroundFeatures:
    """The features of a height map's ground, as grids of its vertices.

    Attributes
    ----------
    grids : dict of str to (rows, cols) float64
        One grid a feature (:data:`FEATURES`; ``water`` only with a mask).
    lo : (2,) float64
        The grid's first vertex (x0, z0).
    step : (2,) float64
        The grid's spacing along x and z (world units).
    maps : GroundMaps or None
        The height map they were computed from (its own triangles give :meth:`normals`).
    """

    grids: dict
    lo: np.ndarray
    step: np.ndarray
    maps: object = None

    @classmethod
    def of(cls, maps, mask: np.ndarray | None = None) -> GroundFeatures:
        """The features of ``maps``' height map (a :class:`~axialdeform.core.generate_ground.GroundMaps` with
        heights), and with ``mask`` ((rows, cols) bool or grey, over the same ground, True/white = water) the
        distance to it."""
        if maps is None or maps.heights is None:
            raise ParamError("learn: terrain: expected a height-map terrain (the ground's features come from its heights)")
        h = np.asarray(maps.heights, np.float64)
        if min(h.shape) < 3:
            raise ParamError(f"learn: terrain: expected a height map of at least 3x3 vertices, found {h.shape[1]}x{h.shape[0]}")
        step = 1.0 / np.asarray(maps.h_inv, np.float64)
        gz, gx = np.gradient(ndimage.gaussian_filter(h, 1.0, mode="nearest"), step[1], step[0])
        grad = np.hypot(gx, gz)
        lap = np.gradient(gx, step[0], axis=1) + np.gradient(gz, step[1], axis=0)
        safe = np.where(grad > 1e-12, grad, 1.0)
        grids = {"altitude": h, "slope": np.degrees(np.arctan(grad)), "curvature": lap,
                 "eastness": np.where(grad > 1e-12, -gx / safe, 0.0), "northness": np.where(grad > 1e-12, -gz / safe, 0.0)}
        if mask is not None:
            wet = np.asarray(mask) > 0.5
            if not wet.any():
                raise ParamError("learn: mask: expected some white pixels (water), found none")
            # the mask's pixels over the height map's ground, distances in world units
            size = np.array(h.shape[::-1], np.float64) - 1.0
            pix = size * step / np.array(wet.shape[::-1], np.float64)
            dist = ndimage.distance_transform_edt(~wet, sampling=(pix[1], pix[0]))
            rows, cols = np.mgrid[0:h.shape[0], 0:h.shape[1]]
            r = np.clip((rows / max(h.shape[0] - 1, 1)) * wet.shape[0] - 0.5, 0, wet.shape[0] - 1)
            c = np.clip((cols / max(h.shape[1] - 1, 1)) * wet.shape[1] - 0.5, 0, wet.shape[1] - 1)
            grids["water"] = ndimage.map_coordinates(dist, [r, c], order=1)
        return cls(grids, np.asarray(maps.h_lo, np.float64), step, maps)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(f for f in FEATURES if f in self.grids)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """The ground the grid covers: (x0, z0, x1, z1)."""
        rows, cols = self.grids["altitude"].shape
        x1, z1 = self.lo + self.step * np.array([cols - 1, rows - 1])
        return float(self.lo[0]), float(self.lo[1]), float(x1), float(z1)

    def at(self, xz: np.ndarray, names=None) -> np.ndarray:
        """The features ``names`` (default all) at points ``xz`` : (n, 2), as (n, k) float64 (clamped to the
        grid beyond its edge)."""
        xz = np.asarray(xz, np.float64).reshape(-1, 2)
        g = (xz - self.lo) / self.step
        rows, cols = self.grids["altitude"].shape
        coords = [np.clip(g[:, 1], 0, rows - 1), np.clip(g[:, 0], 0, cols - 1)]
        names = list(names or self.names)
        return np.stack([ndimage.map_coordinates(self.grids[n], coords, order=1, mode="nearest")
                         for n in names], axis=1).reshape(len(xz), len(names))

    def normals(self, xz: np.ndarray) -> np.ndarray:
        """The ground's unit normals (n, 3) float64 at points ``xz`` (n, 2): of the height map's own triangles,
        unsmoothed, as the generator leans an object toward them
        (:func:`~axialdeform.core.generate_ground.ground_height`; clamped to the grid beyond its edge)."""
        xz = np.asarray(xz, np.float32).reshape(-1, 2)
        grad = ground_height(self.maps, xz)[3].astype(np.float64)
        n = np.column_stack([-grad[:, 0], np.ones(len(xz)), -grad[:, 1]])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

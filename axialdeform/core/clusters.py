"""Matern cluster processes, with a core: parents ``kappa`` a square unit, children uniform in a disc of ``radius``
about theirs, a ``share`` of them in a smaller disc of ``core_radius`` (clumps within clumps; docs/learn.md, "The
spacing").  Ripley's K, the pair correlation's excess ``g - 1``, and what the clumps add to a Poisson fit's
information.  Pure numpy and scipy: no GL here.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["lens_area", "matern_cluster_excess", "matern_cluster_k", "cluster_information"]


def lens_area(d, r1, r2) -> np.ndarray:
    """The area two discs of radii ``r1`` and ``r2`` share, their centres ``d`` apart (arrays broadcast)."""
    d, r1, r2 = np.broadcast_arrays(*(np.asarray(a, np.float64) for a in (d, r1, r2)))
    dd = np.maximum(d, 1e-300)
    c1 = np.clip((dd * dd + r1 * r1 - r2 * r2) / (2.0 * dd * r1), -1.0, 1.0)
    c2 = np.clip((dd * dd + r2 * r2 - r1 * r1) / (2.0 * dd * r2), -1.0, 1.0)
    kite = np.sqrt(np.maximum((-dd + r1 + r2) * (dd + r1 - r2) * (dd - r1 + r2) * (dd + r1 + r2), 0.0))
    area = r1 * r1 * np.arccos(c1) + r2 * r2 * np.arccos(c2) - 0.5 * kite
    area = np.where(d >= r1 + r2, 0.0, area)
    return np.where(d <= np.abs(r1 - r2), math.pi * np.minimum(r1, r2) ** 2, area)


def _mixture(radius: float, share: float, core_radius: float) -> list[tuple[float, float, float]]:
    """The pairs of discs two objects of one clump stand in, with their chances: ``(weight, r1, r2)``."""
    if share <= 0.0 or core_radius <= 0.0:
        return [(1.0, radius, radius)]
    p = share
    return [((1.0 - p) ** 2, radius, radius), (p * p, core_radius, core_radius), (2.0 * p * (1.0 - p), core_radius, radius)]


def matern_cluster_excess(r, kappa: float, radius: float, share: float = 0.0, core_radius: float = 0.0) -> np.ndarray:
    """``g(r) - 1`` of a Matern cluster process (parents ``kappa`` a square unit, children uniform in a disc of
    ``radius``; with a core: a ``share`` of them in a disc of ``core_radius``): the density of the difference of
    two children's places over ``kappa``, ``sum w |D(r1) & D(r2, r)| / (pi r1^2 pi r2^2 kappa)`` over the pairs of
    discs they stand in (:func:`_mixture`); zero beyond ``2 radius``; ``1 / (kappa pi radius^2)`` at 0 without a
    core."""
    r = np.asarray(r, np.float64)
    out = sum(w * lens_area(r, a, b) / (math.pi * a * a * math.pi * b * b) for w, a, b in _mixture(radius, share, core_radius))
    return out / kappa


#: Gauss-Legendre nodes for the chance that two children of one clump (one in the core, one anywhere) stand
#: within r of each other (an integral over the core child's distance from the parent)
_NODES = np.polynomial.legendre.leggauss(48)


def _within(r: np.ndarray, a: float, b: float) -> np.ndarray:
    """``P(|A - B| <= r)`` for A uniform in a disc of radius ``a`` and B in a concentric one of ``b``: the closed
    form (Stoyan, Kendall and Mecke) when ``a == b``, else ``int_0^a 2t/a^2 |D(t, r) & D(0, b)| / (pi b^2) dt``."""
    r = np.asarray(r, np.float64)
    if a == b:
        z = np.clip(r / (2.0 * a), 0.0, 1.0)
        return 2.0 + ((8 * z * z - 4) * np.arccos(z) - 2 * np.arcsin(z) + 4 * z * np.sqrt((1 - z * z) ** 3)
                      - 6 * z * np.sqrt(1 - z * z)) / math.pi
    t = (_NODES[0] + 1.0) * 0.5 * a
    w = _NODES[1] * 0.5 * a * 2.0 * t / (a * a)
    return (lens_area(t[None, :], r[:, None], b) / (math.pi * b * b)) @ w


def cluster_information(x: np.ndarray, rate: np.ndarray, shape: tuple[int, int], cell: tuple[float, float], kappa: float,
                    radius: float, share: float = 0.0, core_radius: float = 0.0) -> np.ndarray:
    """``B = int int lambda(u) lambda(v) (g(|u - v|) - 1) x(u) x(v)^T du dv`` over the window, on the quadrature's
    grid (``x`` and the fitted ``rate`` at its ``shape = (rows, cols)`` cells, row after row, each ``cell`` =
    (width, depth)), by a convolution with ``g - 1`` (:func:`matern_cluster_excess`; pairs within ``2 radius``,
    each cell with itself too; ``g - 1`` averaged over 4 x 4 points a cell, so a core smaller than a cell counts
    as much as it adds): what a Matern cluster process (with a core: ``share``, ``core_radius``) adds to the
    Poisson likelihood's information (Waagepetersen 2007; spatstat's ``vcov.kppm``: the covariance is
    ``F^-1 (F + B) F^-1``)."""
    from scipy.signal import fftconvolve

    rows, cols = shape
    mx, mz = (min(int(math.ceil(2.0 * radius / c)), n) for c, n in zip(cell, (cols, rows)))
    dz, dx = np.meshgrid(np.arange(-mz, mz + 1) * cell[1], np.arange(-mx, mx + 1) * cell[0], indexing="ij")
    sub = (np.arange(4) + 0.5) / 4 - 0.5  # 4 x 4 points a cell
    kernel = np.mean([matern_cluster_excess(np.hypot(dz + a * cell[1], dx + b * cell[0]), kappa, radius, share, core_radius)
                      for a in sub for b in sub], axis=0)
    y = (x * (rate * cell[0] * cell[1])[:, None]).reshape(rows, cols, -1)
    z = np.stack([fftconvolve(y[:, :, c], kernel, mode="same") for c in range(y.shape[2])], axis=2)
    return y.reshape(rows * cols, -1).T @ z.reshape(rows * cols, -1)


def matern_cluster_k(r: np.ndarray, kappa: float, radius: float, share: float = 0.0, core_radius: float = 0.0) -> np.ndarray:
    """Ripley's K of a Matern cluster process: parents ``kappa`` a square unit, children uniform in a disc of
    ``radius`` (with a core: a ``share`` of them in a disc of ``core_radius``): ``pi r^2 + P(|D1 - D2| <= r) /
    kappa``, D1 and D2 two children's places about their parent (Stoyan, Kendall and Mecke)."""
    r = np.asarray(r, np.float64)
    return math.pi * r ** 2 + sum(w * _within(r, a, b) for w, a, b in _mixture(radius, share, core_radius)) / kappa

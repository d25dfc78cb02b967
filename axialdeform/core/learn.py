"""Scenery by example: a generated layer learned from objects placed on a ground (docs/learn.md).

An *example* is where objects stand (``xz`` on a terrain, optional sizes and kinds) inside a window of
ground.  :func:`learn_layers` fits, per kind:

* **the intensity**, piecewise linear on a log scale in each of the ground's features
  (:mod:`~axialdeform.core.ground_features`): ``log lambda(x) = b0 + sum_k b_k t_k(x)``, each term a feature or
  a hinge of it at one of its octiles; the maximum-likelihood fit of an inhomogeneous Poisson process by
  Berman-Turner quadrature (a grid of dummy points over the window; Newton's method on the standardized
  terms, a small ridge).  A term stays only while it is significant (Bonferroni over the features; dropped
  weakest first), so a pattern that ignores the slope does not learn a slope from noise -- or, with
  ``errors="poisson"``, while it lowers Akaike's criterion (the example's own ground reproduced);
* **the spacing**: the hard core (the smallest distance between two objects), and whether the objects stand
  in clumps or apart: Diggle's global test of the inhomogeneous L-function against 19 Poisson patterns of the
  fitted intensity (maximum absolute deviation over r in [0.5, 5] mean spacings; each pattern's lambda at its
  own level).  Clumps are fitted as a Matern cluster process (parents ``kappa`` a square unit, children
  uniform in a disc of radius ``R``; with a core, a share of them within a smaller radius: clumps within
  clumps, where the example has the close pairs they make) by minimum contrast on ``K(r)^(1/4)``;
* **the marks** (:mod:`~axialdeform.core.marks`): the sizes as scales (median 1: their nine quantiles at 0, 1/8,
  .., 1, which the generator draws through piecewise linearly), the turn about up, and the bend, twist, taper
  and tint of an example of the library's records, where the example has them.

:func:`layer_recipe` turns a learned layer into a generated layer's recipe over a ground -- the same ground or
ANOTHER one (the learned relation to slope, altitude and water applied there): a rate and a density map of
``lambda / rate``, and clumps where the example has them.  Pure numpy and scipy: no GL here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize
from scipy.spatial import cKDTree
from scipy.stats import norm

from .clusters import cluster_information, matern_cluster_excess, matern_cluster_k
from .errors import ParamError
from .generate import CLUMP_PARENTS
from .marks import LEAN_FLOOR, Marks, learn_marks
from .recipe import MAX_COUNT

__all__ = ["Example", "Intensity", "Spacing", "LearnedLayer", "fit_intensity", "fit_spacing", "l_function", "largest_deviations",
           "learn_layers", "layer_recipe", "matern_cluster_k", "matern_cluster_excess", "expected_count", "own_rate",
           "SIGNIFICANT", "AIC_Z", "SIMULATIONS", "ERRORS"]

#: a term's coefficient stays while |b / se| is at least this
SIGNIFICANT = 2.0
#: with Akaike's criterion (errors="poisson"): a term stays while |b / se| is at least this, sqrt(2)
AIC_Z = math.sqrt(2.0)
#: the most kinds one example may have (one generated layer each)
MAX_KINDS = 64
#: which standard errors decide an example in clumps' ground terms (learn_layers)
ERRORS = ("clumps", "poisson")
#: Poisson patterns Diggle's test compares the example with (rank 1 of 20: the 5 % level)
SIMULATIONS = 19
#: the spacings (in mean spacings 1 / sqrt(lambda)) the L-function is compared over
SPAN = (0.5, 5.0)
#: a core of the clumps stays when its minimum contrast is below this share of the plain clumps' (clumps within
#: clumps: many more close pairs than one radius makes; plain Matern patterns: 0.5 to 1 in 5 of 6 seeds, 0.16 in
#: one; with a core: 0.003 to 0.14)
CORE_GAIN = 0.25
#: a core stays only where the example has more close pairs than the plain clumps make: within the fitted core's
#: radius its pair count ``lambda n K(a) / 2`` above theirs by at least CORE_Z standard errors of a count (the
#: square root of theirs).  Plain Matern patterns whose contrast alone kept a core: -0.1 to 1.0; cores of bei,
#: longleaf and the synthetic patterns with one: 4 to 22
CORE_Z = 3.0
#: Diggle's test takes each pattern's lambda as at least this share of its mean (:func:`_diggle`)
TEST_FLOOR = 0.05


@dataclass(frozen=True, eq=False)
class Example:
    """Objects standing on a ground.

    Attributes
    ----------
    xz : (n, 2) float64
        Where each object stands (world units).
    window : (4,) float
        The ground the example covers, (x0, z0, x1, z1).
    size : (n,) float64 or None
        Each object's size (any unit: a trunk's diameter, a record's scale).
    kind : (n,) str or None
        Each object's kind (a species): one layer a kind.
    yaw : (n,) float64 or None
        Each object's turn about up (radians), where the example has it.
    source : str
        Where it came from (error messages).
    records : (n, 10 K + 6 (+3, +6)) float64 or None
        Each object's record (of K axes), where the example is made of the library's records: its bend (each
        axis's), twist, taper and tint are learned too.
    up : (n, 3) float64 or None
        Each object's up (its y in the world), where the example has its turn: how far it leans toward the
        ground's normal is learned too.
    """

    xz: np.ndarray
    window: tuple
    size: np.ndarray | None = None
    kind: np.ndarray | None = None
    yaw: np.ndarray | None = None
    source: str = "<example>"
    records: np.ndarray | None = None
    up: np.ndarray | None = None

    @property
    def area(self) -> float:
        x0, z0, x1, z1 = self.window
        return (x1 - x0) * (z1 - z0)

    def subset(self, keep: np.ndarray) -> Example:
        """The objects where ``keep`` (n,) bool is True, in the same window."""
        size, kind, yaw, records, up = (None if a is None else a[keep] for a in
                                        (self.size, self.kind, self.yaw, self.records, self.up))
        return Example(self.xz[keep], self.window, size, kind, yaw, self.source, records, up)


@dataclass(frozen=True, eq=False)
class Intensity:
    """``lambda(x) = exp(b0 + sum_k b_k t_k(x))`` objects a square unit, each term ``t_k`` a ground feature
    ``f`` or a hinge of it, ``max(0, f - knot)``: piecewise linear in each feature.

    Attributes
    ----------
    names : tuple of str
        The feature of each term (none: a constant intensity).
    coef : (k + 1,) float64
        ``b0`` then one coefficient a term, in the features' own units.
    z : (k,) float64
        Each coefficient over its standard error (the Wald statistic, on standardized terms).
    knots : (k,) float64 or None
        Each term's knot (NaN: the feature itself).
    lo, hi : (k,) float64 or None
        Each term's feature's range over the example's ground: a ground beyond it (another terrain) is read
        as its nearest end, so the fit is never extrapolated.
    """

    names: tuple
    coef: np.ndarray
    z: np.ndarray
    knots: np.ndarray | None = None
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None

    @property
    def labels(self) -> tuple[str, ...]:
        """Each term in words: ``slope``, or ``slope>4.25`` for ``max(0, slope - 4.25)``."""
        knots = self.knots if self.knots is not None else np.full(len(self.names), np.nan)
        return tuple(n if np.isnan(k) else f"{n}>{k:.4g}" for n, k in zip(self.names, knots))

    def terms(self, feats: np.ndarray) -> np.ndarray:
        """The terms ``t_k`` of features ``feats`` : (n, k) (a column a term, as :attr:`names`)."""
        feats = np.asarray(feats, np.float64).reshape(-1, len(self.names))
        if self.lo is not None:
            feats = np.clip(feats, self.lo, self.hi)
        if self.knots is None:
            return feats
        return np.where(np.isnan(self.knots), feats, np.maximum(0.0, feats - np.nan_to_num(self.knots)))

    def rate(self, feats: np.ndarray) -> np.ndarray:
        """``lambda`` at points of features ``feats`` : (n, k) (a column a term, as :attr:`names`)."""
        return np.exp(self.coef[0] + self.terms(feats) @ self.coef[1:])

    def rate_at(self, ground, xz: np.ndarray) -> np.ndarray:
        """``lambda`` at points ``xz`` (n, 2) of ``ground`` (a GroundFeatures; None: a constant intensity)."""
        xz = np.asarray(xz, np.float64).reshape(-1, 2)
        if not self.names:
            return np.full(len(xz), math.exp(self.coef[0]))
        return self.rate(ground.at(xz, self.names))


@dataclass(frozen=True)
class Spacing:
    """How the objects stand with respect to each other.

    Attributes
    ----------
    hard_core : float
        The smallest distance between two objects (world units).
    pattern : str
        ``"poisson"``, ``"cluster"`` (clumps) or ``"regular"`` (apart): Diggle's test at the 5 % level.
    cluster : tuple or None
        A cluster pattern's ``(kappa, radius)``: parents a square unit, the radius of a clump.
    core : tuple or None
        A cluster pattern's core, ``(share, radius)``: that share of each clump's objects stand within the smaller
        radius of its parent (clumps within clumps; None: none).
    """

    hard_core: float
    pattern: str
    cluster: tuple | None = None
    core: tuple | None = None

    @property
    def process(self) -> tuple | None:
        """The cluster process's numbers ``(kappa, radius, share, core_radius)`` (:func:`matern_cluster_k`'s), or None."""
        if self.cluster is None:
            return None
        return (*self.cluster, *(self.core or (0.0, 0.0)))


@dataclass(frozen=True, eq=False)
class LearnedLayer:
    """One kind of object learned from an example.

    Attributes
    ----------
    kind : str or None
        The kind (None: the example has one).
    count : int
        How many objects of it the example has.
    intensity : Intensity
    spacing : Spacing
    marks : Marks
        Sizes, turns, and the records' bends, twists, tapers and tints (:mod:`~axialdeform.core.marks`).
    window : (4,) float
        The example's ground (x0, z0, x1, z1).
    """

    kind: str | None
    count: int
    intensity: Intensity
    spacing: Spacing
    marks: Marks = Marks()
    window: tuple = (0.0, 0.0, 1.0, 1.0)

    def describe(self, digits: int = 4) -> str:
        """What was learned, in words: ``learned from N objects: log rate = ...; spacing: ...``."""
        terms = "".join(f" + {c:.{digits}g} {n}" for n, c in zip(self.intensity.labels, self.intensity.coef[1:]))
        s = self.spacing
        clumps = f", clumps: {s.cluster[0]:.{digits}g} a square unit, radius {s.cluster[1]:.{digits}g}" if s.cluster else ""
        if s.core:
            clumps += f", core: {s.core[0]:.{digits}g} of them within {s.core[1]:.{digits}g}"
        m, marks = self.marks, []
        if m.bend is not None:
            marks.append(f"offsets within {m.bend:.{digits}g}")
        if m.twist:
            marks.append(f"twist within {m.twist:.{digits}g}")
        if m.taper:
            marks.append(f"taper up to {m.taper:.{digits}g}")
        if m.align is not None and m.align >= LEAN_FLOOR:
            marks.append(f"leaning toward the ground's normal by {m.align:.{digits}g} of its slope")
        if m.tint is not None:
            marks.append(f"tint {m.tint[0]:.{digits}g} of ({', '.join(f'{c:.{digits}g}' for c in m.tint[1])}), hue {m.tint[2]:.{digits}g}")
        return (f"learned from {self.count} objects: log rate = {self.intensity.coef[0]:.{digits}g}{terms}; "
                f"spacing: {s.pattern}, hard core {s.hard_core:.{digits}g}{clumps}" + "".join(f"; {t}" for t in marks))


def _quadrature(example: Example, cells: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int]]:
    """Berman-Turner quadrature: the points (data then dummy: a grid of about ``cells`` square cells each way,
    row after row), their weights, 1 for data, and the grid's (rows, cols)."""
    x0, z0, x1, z1 = example.window
    nx = max(8, int(round(cells * math.sqrt((x1 - x0) / (z1 - z0)))))
    nz = max(8, int(round(cells * cells / nx)))
    gx, gz = np.meshgrid((np.arange(nx) + 0.5) / nx * (x1 - x0) + x0, (np.arange(nz) + 0.5) / nz * (z1 - z0) + z0)
    dummy = np.stack([gx.ravel(), gz.ravel()], axis=1)
    pts = np.concatenate([example.xz, dummy])
    cx = np.clip(((pts[:, 0] - x0) / (x1 - x0) * nx).astype(np.int64), 0, nx - 1)
    cz = np.clip(((pts[:, 1] - z0) / (z1 - z0) * nz).astype(np.int64), 0, nz - 1)
    cell = cz * nx + cx
    count = np.bincount(cell, minlength=nx * nz)
    w = example.area / (nx * nz) / count[cell]
    is_data = np.zeros(len(pts))
    is_data[:len(example.xz)] = 1.0
    return pts, w, is_data, (nz, nx)


def _newton(x: np.ndarray, w: np.ndarray, y: np.ndarray, start: float) -> tuple[np.ndarray, np.ndarray]:
    """The Poisson log-likelihood ``sum y x.b - sum w exp(x.b)``, less a ridge ``RIDGE |b|^2 / 2`` on the
    standardized terms (not the intercept), maximized: b and the inverse of its Hessian."""
    b = np.zeros(x.shape[1])
    b[0] = start
    ridge = np.full(len(b), RIDGE)
    ridge[0] = 0.0  # the intercept is free

    def loglik(c):
        return y @ (x @ c) - (w * np.exp(np.clip(x @ c, -700, 700))).sum() - 0.5 * ridge @ (c * c)

    for _ in range(100):
        mu = w * np.exp(np.clip(x @ b, -700, 700))
        grad = x.T @ (y - mu) - ridge * b
        fisher = (x * mu[:, None]).T @ x + np.diag(ridge) + 1e-9 * np.eye(len(b))
        step = np.linalg.solve(fisher, grad)
        ll = loglik(b)
        t = 1.0
        while t > 1e-6:  # halve the step until the likelihood grows
            if loglik(b + t * step) >= ll - 1e-12:
                break
            t /= 2
        b = b + t * step
        if np.abs(t * step).max() < 1e-10:
            break
    mu = w * np.exp(np.clip(x @ b, -700, 700))
    return b, np.linalg.pinv((x * mu[:, None]).T @ x + np.diag(ridge))


#: the ridge on a standardized term's coefficient: it keeps near-collinear hinges from running away, and is
#: negligible beside the likelihood of a pattern of more than a few objects
RIDGE = 1.0
#: the knots of each feature's hinges: its octiles over the example's ground
KNOTS = (0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875)


def fit_intensity(example: Example, ground=None, names=None, cells: int = 0, significant: float = SIGNIFICANT,
                  cluster: tuple | None = None, aic: bool = False) -> Intensity:
    """The intensity of ``example`` over ``ground``'s features ``names`` (default: all of them; none without a
    ground): log-linear in each feature and its hinges at the octiles (:data:`KNOTS`) of the feature over
    the example's ground, the terms that are not significant dropped: ``|b / se| <`` the larger of
    ``significant`` and the normal quantile of a 5 % chance over all the features (Bonferroni).  With
    ``cluster`` ((kappa, radius): a Matern cluster process, :func:`fit_spacing`'s) the standard errors are
    the cluster process's (:func:`~axialdeform.core.clusters.cluster_information`), not Poisson's: clumps make
    counts vary more.  ``aic``: a term stays while it lowers Akaike's criterion instead, ``|b / se| >=`` sqrt(2)
    (Wald's approximation of twice the log-likelihood it adds against the 2 its coefficient costs; no Bonferroni,
    ``significant`` unused): the terms that best predict the example's own ground, not the ones a test is sure of."""
    n = len(example.xz)
    if n == 0:
        raise ParamError(f"{example.source}: expected at least one object to learn from, found none")
    base = list(() if ground is None else (names or ground.names))
    cells = cells or int(min(250, max(48, math.sqrt(4 * n))))
    pts, w, y, shape = _quadrature(example, cells)
    cell = ((example.window[2] - example.window[0]) / shape[1], (example.window[3] - example.window[1]) / shape[0])
    raw = ground.at(pts, base) if base else np.zeros((len(pts), 0))
    term_names, knots, cols = [], [], []
    for i, name in enumerate(base):
        f = raw[:, i]
        if f[n:].std() <= 1e-12:
            continue  # a feature constant over the window says nothing
        term_names.append(name)
        knots.append(np.nan)
        cols.append(f)
        lo, hi = f[n:].min(), f[n:].max()
        for q in np.unique(np.quantile(f[n:], KNOTS)):  # not within 2 % of either end
            if lo + 0.02 * (hi - lo) < q < hi - 0.02 * (hi - lo):
                term_names.append(name)
                knots.append(float(q))
                cols.append(np.maximum(0.0, f - q))
    feats = np.stack(cols, axis=1) if cols else np.zeros((len(pts), 0))
    if aic:
        significant = AIC_Z
    elif cols:  # a 5 % chance over all the features, not each (Bonferroni; a feature's hinges go together)
        significant = max(significant, float(norm.isf(0.025 / len(set(term_names)))) * significant / SIGNIFICANT)
    mean, sd = feats[n:].mean(axis=0), feats[n:].std(axis=0)
    keep = [i for i in range(feats.shape[1]) if sd[i] > 1e-12]
    excess = first = None
    while True:
        x = np.concatenate([np.ones((len(pts), 1)), (feats[:, keep] - mean[keep]) / sd[keep]], axis=1)
        b, cov = _newton(x, w, y, math.log(n / example.area))
        if cluster is not None:  # the clumps' part of the information, once, at the fullest model
            if excess is None:
                grid = x[n:]  # the quadrature's dummy points: its grid, row after row
                excess = cluster_information(grid, np.exp(np.clip(grid @ b, -700, 700)), shape, cell, *cluster)
                first = list(keep)
            at = [0] + [1 + first.index(k) for k in keep]
            cov = cov + cov @ excess[np.ix_(at, at)] @ cov
        z = b[1:] / np.sqrt(np.maximum(np.diag(cov)[1:], 1e-300))
        if not keep or np.abs(z).min() >= significant:
            break
        keep.pop(int(np.argmin(np.abs(z))))
    coef = np.concatenate([[b[0] - np.sum(b[1:] * mean[keep] / sd[keep])], b[1:] / sd[keep]])
    seen = raw[n:][:, [base.index(term_names[i]) for i in keep]] if keep else np.zeros((0, 0))
    return Intensity(tuple(term_names[i] for i in keep), coef, z, np.array([knots[i] for i in keep]),
                     seen.min(axis=0) if keep else None, seen.max(axis=0) if keep else None)


def _border(xz: np.ndarray, window) -> np.ndarray:
    x0, z0, x1, z1 = window
    return np.minimum.reduce([xz[:, 0] - x0, x1 - xz[:, 0], xz[:, 1] - z0, z1 - xz[:, 1]])


def l_function(xz: np.ndarray, window, r: np.ndarray, rate: np.ndarray | None = None) -> np.ndarray:
    """The (inhomogeneous) L-function ``sqrt(K(r) / pi)`` of points ``xz`` (n, 2) in ``window`` at distances ``r``
    (m,), border-corrected: ``K(r) = sum_{i: b_i >= r} sum_{j != i, d_ij <= r} 1 / (lambda_i lambda_j) /
    sum_{i: b_i >= r} 1 / lambda_i`` (``b_i``: the distance to the window's edge; ``rate``: lambda at each point,
    default ``n / area``).  NaN where no point lies ``r`` inside the edge."""
    xz = np.asarray(xz, np.float64)
    x0, z0, x1, z1 = window
    lam = np.full(len(xz), len(xz) / ((x1 - x0) * (z1 - z0))) if rate is None else np.asarray(rate, np.float64)
    b = _border(xz, window)
    pairs = cKDTree(xz).query_pairs(float(np.max(r)), output_type="ndarray")
    i, j = np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]])
    d = np.linalg.norm(xz[i] - xz[j], axis=1)
    w = 1.0 / (lam[i] * lam[j])
    out = np.full(len(r), np.nan)
    for k, rk in enumerate(np.asarray(r, np.float64)):  # one distance at a time (tens), every pair at once
        inner = b >= rk
        norm = np.sum(1.0 / lam[inner])
        if norm > 0:
            out[k] = math.sqrt(np.sum(w[(d <= rk) & inner[i]]) / norm / math.pi)
    return out


def simulate(intensity: Intensity, ground, window, rng: np.random.Generator, top: float) -> np.ndarray:
    """A Poisson pattern of ``intensity`` in ``window`` (thinning from ``top`` >= its largest value): (k, 2)."""
    x0, z0, x1, z1 = window
    n = rng.poisson(top * (x1 - x0) * (z1 - z0))
    xz = np.stack([rng.uniform(x0, x1, n), rng.uniform(z0, z1, n)], axis=1)
    return xz[rng.uniform(0, top, n) < intensity.rate_at(ground, xz)]


def _largest_rate(intensity: Intensity, ground, window) -> float:
    x0, z0, x1, z1 = window
    gx, gz = np.meshgrid(np.linspace(x0, x1, 200), np.linspace(z0, z1, 200))
    return 1.05 * float(intensity.rate_at(ground, np.stack([gx.ravel(), gz.ravel()], axis=1)).max())


def expected_count(intensity: Intensity, ground, window, n: int = 200) -> float:
    """``int_W lambda``: the objects ``intensity`` puts in ``window`` (x0, z0, x1, z1), on ``n x n`` midpoints."""
    x0, z0, x1, z1 = window
    gx, gz = np.meshgrid(x0 + (np.arange(n) + 0.5) * (x1 - x0) / n, z0 + (np.arange(n) + 0.5) * (z1 - z0) / n)
    return float(intensity.rate_at(ground, np.stack([gx.ravel(), gz.ravel()], axis=1)).mean()) * (x1 - x0) * (z1 - z0)


def own_rate(intensity: Intensity, ground, xz: np.ndarray, total: float) -> np.ndarray:
    """``lambda`` at a pattern's points ``xz`` (n, 2), its level fitted to the pattern: ``lambda(x) n / total``
    (``total``: :func:`expected_count` over the pattern's window).  Each pattern's inhomogeneous L-function is
    taken with its own level, as spatstat's ``Linhom`` refits the model to each simulated pattern: else a pattern
    with more objects than expected has a larger L at every distance, and that spread hides the clumps."""
    return intensity.rate_at(ground, xz) * (len(xz) / total)


def largest_deviations(curves: np.ndarray) -> np.ndarray:
    """Diggle's statistic: each of ``curves`` (k, m) (an L-function at m distances) its largest absolute deviation
    from their mean over the distances, (k,) (NaN ignored)."""
    return np.nanmax(np.abs(curves - np.nanmean(curves, axis=0)), axis=1)


def _diggle(example: Example, intensity: Intensity, ground, seed: int, r: np.ndarray) -> str:
    """Diggle's global test of the example's L-function at ``r`` against :data:`SIMULATIONS` Poisson patterns of
    ``intensity`` (the largest deviation from the mean, ranked first of 20: the 5 % level): ``"poisson"``,
    ``"cluster"`` (above the mean where it deviates most) or ``"regular"`` (below).  Each pattern's lambda at its
    own level (:func:`own_rate`) and at least :data:`TEST_FLOOR` of its mean: a pattern with a pair of objects
    where the fitted lambda is near 0 (a fit of many hinges) would else weigh that pair by 1 / lambda^2 and
    deviate more than any clumps."""
    xz = example.xz
    total = expected_count(intensity, ground, example.window)

    def rate(p):  # its own level, and never below TEST_FLOOR of its mean
        return np.maximum(own_rate(intensity, ground, p, total), TEST_FLOOR * len(p) / example.area)

    observed = l_function(xz, example.window, r, rate(xz))
    rng = np.random.default_rng(seed)
    top = _largest_rate(intensity, ground, example.window)
    sims = []
    for _ in range(SIMULATIONS):  # 19 patterns, each one vectorized
        p = simulate(intensity, ground, example.window, rng, top)
        sims.append(l_function(p, example.window, r, rate(p)) if len(p) > 1 else np.full(len(r), np.nan))
    curves = np.vstack([np.array(sims), observed])
    dev = largest_deviations(curves)  # the 19, then the example
    if dev[-1] <= dev[:-1].max():
        return "poisson"
    mean = np.nanmean(curves, axis=0)
    at = int(np.nanargmax(np.abs(observed - mean)))
    return "regular" if observed[at] < mean[at] else "cluster"


def fit_spacing(example: Example, intensity: Intensity, ground=None, seed: int = 0, clumped: bool = False) -> Spacing:
    """The hard core, and clumps or not: Diggle's test (:data:`SIMULATIONS` Poisson patterns of ``intensity``);
    clumps fitted as a Matern cluster process by minimum contrast (none where the best fit's clumps are wider
    than the example's ground: no clumps the generator can grow), with a core where it fits far closer
    (:data:`CORE_GAIN`) and the example has more close pairs within its radius than the plain clumps make
    (:data:`CORE_Z`).  ``clumped``: the test found clumps already (with the intensity first fitted); only their
    parameters are fitted again for this ``intensity``."""
    xz, n = example.xz, len(example.xz)
    if n < 2:
        return Spacing(0.0, "poisson")
    hard = float(cKDTree(xz).query(xz, k=2)[0][:, 1].min())
    x0, z0, x1, z1 = example.window
    spacing = math.sqrt(example.area / n)
    r = np.linspace(SPAN[0], SPAN[1], 30) * spacing
    r = r[r <= min(x1 - x0, z1 - z0) / 4]
    if n < 10 or len(r) < 3:
        return Spacing(hard, "poisson")
    if not clumped:
        test = _diggle(example, intensity, ground, seed, r)
        if test != "cluster":
            return Spacing(hard, test)
    r = np.linspace(0.05, SPAN[1], 60) * spacing  # the clumps' own scale too
    r = r[r <= min(x1 - x0, z1 - z0) / 4]
    k_obs = math.pi * l_function(xz, example.window, r, intensity.rate_at(ground, xz)) ** 2
    ok = np.isfinite(k_obs)
    lam = n / example.area

    def misfit(*process):  # the contrast: K^(1/4) of the example against the process's, over the distances fitted
        return float(np.sum((k_obs[ok] ** 0.25 - np.maximum(matern_cluster_k(r[ok], *process), 0.0) ** 0.25) ** 2))

    def contrast(p):  # log kappa, log R
        return misfit(math.exp(p[0]), math.exp(p[1]))

    tight = {"maxiter": 2000, "xatol": 1e-6, "fatol": 1e-12}  # the contrast of a close fit is ~1e-3: no early stop
    best = min((minimize(contrast, [math.log(lam / c), math.log(f * spacing)], method="Nelder-Mead", options=tight)
                for c in (3.0, 10.0, 30.0) for f in (0.5, 1.0, 2.0)), key=lambda res: res.fun)
    kappa, radius = math.exp(best.x[0]), math.exp(best.x[1])
    if radius > max(x1 - x0, z1 - z0):  # a clump wider than the example's ground (pairs in excess as r^2, the
        return Spacing(hard, "poisson")  # radius running off to 1e7): the ground's unexplained unevenness, no clump

    def cored(p):  # log kappa, log R, logit(core radius / R), logit(share): the core within the clump
        a, share = radius_core(p)
        if math.exp(p[1]) > r[-1]:  # a clump no wider than the distances fitted (else it is no clump the generator can grow)
            return 1e30
        return misfit(math.exp(p[0]), math.exp(p[1]), share, a)

    def radius_core(p):
        return math.exp(p[1]) / (1.0 + math.exp(-p[2])), 1.0 / (1.0 + math.exp(-p[3]))

    wider = min(0.5, math.log(r[-1] / radius) - 1e-6)  # starts: the plain clumps', fewer parents, wider; a core of R / 8
    inner = min((minimize(cored, [best.x[0] + dk, best.x[1] + dr, -2.0, g], method="Nelder-Mead", options=tight)
                 for dk in (0.0, -0.7) for dr in (0.0, wider) for g in (-1.0, 0.0)), key=lambda res: res.fun)
    a, share = radius_core(inner.x)
    at = int(np.argmin(np.where(ok, np.abs(r - a), np.inf)))  # the close pairs within the core's radius
    pairs = lam * n / 2.0  # a pair count is pairs K(r)
    expected = pairs * max(float(matern_cluster_k(r[at:at + 1], kappa, radius)[0]), 0.0)
    close = (pairs * k_obs[at] - expected) / math.sqrt(max(expected, 1.0))  # above the plain clumps', in standard errors
    if inner.fun < CORE_GAIN * best.fun and close >= CORE_Z:  # clumps within clumps fit far closer, where they show
        return Spacing(hard, "cluster", (math.exp(inner.x[0]), math.exp(inner.x[1])), (share, a))
    return Spacing(hard, "cluster", (kappa, radius))


def learn_layers(example: Example, ground=None, names=None, seed: int = 0, errors: str = "clumps") -> list[LearnedLayer]:
    """One :class:`LearnedLayer` a kind of ``example`` (in the order kinds first appear), over ``ground`` (a
    :class:`~axialdeform.core.ground_features.GroundFeatures`, None: a flat ground with no features) and its
    features ``names`` (default all).  ``errors`` (:data:`ERRORS`): which standard errors decide the ground's
    terms of an example in clumps -- ``"clumps"`` the cluster process's (a term stays only where the clumps'
    own variation does not explain it: what transfers to another ground), ``"poisson"`` Poisson's, and a term
    stays while it lowers Akaike's criterion (:func:`fit_intensity`'s ``aic``: every dependence the example
    shows stays, also one its clumps make: the example's own ground reproduced more closely)."""
    if errors not in ERRORS:
        raise ParamError(f"{example.source}: errors: expected one of {', '.join(ERRORS)}, found {errors!r}")
    if ground is not None:
        gx0, gz0, gx1, gz1 = ground.bounds
        x0, z0, x1, z1 = example.window
        tol = 1e-5 * max(gx1 - gx0, gz1 - gz0)  # the terrain's corners are float32
        if x0 < gx0 - tol or z0 < gz0 - tol or x1 > gx1 + tol or z1 > gz1 + tol:
            raise ParamError(f"{example.source}: window: expected the example's ground [{x0:g}, {z0:g}, {x1:g}, {z1:g}] "
                             f"within the terrain's [{gx0:g}, {gz0:g}, {gx1:g}, {gz1:g}]")
    kinds = [None] if example.kind is None else list(dict.fromkeys(example.kind.tolist()))
    if len(kinds) > MAX_KINDS:
        raise ParamError(f"{example.source}: kind: expected at most {MAX_KINDS} kinds (one layer each), found {len(kinds)}")
    out = []
    for kind in kinds:
        part = example if kind is None else example.subset(example.kind == kind)
        intensity = fit_intensity(part, ground, names, aic=errors == "poisson")
        spacing = fit_spacing(part, intensity, ground, seed)
        if spacing.pattern == "cluster" and errors == "clumps":  # clumps make counts vary more than Poisson's
            intensity = fit_intensity(part, ground, names, cluster=spacing.process)
            spacing = fit_spacing(part, intensity, ground, seed, clumped=True)  # the clumps' size for it
        normal = None if ground is None or part.up is None else ground.normals(part.xz)
        marks = learn_marks(part.size, part.yaw, part.records, part.up, normal)
        out.append(LearnedLayer(kind, len(part.xz), intensity, spacing, marks, example.window))
    return out


#: the rate a learned layer's grid draws, over its largest intensity (thinned back by the density map), so
#: the jittered grid's own regularity stays below the example's spacing
OVERSAMPLE = 4.0


def layer_recipe(layer: LearnedLayer, ground, extent, shape=None, oversample: float = OVERSAMPLE,
                 mesh=None) -> tuple[dict, np.ndarray]:
    """A generated layer's recipe keys for ``layer`` over ``extent`` (x0, z0, x1, z1) of ``ground`` (the same
    ground it was learned on, or another: its features), and its density map, (rows, cols) in [0, 1] over
    ``extent`` (default the ground's grid, or 256 x 256 on flat ground): ``lambda / rate`` at each pixel's
    centre, where ``rate = oversample * max lambda`` (fewer where the hard core needs larger cells); in clumps
    8 parents (``CLUMP_PARENTS``) to every ``s x s`` cells of area ``8 / kappa``,
    ``s = ceil(sqrt(oversample max lambda 8 / kappa))`` (2 .. 256), so ``rate = s^2 kappa / 8``.  The marks'
    keys (:meth:`~axialdeform.core.marks.Marks.recipe`; the bend in the axis lengths of ``mesh``, the layer's)."""
    x0, z0, x1, z1 = extent
    if shape is None:
        shape = ground.grids["altitude"].shape if ground is not None else (256, 256)
    rows, cols = shape
    gx, gz = np.meshgrid(x0 + (np.arange(cols) + 0.5) * (x1 - x0) / cols, z0 + (np.arange(rows) + 0.5) * (z1 - z0) / rows)
    lam = layer.intensity.rate_at(ground, np.stack([gx.ravel(), gz.ravel()], axis=1)).reshape(rows, cols)
    top = float(lam.max())
    if layer.spacing.cluster is not None:  # clumps: 8 parents every s x s cells, kappa a square unit
        kappa, radius = layer.spacing.cluster
        block = CLUMP_PARENTS / kappa  # the area of s x s cells
        s = int(min(MAX_COUNT, max(2, math.ceil(math.sqrt(oversample * top * block)))))
        cell = math.sqrt(block) / s
        rate, min_distance, tile = 1.0 / cell ** 2, 0.0, cell * s * math.ceil(32 / s)
        clumps = {"clump_cells": s, "clump_radius": float(radius)}
        if layer.spacing.core is not None:  # clumps within clumps: a share of each clump within a smaller radius
            clumps.update(clump_core=float(layer.spacing.core[0]), clump_core_radius=float(min(layer.spacing.core[1], radius)))
    else:
        rate = oversample * top
        hard = layer.spacing.hard_core
        if hard > 0:
            rate = max(top, min(rate, (0.9 / hard) ** 2))  # cells of at least hard / 0.9, never fewer than the rate
        min_distance = min(hard, 0.9 / math.sqrt(rate))
        tile, clumps = 32.0 / math.sqrt(rate), {}
    keys = {"rate": float(rate), "tile": float(tile), "min_distance": float(min_distance), **clumps,
            **layer.marks.recipe(mesh)}
    return keys, np.clip(lam / rate, 0.0, 1.0)

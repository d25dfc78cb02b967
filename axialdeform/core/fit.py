"""Fitting: recover the 16 numbers of instances from meshes that already exist.

Given a base mesh and variants with its topology (same vertices in the same
order, each a bent, rotated and moved copy), find for each variant the
offsets ``d1..d5``, the position ``p`` and the angles ``rx ry rz`` with
``W ≈ R·(V + E(Σ B_i(t) d_i)) + p`` (``docs/method.md``).

Method (``docs/interop.md``), for every instance, vectorized over the
vertices and over batches of instances:

* ``t`` comes from the base mesh, so the model is linear in the offsets and
  the position once ``R`` is known;
* start: ``R, p`` by Kabsch alignment of the base mesh onto the variant
  (no scaling), offsets zero;
* then alternate: offsets and position by linear least squares for the
  current ``R``; ``R, p`` by Kabsch for the current offsets; and, because
  bending and rotation interact (a tilt of the axis looks much like a linear
  bend), a joint Gauss-Newton step on all free parameters that is kept only
  if it lowers the error.  Stop when a round no longer lowers the error.
* canonical form: the five offsets have zero mean per component (a shift
  shared by all five is a translation); the fit solves in a basis of
  zero-mean offsets, so it returns that form.

The residual reported is the distance between the variant and the shape the
fitted float32 parameters actually give (:func:`axialdeform.core.deform.deform`),
RMS and maximum over the vertices, as a fraction of the axis length ``L``.
A variant that the method did not make (noise, a scaled copy, another mesh)
gets an honest residual; fits above ``max_residual`` are flagged.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .deform import bend_model, bernstein, deform, displace
from .errors import MeshError, ResidualError, TopologyError
from .fit_tree import TreeModel, fit_batch_tree, fit_batch_tree_extended
from .io.mesh import MESH_SUFFIXES
from .io.variants import load_variant, variant_paths
from .lsq import CANONICAL, TallLeastSquares, block_rows, kabsch, solve, umeyama_scale
from .params import as_params
from .record import ANGLES, EXTRA, OFFSETS, POSITION, tree_width
from .transforms import (
    angles_from_matrices,
    matrices_from_rotation_vectors,
    rotation_matrices,
)

__all__ = [
    "TopologyError",
    "ResidualError",
    "FitResult",
    "DEFAULT_MAX_RESIDUAL",
    "MESH_SUFFIXES",
    "angles_from_matrices",
    "kabsch",
    "fit_instance",
    "fit_params",
    "fit_files",
    "load_variant",
    "variant_paths",
]

#: default limit on the worst vertex distance of a fit, as a fraction of L
DEFAULT_MAX_RESIDUAL = 1e-3


# ---------------------------------------------------------------------- fitting




class _Model:
    """What the fit needs from the base mesh, computed once.  Every method
    works on a batch of n instances: ``rot`` (n, 3, 3), ``z`` (n, 4, 2),
    ``pos`` (n, 3), ``target`` (n, v, 3)."""

    def __init__(self, mesh) -> None:
        axis = mesh.axis
        self.axis = axis
        self.length = axis.length
        self.base = mesh.positions.astype(np.float64)  # (v, 3)
        # the offsets' directions e_u, e_v (model space): coordinates of an aligned axis, rows of a frame
        self.across = None if axis.framed else axis.perpendicular
        self.frame = axis.matrix
        # (v, 4): the Bernstein weights in the canonical basis; D(t) = basis @ z, z (4, 2)
        self.basis = bernstein(axis.parameter(self.base), 4) @ CANONICAL

    def bent(self, z: np.ndarray) -> np.ndarray:
        """``V'`` (n, v, 3) for canonical offset coordinates ``z`` (n, 4, 2)."""
        return displace(self.axis, self.base, self.basis @ z)  # D(t) = basis @ z: (n, v, 2)

    def _offset_columns(self, rot: np.ndarray, a: np.ndarray, first: int, rows: slice = slice(None)) -> None:
        """Fill ``a[..., first:first + 8]`` with d(R·E(basis z))/dz for the vertices ``rows``."""
        basis = self.basis[rows]
        for k in range(2):  # R·e_u, R·e_v: a column of R for an aligned axis
            col = rot[:, :, self.across[k]] if self.across is not None else rot @ self.frame[1 + k]
            a[..., first + 4 * k:first + 4 * k + 4] = col[:, None, :, None] * basis[None, :, None, :]

    def linear_offsets(self, rot: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Offsets ``z`` (n, 4, 2) and positions ``p`` (n, 3) minimising the error for fixed ``R``.

        ``W - R·V = R·E(basis z) + p`` is linear in ``(z, p)``: n systems of (3v, 11)."""
        n, v = len(rot), len(self.base)
        lsq = TallLeastSquares(n, 11)
        step = block_rows(n, 11)
        for s in range(0, v, step):  # blocks of vertices: the (3v, 11) system is never held whole
            e = min(v, s + step)
            rhs = (target[:, s:e] - self.base[s:e] @ np.swapaxes(rot, -1, -2)).reshape(n, -1)
            a = np.empty((n, e - s, 3, 11))
            self._offset_columns(rot, a, 0, slice(s, e))
            a[..., 8:] = np.eye(3)
            lsq.add(a.reshape(n, 3 * (e - s), 11), rhs)
        sol = lsq.solve()
        return np.swapaxes(sol[:, :8].reshape(n, 2, 4), 1, 2), sol[:, 8:]

    def normal_equations(self, rot, z, pos, target):
        """``JᵀJ`` (n, 14, 14) and ``Jᵀr`` (n, 14) of the joint problem in (rotation
        vector, canonical offsets, position), linearised at the current state."""
        n, v = len(rot), len(self.base)
        jtj, jtr = np.zeros((n, 14, 14)), np.zeros((n, 14))
        step = block_rows(n, 14)
        for s in range(0, v, step):  # blocks of vertices: the (3v, 14) Jacobian is never held whole
            e = min(v, s + step)
            q = displace(self.axis, self.base[s:e], self.basis[s:e] @ z) @ np.swapaxes(rot, -1, -2)  # R·V'
            resid = (target[:, s:e] - q - pos[:, None]).reshape(n, -1)
            a = np.empty((n, e - s, 3, 14))
            # d(ω × q)/dω = -[q]×
            a[..., 0, 0], a[..., 0, 1], a[..., 0, 2] = 0.0, q[..., 2], -q[..., 1]
            a[..., 1, 0], a[..., 1, 1], a[..., 1, 2] = -q[..., 2], 0.0, q[..., 0]
            a[..., 2, 0], a[..., 2, 1], a[..., 2, 2] = q[..., 1], -q[..., 0], 0.0
            self._offset_columns(rot, a, 3, slice(s, e))
            a[..., 11:] = np.eye(3)
            a = a.reshape(n, 3 * (e - s), 14)
            at = np.swapaxes(a, -1, -2)
            jtj += at @ a
            jtr += (at @ resid[..., None])[..., 0]
        return jtj, jtr

    @staticmethod
    def apply(step, rot, z, pos):
        dz = np.swapaxes(step[:, 3:11].reshape(-1, 2, 4), 1, 2)
        return matrices_from_rotation_vectors(step[:, :3]) @ rot, z + dz, pos + step[:, 11:]

    def error(self, rot, z, pos, target) -> np.ndarray:
        """Squared error (n,) of each instance."""
        d = self.bent(z) @ np.swapaxes(rot, -1, -2) + pos[:, None] - target
        return np.einsum("nvc,nvc->n", d, d)


def _fit_batch(m: _Model, targets: np.ndarray, max_iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """Fit n variants at once: ``targets`` (n, v, 3) float64 -> params (n, 16)
    float64 (canonical) and rounds (n,) int.  Every instance follows exactly
    the steps it would follow alone; the converged ones drop out of the batch."""
    w = targets
    n = len(w)
    rot, pos = kabsch(m.base, w)
    z = np.zeros((n, 4, 2))
    best = m.error(rot, z, pos, w)
    floor = 1e-30 * m.length**2 * w.shape[1]  # below this the fit is exact to float64
    lam = np.full(n, 1e-3)
    rounds = np.zeros(n, dtype=np.int64)
    active = np.arange(n)
    eye = np.eye(14)
    for r in range(1, max_iterations + 1):
        if not active.size:
            break
        wa, la = w[active], lam[active]
        # alternate: the exact optimum of each block given the other
        za, pa = m.linear_offsets(rot[active], wa)
        ra, pa = kabsch(m.bent(za), wa)
        err = m.error(ra, za, pa, wa)
        # joint Levenberg-Marquardt step: follows the valley where tilting the
        # axis and bending it linearly look alike (flat or thin meshes)
        jtj, jtr = m.normal_equations(ra, za, pa, wa)
        damp = np.diagonal(jtj, axis1=1, axis2=2)[..., None] * eye + 1e-12 * np.trace(jtj, axis1=1, axis2=2)[:, None, None] * eye
        pending = np.arange(len(active))
        for _ in range(16):
            if not pending.size:
                break
            step = solve(jtj[pending] + la[pending, None, None] * damp[pending], jtr[pending])
            trial = m.apply(step, ra[pending], za[pending], pa[pending])
            trial_err = m.error(*trial, wa[pending])
            ok = trial_err < err[pending]
            took = pending[ok]
            ra[took], za[took], pa[took], err[took] = trial[0][ok], trial[1][ok], trial[2][ok], trial_err[ok]
            la[took] = np.maximum(la[took] / 4.0, 1e-9)
            la[pending[~ok]] = np.minimum(la[pending[~ok]] * 8.0, 1e9)
            pending = pending[~ok]
        rot[active], z[active], pos[active], lam[active], rounds[active] = ra, za, pa, la, r
        # converged when a round no longer lowers the squared error noticeably
        done = (best[active] - err <= 1e-12 * best[active]) | (err <= floor)
        best[active] = np.where(done, np.minimum(best[active], err), err)
        active = active[~done]
    out = np.empty((n, 16))
    out[:, OFFSETS] = (CANONICAL @ z).reshape(n, 10)  # (n, 5, 2): zero mean per component
    out[:, POSITION] = pos
    out[:, ANGLES] = angles_from_matrices(rot)
    return out, rounds


def _extended_shape(m: _Model, rot, z, pos, extra, rows: slice = slice(None)) -> np.ndarray:
    """``R·(s·V'') + p`` (n, v, 3) of canonical offsets ``z`` (n, 4, 2) and ``extra`` (n, 3) = s tw tp,
    for the base mesh's vertices ``rows`` (all of them by default)."""
    base = m.base[rows]
    moved, _ = bend_model(m.axis, base, base, CANONICAL @ z, extra)
    return moved @ np.swapaxes(rot, -1, -2) + pos[:, None]


def _fit_batch_extended(m: _Model, targets: np.ndarray, max_iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """Fit n variants with the 19 numbers of extended instances: ``targets``
    (n, v, 3) -> params (n, 19) float64 and rounds (n,).

    Start: the uniform scale of the best similarity map, the Kabsch rotation
    and the least-squares bend of the variant divided by it; then
    Levenberg-Marquardt on all 17
    unknowns (rotation vector, canonical offsets, position, log s, tw, tp)
    with a central-difference Jacobian, vectorized over the batch."""
    n = len(targets)
    scale0 = umeyama_scale(m.base, targets)
    unscaled = targets / scale0[:, None, None]
    rot, _ = kabsch(m.base, unscaled)
    z, pos = m.linear_offsets(rot, unscaled)  # the bend for that rotation, then refine everything together
    pos = pos * scale0[:, None]
    rounds = np.zeros(n, dtype=np.int64)
    extra = np.stack([scale0, np.zeros(n), np.zeros(n)], axis=1)
    L = m.length

    def shape(rot, z, pos, extra, rows=slice(None)):
        return _extended_shape(m, rot, z, pos, extra, rows)

    def err_of(shp, w):
        d = shp - w
        return np.einsum("nvc,nvc->n", d, d)

    # step sizes of the central differences, per unknown
    h = np.array([1e-6] * 3 + [1e-6 * L] * 8 + [1e-6 * L] * 3 + [1e-6, 1e-6, 1e-6])

    def perturbed(k, sign, rot, z, pos, extra):
        rot2, z2, pos2, ex2 = rot, z, pos, extra
        if k < 3:
            w = np.zeros((len(rot), 3))
            w[:, k] = sign * h[k]
            rot2 = matrices_from_rotation_vectors(w) @ rot
        elif k < 11:
            z2 = z.copy()
            c = k - 3
            z2[:, c % 4, c // 4] += sign * h[k]
        elif k < 14:
            pos2 = pos.copy()
            pos2[:, k - 11] += sign * h[k]
        else:
            ex2 = extra.copy()
            if k == 14:
                ex2[:, 0] *= np.exp(sign * h[k])
            else:
                ex2[:, k - 14] += sign * h[k]
        return rot2, z2, pos2, ex2

    def apply(step, rot, z, pos, extra):
        z2 = z + np.stack([step[:, 3:7], step[:, 7:11]], axis=2)
        ex2 = extra.copy()
        ex2[:, 0] *= np.exp(np.clip(step[:, 14], -1.0, 1.0))
        ex2[:, 1:] += step[:, 15:17]
        return matrices_from_rotation_vectors(step[:, :3]) @ rot, z2, pos + step[:, 11:14], ex2

    w_all = targets
    best = err_of(shape(rot, z, pos, extra), w_all)
    floor = 1e-30 * L**2 * w_all.shape[1]
    lam = np.full(n, 1e-3)
    active = np.arange(n)
    eye = np.eye(17)
    for _ in range(max_iterations):
        if not active.size:
            break
        ra, za, pa, ea, wa = rot[active], z[active], pos[active], extra[active], w_all[active]
        na, v = len(active), w_all.shape[1]
        states = [(perturbed(k, 1.0, ra, za, pa, ea), perturbed(k, -1.0, ra, za, pa, ea)) for k in range(17)]
        jtj, jtr = np.zeros((na, 17, 17)), np.zeros((na, 17))
        step_rows = block_rows(na, 17)
        for s in range(0, v, step_rows):  # blocks of vertices: the (3v, 17) Jacobian is never held whole
            rows = slice(s, min(v, s + step_rows))
            resid = (wa[:, rows] - shape(ra, za, pa, ea, rows)).reshape(na, -1)
            jac = np.empty((na, resid.shape[1], 17))
            for k, (plus, minus) in enumerate(states):  # 17 unknowns: central differences, vectorized over the batch
                jac[..., k] = ((shape(*plus, rows) - shape(*minus, rows)) / (2.0 * h[k])).reshape(na, -1)
            jt = np.swapaxes(jac, -1, -2)
            jtj += jt @ jac
            jtr += (jt @ resid[..., None])[..., 0]
        damp = np.diagonal(jtj, axis1=1, axis2=2)[..., None] * eye + 1e-12 * np.trace(jtj, axis1=1, axis2=2)[:, None, None] * eye
        err = best[active].copy()
        la = lam[active]
        pending = np.arange(len(active))
        for _ in range(16):
            if not pending.size:
                break
            step = solve(jtj[pending] + la[pending, None, None] * damp[pending], jtr[pending])
            trial = apply(step, ra[pending], za[pending], pa[pending], ea[pending])
            valid = trial[3][:, 2] < 1.0 - 1e-6
            trial_err = np.where(valid, err_of(shape(*trial), wa[pending]), np.inf)
            ok = trial_err < err[pending]
            took = pending[ok]
            ra[took], za[took], pa[took], ea[took] = trial[0][ok], trial[1][ok], trial[2][ok], trial[3][ok]
            err[took] = trial_err[ok]
            la[took] = np.maximum(la[took] / 4.0, 1e-9)
            la[pending[~ok]] = np.minimum(la[pending[~ok]] * 8.0, 1e9)
            pending = pending[~ok]
        rot[active], z[active], pos[active], extra[active], lam[active] = ra, za, pa, ea, la
        rounds[active] += 1
        done = (best[active] - err <= 1e-12 * best[active]) | (err <= floor)
        best[active] = np.minimum(best[active], err)
        active = active[~done]
    out = np.empty((n, 19))
    out[:, OFFSETS] = (CANONICAL @ z).reshape(n, 10)
    out[:, POSITION] = pos
    out[:, ANGLES] = angles_from_matrices(rot)
    out[:, EXTRA] = extra
    return out, rounds


def _rotations(angles: np.ndarray) -> np.ndarray:
    return rotation_matrices(angles)


def fit_instance(mesh, target: np.ndarray, *, max_iterations: int = 100, model: _Model | None = None):
    """Fit the 16 numbers of one variant (:func:`fit_params` fits many at once).

    Parameters
    ----------
    mesh : BaseMesh
        The base mesh (its vertices give ``t`` and the axis).
    target : (v, 3) float
        The variant's world positions, in the base mesh's vertex order.
    max_iterations : int
        Upper bound on alternation rounds.

    Returns
    -------
    params : (16,) float64
        Canonical offsets (zero mean per component), position, angles (radians).
    iterations : int
        Rounds used.
    """
    params, rounds = _fit_batch(model or _Model(mesh), np.asarray(target, dtype=np.float64)[None], max_iterations)
    return params[0], int(rounds[0])


@dataclass(frozen=True)
class FitResult:
    """Fitted parameters and how well they reproduce the variants.

    Attributes
    ----------
    params : (n, 16) float32
        Canonical parameters, one row per variant.
    rms : (n,) float64
        RMS vertex distance between variant and fitted shape, fraction of L.
    max : (n,) float64
        Largest vertex distance, fraction of L.
    iterations : (n,) int
        Alternation rounds per variant.
    max_residual : float
        The limit (fraction of L) the ``exceeds`` flags are judged against.
    names : tuple of str
        Where each variant came from (file names, or ``variant K``).
    """

    params: np.ndarray
    rms: np.ndarray
    max: np.ndarray
    iterations: np.ndarray
    max_residual: float = DEFAULT_MAX_RESIDUAL
    names: tuple = ()

    @property
    def exceeds(self) -> np.ndarray:
        """(n,) bool: the fits whose largest vertex distance is above ``max_residual``."""
        return self.max > self.max_residual

    @property
    def worst(self) -> int:
        """Index of the variant with the largest residual (-1 if none)."""
        return int(np.argmax(self.max)) if len(self.max) else -1

    def check(self) -> None:
        """Raise :class:`ResidualError` if any fit exceeds ``max_residual``."""
        bad = int(self.exceeds.sum())
        if bad:
            k = self.worst
            raise ResidualError(
                f"{bad} of {len(self.max)} fits exceed the residual limit {self.max_residual:g} L "
                f"(worst: {self.names[k] if self.names else f'variant {k}'}, max {self.max[k]:.3g} L, "
                f"rms {self.rms[k]:.3g} L); the variants were not made by this deformation of this base mesh, "
                "or use --allow-residual / a larger --max-residual"
            )


def _residuals(mesh, params32: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """RMS and max vertex distance (n,) (fraction of L) of the shapes ``params32`` (n, 16) give."""
    shapes = deform(mesh, params32)[0].astype(np.float64)
    dist = np.linalg.norm(shapes - targets, axis=2)
    return np.sqrt(np.mean(dist**2, axis=1)) / mesh.axis.length, dist.max(axis=1) / mesh.axis.length


def _in_loaded_order(mesh, pos: np.ndarray) -> np.ndarray:
    """Positions given in the file's own vertex order (``mesh.source_count``
    of them) put into the loaded order; loaded-order positions unchanged."""
    if len(pos) == mesh.vertex_count or len(pos) != mesh.source_count or (mesh.source_index < 0).any():
        return pos
    return pos[mesh.source_index]


def _check_shape(mesh, positions: np.ndarray, name: str) -> np.ndarray:
    pos = np.asarray(positions, dtype=np.float64)
    if pos.ndim == 2 and pos.shape[1] == 3:
        pos = _in_loaded_order(mesh, pos)
    if pos.ndim != 2 or pos.shape[1] != 3 or len(pos) != mesh.vertex_count:
        found = len(pos) if pos.ndim == 2 else pos.shape
        also = f" or {mesh.source_count} (its file's own order)" if mesh.source_count != mesh.vertex_count else ""
        raise TopologyError(
            f"{name}: has {found} vertices, expected {mesh.vertex_count} (the base mesh {mesh.name}'s count, "
            f"same order){also}"
        )
    if not np.isfinite(pos).all():
        raise MeshError(f"{name}: has non-finite vertex coordinates; expected finite numbers")
    return pos


#: float64 bytes of the largest work array of a batch (n, 3v, 14): bounds the instances fitted at once
_BATCH_BYTES = 64 << 20


def _fit_all(mesh, items, count, *, max_residual, max_iterations, progress, extended=False):
    axes = getattr(mesh, "axis_count", 1)
    model = _Model(mesh) if axes == 1 else TreeModel(mesh)
    width = tree_width(axes, 1 if extended else 0)
    params = np.empty((count, width), dtype=np.float32)
    rms, mx, its, names = np.empty(count), np.empty(count), np.empty(count, dtype=np.int64), []
    batch = max(1, _BATCH_BYTES // (mesh.vertex_count * 3 * (17 if extended else 14 if axes == 1 else width) * 8))
    fit_batch = {(False, True): _fit_batch, (True, True): _fit_batch_extended,
                 (False, False): fit_batch_tree, (True, False): fit_batch_tree_extended}[(bool(extended), axes == 1)]
    chunk: list[np.ndarray] = []

    def flush(end: int) -> None:  # fit the variants [end - len(chunk), end) together
        start = end - len(chunk)
        targets = np.stack(chunk)
        values, its[start:end] = fit_batch(model, targets, max_iterations)
        params[start:end] = values.astype(np.float32)
        rms[start:end], mx[start:end] = _residuals(mesh, params[start:end], targets)
        if progress is not None:
            progress.update(len(chunk))
        chunk.clear()

    k = 0
    for k, (name, positions) in enumerate(items, 1):  # files are read one by one; the fit runs per batch
        chunk.append(_check_shape(mesh, positions, name))
        names.append(name)
        if len(chunk) == batch:
            flush(k)
    if chunk:
        flush(k)
    return FitResult(as_params(params, axes=axes), rms, mx, its, float(max_residual), tuple(names))


def fit_params(mesh, variants, *, max_residual: float = DEFAULT_MAX_RESIDUAL, max_iterations: int = 100,
               progress=None, extended: bool = False) -> FitResult:
    """Fit every variant given as vertex positions.

    Parameters
    ----------
    mesh : BaseMesh
    variants : (n, v, 3) float, or a sequence of n (v, 3) arrays
        World positions of each variant in the base mesh's vertex order
        (``mesh.vertex_count`` rows), or in its file's own vertex order
        (``mesh.source_count`` rows; see ``BaseMesh.source_index``).
    max_residual : float
        Limit on the largest vertex distance, fraction of L (flags only;
        call :meth:`FitResult.check` to raise).
    max_iterations : int
        The most Levenberg-Marquardt rounds a variant takes.
    progress : tqdm-like, optional
        ``update(k)`` after each batch of k variants.
    extended : bool
        Fit the 19 numbers of extended instances (scale, twist, taper too):
        ``params`` is then (n, 19).
    """
    variants = list(variants) if not isinstance(variants, np.ndarray) else variants
    items = ((f"variant {k}", v) for k, v in enumerate(variants))
    return _fit_all(mesh, items, len(variants), max_residual=max_residual, max_iterations=max_iterations,
                    progress=progress, extended=extended)


def fit_files(mesh, paths, *, max_residual: float = DEFAULT_MAX_RESIDUAL, max_iterations: int = 100,
              progress=None, extended: bool = False) -> FitResult:
    """Read variant mesh files one at a time and fit them in batches (see :func:`fit_params`)."""
    paths = [Path(p) for p in paths]
    items = ((str(p), load_variant(p, mesh)) for p in paths)
    return _fit_all(mesh, items, len(paths), max_residual=max_residual, max_iterations=max_iterations,
                    progress=progress, extended=extended)


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

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .deform import bend_model, bernstein, deform, displace, tree_bend
from .errors import AxialDeformError, MeshError, ResidualError, TopologyError
from .io.mesh import MESH_SUFFIXES, load_mesh
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


def kabsch(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation (no scaling) that best map ``source`` onto ``target``.

    Parameters
    ----------
    source, target : (..., v, 3) float
        Corresponding points; leading dimensions broadcast (one base mesh
        against n variants: ``(v, 3)`` and ``(n, v, 3)``).

    Returns
    -------
    R : (..., 3, 3) float64
        Proper rotations (det +1) minimising ``Σ |R·s + p - t|²``.
    p : (..., 3) float64
    """
    s = np.asarray(source, dtype=np.float64)
    t = np.asarray(target, dtype=np.float64)
    sc, tc = s.mean(axis=-2, keepdims=True), t.mean(axis=-2, keepdims=True)
    h = np.swapaxes(s - sc, -1, -2) @ (t - tc)
    u, _sv, vt = np.linalg.svd(h)
    v, ut = np.swapaxes(vt, -1, -2), np.swapaxes(u, -1, -2)
    d = np.sign(np.linalg.det(v @ ut))
    flip = np.ones(h.shape[:-1])
    flip[..., 2] = np.where(d == 0.0, 1.0, d)
    rot = v @ (flip[..., :, None] * ut)
    return rot, tc[..., 0, :] - (rot @ sc[..., 0, :, None])[..., 0]


def _solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Least-squares solutions ``x`` (n, k) of the stacked systems ``a`` (n, m, k) ``x = b`` (n, m),
    minimum-norm where a system is rank-deficient (what ``np.linalg.lstsq`` gives for one)."""
    return (np.linalg.pinv(a) @ b[..., None])[..., 0]


#: float64 bytes of one block of a tall system (n, 3·vb, k) built at a time: the fit's
#: work memory no longer grows with the vertex count (docs/reliability.md)
_BLOCK_BYTES = 8 << 20


def _block_rows(n: int, k: int) -> int:
    """Vertices per block so that a (n, 3·vb, k) float64 block stays under ``_BLOCK_BYTES``."""
    return max(1, _BLOCK_BYTES // (n * 3 * k * 8))


class _TallLeastSquares:
    """Stacked least-squares problems ``a x = b`` whose rows come in blocks.

    Keeps only the triangular factor ``R`` (n, k+1, k+1) of the QR
    decomposition of ``[a | b]`` (a tall-skinny QR, updated per block); its
    top-left (k, k) part has the singular values of ``a`` and its last column
    is ``Qᵀb``, so :meth:`solve` gives what ``pinv(a) @ b`` gives on the full
    system (the same minimum-norm solution) without ever holding ``a``.
    """

    def __init__(self, n: int, k: int) -> None:
        self.k = k
        self.r = np.zeros((n, 0, k + 1))

    def add(self, a: np.ndarray, b: np.ndarray) -> None:
        """Rows ``a`` (n, m, k) and right-hand sides ``b`` (n, m)."""
        block = np.concatenate([a, b[..., None]], axis=-1)
        self.r = np.linalg.qr(np.concatenate([self.r, block], axis=1), mode="r")

    def solve(self) -> np.ndarray:
        """``x`` (n, k)."""
        k = self.k
        return _solve(self.r[:, :k, :k], self.r[:, :k, k])


# ---------------------------------------------------------------------- fitting


# an orthonormal basis of the zero-mean vectors of length 5: the canonical offsets
_CANONICAL = np.linalg.svd(np.eye(5) - 1.0 / 5.0)[0][:, :4]  # (5, 4)


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
        self.basis = bernstein(axis.parameter(self.base), 4) @ _CANONICAL

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
        lsq = _TallLeastSquares(n, 11)
        step = _block_rows(n, 11)
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
        step = _block_rows(n, 14)
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
            step = _solve(jtj[pending] + la[pending, None, None] * damp[pending], jtr[pending])
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
    out[:, OFFSETS] = (_CANONICAL @ z).reshape(n, 10)  # (n, 5, 2): zero mean per component
    out[:, POSITION] = pos
    out[:, ANGLES] = angles_from_matrices(rot)
    return out, rounds


def umeyama_scale(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The uniform scale (n,) of the best similarity map of ``source`` (v, 3)
    onto each ``target`` (n, v, 3) (Umeyama 1991): the start of an extended fit."""
    s = np.asarray(source, dtype=np.float64)
    t = np.asarray(target, dtype=np.float64)
    sc = s - s.mean(axis=0)
    tc = t - t.mean(axis=-2, keepdims=True)
    sv = np.linalg.svd(np.swapaxes(sc, -1, -2)[None] @ tc, compute_uv=False)  # (n, 3)
    var = float((sc**2).sum())
    return np.maximum(sv.sum(axis=-1) / max(var, 1e-300), 1e-12)


def _extended_shape(m: _Model, rot, z, pos, extra, rows: slice = slice(None)) -> np.ndarray:
    """``R·(s·V'') + p`` (n, v, 3) of canonical offsets ``z`` (n, 4, 2) and ``extra`` (n, 3) = s tw tp,
    for the base mesh's vertices ``rows`` (all of them by default)."""
    base = m.base[rows]
    moved, _ = bend_model(m.axis, base, base, _CANONICAL @ z, extra)
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
        step_rows = _block_rows(na, 17)
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
            step = _solve(jtj[pending] + la[pending, None, None] * damp[pending], jtr[pending])
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
    out[:, OFFSETS] = (_CANONICAL @ z).reshape(n, 10)
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


class _TreeModel:
    """What the fit of a mesh of several axes needs, computed once: the
    design matrix of ``Rᵀ(W − p) − V = Σ_chain F_jᵀ E(D_j(t_j))`` in the
    offsets (axis 0 in the canonical basis, every child axis's ten) and
    ``Rᵀp``; it does not depend on the rotation, so its pseudo-inverse is
    made once (docs/method.md, "Several axes")."""

    def __init__(self, mesh) -> None:
        tree = mesh.tree
        self.mesh, self.k = mesh, tree.count
        self.base = mesh.positions.astype(np.float64)
        v, k = len(self.base), self.k
        chain = tree.chain[tree.vertex_axis]  # (v, K)
        cols = []
        for j, axis in enumerate(tree.axes):
            w = bernstein(axis.parameter(self.base), 4) * chain[:, j, None]  # (v, 5), 0 off the chain
            if j == 0:
                w = w @ _CANONICAL  # (v, 4): axis 0's offsets up to a shift (that is p's)
            for e in axis.matrix[1:]:  # the u, then the v component
                cols.append(w[:, None, :] * e[None, :, None])  # (v, 3, m)
        cols.append(np.broadcast_to(np.eye(3), (v, 3, 3)))  # Rᵀp
        self.design = np.concatenate(cols, axis=2).reshape(3 * v, -1)
        self.pinv = np.linalg.pinv(self.design)
        self.unknowns = self.design.shape[1]
        assert self.unknowns == 8 + 10 * (k - 1) + 3

    def shapes(self, x: np.ndarray) -> np.ndarray:
        """Model-space ``V'`` (n, v, 3) of the solutions ``x`` (n, unknowns) (without Rᵀp)."""
        x = x.copy()
        x[:, -3:] = 0.0
        return self.base + (x @ self.design.T).reshape(len(x), -1, 3)

    def params(self, x: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """``(n, 10·K + 6)`` float64 of the solutions and rotations."""
        n, k = len(x), self.k
        out = np.zeros((n, 10 * k + 6))
        out[:, :10] = np.concatenate([_CANONICAL @ x[:, 0:4, None], _CANONICAL @ x[:, 4:8, None]], axis=2).reshape(n, 10)
        children = x[:, 8:8 + 10 * (k - 1)].reshape(n, k - 1, 2, 5)  # per axis: the u offsets, then the v offsets
        out[:, 10:10 * k] = np.swapaxes(children, 2, 3).reshape(n, 10 * (k - 1))
        out[:, 10 * k:10 * k + 3] = (rot @ x[:, -3:, None])[..., 0]
        out[:, 10 * k + 3:] = angles_from_matrices(rot)
        return out


def _fit_batch_tree(m: _TreeModel, targets: np.ndarray, max_iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """Fit n variants of a mesh of several axes by Gauss-Newton: start from
    the Kabsch rotation; each round solves, for every variant at once, the
    linear problem in the offsets, ``Rᵀp`` and a small turn ``ω`` of the
    rotation (``Rᵀ W − V ≈ Σ_chain F_jᵀ E(D_j) + Rᵀp + ω × V'``), turns ``R``
    by ``ω``, until ``|ω|`` and the shape's change vanish; the offsets and
    ``Rᵀp`` of the final rotation come from the shared pseudo-inverse.
    ``targets`` (n, v, 3) -> params (n, 10·K + 6), rounds (n,)."""
    n, v = len(targets), len(m.base)
    rot, _ = kabsch(m.base, targets)
    rounds = np.zeros(n, dtype=np.int64)
    active = np.ones(n, dtype=bool)
    scale = float(np.ptp(m.base, axis=0).max())
    design = m.design  # (3v, U)
    for it in range(1, max(1, int(max_iterations)) + 1):
        idx = np.flatnonzero(active)
        local = np.einsum("nji,nvj->nvi", rot[idx], targets[idx])  # Rᵀ W
        resid = (local - m.base).reshape(len(idx), -1)
        x = resid @ m.pinv.T
        bent = m.shapes(x)  # (a, v, 3): V'
        a, b, c = bent[..., 0], bent[..., 1], bent[..., 2]
        turn = np.zeros((len(idx), v, 3, 3))  # d(ω × V')/dω = −[V']×
        turn[..., 0, 1], turn[..., 0, 2] = c, -b
        turn[..., 1, 0], turn[..., 1, 2] = -c, a
        turn[..., 2, 0], turn[..., 2, 1] = b, -a
        full = np.concatenate([np.broadcast_to(design, (len(idx),) + design.shape), turn.reshape(len(idx), 3 * v, 3)],
                              axis=2)
        y = _solve(full, resid)
        omega = y[:, -3:]
        rot[idx] = rot[idx] @ matrices_from_rotation_vectors(omega)
        rounds[idx] = it
        moved = np.linalg.norm(omega, axis=1) * scale
        active[idx] = moved > 1e-10 * scale
        if not active.any():
            break
    local = np.einsum("nji,nvj->nvi", rot, targets)
    x = ((local - m.base).reshape(n, -1)) @ m.pinv.T
    return m.params(x, rot), rounds


def _fit_batch_tree_extended(m: _TreeModel, targets: np.ndarray, max_iterations: int):
    """The extended numbers too (scale, twist, taper about axis 0's axis line):
    Gauss-Newton on ``RᵀW = s·(TT(V; tw, tp) + Σ_chain F_jᵀ E(D_j)) + Rᵀp``
    in the offsets, ``Rᵀp``, a small turn, ``s``, ``tw`` and ``tp`` (the
    twist and taper's derivatives by central differences of the CPU
    reference).  Starts from the similarity map (scale, Kabsch rotation).
    ``targets`` (n, v, 3) -> params (n, 10·K + 9), rounds (n,)."""
    n, v = len(targets), len(m.base)
    tree = m.mesh.tree
    scale0 = umeyama_scale(m.base, targets)
    rot, _ = kabsch(m.base * scale0[:, None, None], targets)
    x = np.zeros((n, m.unknowns))
    ext = np.stack([scale0, np.zeros(n), np.zeros(n)], axis=1)  # s tw tp
    size = float(np.ptp(m.base, axis=0).max())
    zero = np.zeros((n, tree.count, 5, 2))

    def turned(tw_tp):  # TT(V): the twisted, tapered mesh (no offsets, s = 1)
        extra = np.concatenate([np.ones((len(tw_tp), 1)), tw_tp], axis=1)
        return tree_bend(tree, m.base, m.base, zero[:len(tw_tp)], extra)[0]

    rounds = np.zeros(n, dtype=np.int64)
    for it in range(1, max(1, int(max_iterations)) + 1):
        local = np.einsum("nji,nvj->nvi", rot, targets)  # Rᵀ W
        tt = turned(ext[:, 1:])
        bend = m.shapes(x) - m.base  # Σ(z)
        shape = tt + bend  # V''
        q = x[:, -3:]
        model = ext[:, 0, None, None] * shape + q[:, None]
        resid = (local - model).reshape(n, -1)
        h = 1e-6
        d_tw = (turned(ext[:, 1:] + [h, 0]) - turned(ext[:, 1:] - [h, 0])) / (2 * h)
        d_tp = (turned(ext[:, 1:] + [0, h]) - turned(ext[:, 1:] - [0, h])) / (2 * h)
        sv = ext[:, 0, None, None] * shape
        a, b, c = sv[..., 0], sv[..., 1], sv[..., 2]
        turn = np.zeros((n, v, 3, 3))  # d(ω × sV'')/dω
        turn[..., 0, 1], turn[..., 0, 2] = c, -b
        turn[..., 1, 0], turn[..., 1, 2] = -c, a
        turn[..., 2, 0], turn[..., 2, 1] = b, -a
        design = m.design.copy()
        offsets = ext[:, 0, None, None] * design[None, :, :-3]  # s · ∂Σ/∂z
        full = np.concatenate([offsets, np.broadcast_to(design[:, -3:], (n,) + design[:, -3:].shape),
                               turn.reshape(n, 3 * v, 3), shape.reshape(n, 3 * v, 1),
                               (ext[:, 0, None, None] * d_tw).reshape(n, 3 * v, 1),
                               (ext[:, 0, None, None] * d_tp).reshape(n, 3 * v, 1)], axis=2)
        step = _solve(full, resid)
        u = m.unknowns
        x += step[:, :u]
        rot = rot @ matrices_from_rotation_vectors(step[:, u:u + 3])
        ext += step[:, u + 3:]
        ext[:, 2] = np.minimum(ext[:, 2], 0.99)  # a taper stays < 1
        rounds[:] = it
        if np.abs(step[:, u:]).max() * size < 1e-10 * size and np.abs(step[:, :u]).max() < 1e-10 * size:
            break
    out = np.zeros((n, 10 * m.k + 9))
    out[:, :10 * m.k + 6] = m.params(x, rot)
    out[:, 10 * m.k + 6:] = ext
    return out, rounds


def _fit_all(mesh, items, count, *, max_residual, max_iterations, progress, extended=False):
    axes = getattr(mesh, "axis_count", 1)
    model = _Model(mesh) if axes == 1 else _TreeModel(mesh)
    width = tree_width(axes, 1 if extended else 0)
    params = np.empty((count, width), dtype=np.float32)
    rms, mx, its, names = np.empty(count), np.empty(count), np.empty(count, dtype=np.int64), []
    batch = max(1, _BATCH_BYTES // (mesh.vertex_count * 3 * (17 if extended else 14 if axes == 1 else width) * 8))
    fit_batch = {(False, True): _fit_batch, (True, True): _fit_batch_extended,
                 (False, False): _fit_batch_tree, (True, False): _fit_batch_tree_extended}[(bool(extended), axes == 1)]
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


def load_variant(path: str | os.PathLike, mesh) -> np.ndarray:
    """Vertex positions ``(v, 3) float64`` of a variant mesh file, checked against ``mesh``.

    Raises :class:`TopologyError` naming the file if its vertex count, triangle
    count or triangles differ from the base mesh's.
    """

    variant = load_mesh(path)
    name = str(path)
    if not (variant.vertex_count == mesh.vertex_count and np.array_equal(variant.faces, mesh.faces)):
        # the same file vertices and triangles, split or ordered differently by the reader
        # (an OBJ written with other UV seams, or none): compare and map in the file's own order
        same_file_triangles = (len(variant.faces) == len(mesh.faces) and variant.source_count == mesh.source_count
                               and not (variant.source_index < 0).any() and not (mesh.source_index < 0).any()
                               and np.array_equal(variant.source_index[variant.faces], mesh.source_index[mesh.faces]))
        if same_file_triangles:
            file_positions = np.zeros((variant.source_count, 3))
            file_positions[variant.source_index] = variant.positions
            return file_positions[mesh.source_index]
    if variant.vertex_count != mesh.vertex_count:
        raise TopologyError(f"{name}: has {variant.vertex_count} vertices, expected {mesh.vertex_count} "
                            f"(the base mesh {mesh.name}'s count, same order)")
    if len(variant.faces) != len(mesh.faces):
        raise TopologyError(f"{name}: has {len(variant.faces)} triangles, expected {len(mesh.faces)} "
                            f"(the base mesh {mesh.name}'s count)")
    if not np.array_equal(variant.faces, mesh.faces):
        k = int(np.argwhere((variant.faces != mesh.faces).any(axis=1))[0, 0])
        raise TopologyError(f"{name}: triangle {k} is {variant.faces[k].tolist()}, expected {mesh.faces[k].tolist()} "
                            f"as in the base mesh {mesh.name} (same vertices in the same order)")
    return variant.positions.astype(np.float64)


def variant_paths(inputs) -> list[Path]:
    """The variant files: the given files in order, or the mesh files of ONE folder sorted by name."""
    paths = [Path(p) for p in inputs]
    if not paths:
        raise AxialDeformError("variants: expected mesh files or one folder of mesh files, found none")
    folders = [p for p in paths if p.is_dir()]
    if folders:
        if len(paths) != 1:
            raise AxialDeformError(f"variants: a folder ({folders[0]}) must be the only VARIANTS argument; "
                                   f"found {len(paths)} arguments")
        found = sorted((p for p in paths[0].iterdir() if p.is_file() and p.suffix.lower() in MESH_SUFFIXES
                        and not p.name.startswith(".")), key=lambda p: p.name)
        if not found:
            raise AxialDeformError(f"{paths[0]}: no mesh files ({', '.join(MESH_SUFFIXES)}) in the folder")
        return found
    return paths


def fit_files(mesh, paths, *, max_residual: float = DEFAULT_MAX_RESIDUAL, max_iterations: int = 100,
              progress=None, extended: bool = False) -> FitResult:
    """Read variant mesh files one at a time and fit them in batches (see :func:`fit_params`)."""
    paths = [Path(p) for p in paths]
    items = ((str(p), load_variant(p, mesh)) for p in paths)
    return _fit_all(mesh, items, len(paths), max_residual=max_residual, max_iterations=max_iterations,
                    progress=progress, extended=extended)


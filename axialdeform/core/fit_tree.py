"""Fitting the numbers of a mesh of several axes (a trunk, its branches): Gauss-Newton over every
axis's offsets at once, plain and extended (:func:`axialdeform.core.fit.fit_params` calls it)."""

from __future__ import annotations

import numpy as np

from .deform import bernstein, tree_bend
from .lsq import CANONICAL, kabsch, solve, umeyama_scale
from .transforms import (
    angles_from_matrices,
    matrices_from_rotation_vectors,
)

__all__ = ["TreeModel", "fit_batch_tree", "fit_batch_tree_extended"]


class TreeModel:
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
        weight = tree.weights  # (v, K): 1 on a vertex's chain, 0 off it (a blend: its two chains' weights)
        cols = []
        for j, axis in enumerate(tree.axes):
            w = bernstein(axis.parameter(self.base), 4) * weight[:, j, None]  # (v, 5), 0 off the chain
            if j == 0:
                w = w @ CANONICAL  # (v, 4): axis 0's offsets up to a shift (that is p's)
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
        out[:, :10] = np.concatenate([CANONICAL @ x[:, 0:4, None], CANONICAL @ x[:, 4:8, None]], axis=2).reshape(n, 10)
        children = x[:, 8:8 + 10 * (k - 1)].reshape(n, k - 1, 2, 5)  # per axis: the u offsets, then the v offsets
        out[:, 10:10 * k] = np.swapaxes(children, 2, 3).reshape(n, 10 * (k - 1))
        out[:, 10 * k:10 * k + 3] = (rot @ x[:, -3:, None])[..., 0]
        out[:, 10 * k + 3:] = angles_from_matrices(rot)
        return out


def fit_batch_tree(m: TreeModel, targets: np.ndarray, max_iterations: int) -> tuple[np.ndarray, np.ndarray]:
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
        y = solve(full, resid)
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


def fit_batch_tree_extended(m: TreeModel, targets: np.ndarray, max_iterations: int):
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
        step = solve(full, resid)
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

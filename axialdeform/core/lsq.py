"""The least-squares pieces the fits share: the best rotation (Kabsch) and uniform scale (Umeyama)
between point sets, stacked minimum-norm solves, and tall systems solved block by block."""

from __future__ import annotations

import numpy as np

__all__ = ["kabsch", "umeyama_scale", "solve", "block_rows", "TallLeastSquares", "CANONICAL", "BLOCK_BYTES"]

# an orthonormal basis of the zero-mean vectors of length 5: the canonical offsets
CANONICAL = np.linalg.svd(np.eye(5) - 1.0 / 5.0)[0][:, :4]  # (5, 4)


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


def solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Least-squares solutions ``x`` (n, k) of the stacked systems ``a`` (n, m, k) ``x = b`` (n, m),
    minimum-norm where a system is rank-deficient (what ``np.linalg.lstsq`` gives for one)."""
    return (np.linalg.pinv(a) @ b[..., None])[..., 0]


#: float64 bytes of one block of a tall system (n, 3·vb, k) built at a time: the fit's
#: work memory no longer grows with the vertex count (docs/reliability.md)
BLOCK_BYTES = 8 << 20


def block_rows(n: int, k: int) -> int:
    """Vertices per block so that a (n, 3·vb, k) float64 block stays under ``BLOCK_BYTES``."""
    return max(1, BLOCK_BYTES // (n * 3 * k * 8))


class TallLeastSquares:
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
        return solve(self.r[:, :k, :k], self.r[:, :k, k])


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

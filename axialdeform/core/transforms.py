"""Every rotation, quaternion and angle conversion of the library, in one place
(pure numpy, vectorized over any leading dimensions).

Convention (``docs/method.md``): an instance's rotation is
``R = Rz(rz) · Ry(ry) · Rx(rx)`` with column vectors (a model vector ``v``
goes to ``R @ v``); quaternions are ``x, y, z, w`` (glTF's order).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "rotation_matrices",
    "angles_from_matrices",
    "quaternions_from_angles",
    "matrices_from_quaternions",
    "matrices_from_rotation_vectors",
]


def rotation_matrices(angles: np.ndarray) -> np.ndarray:
    """``R = Rz(rz) · Ry(ry) · Rx(rx)`` for angles (..., 3) radians -> (..., 3, 3) float64.

    Column-vector convention: a model vector ``v`` goes to ``R @ v``.
    """
    a = np.asarray(angles, dtype=np.float64)
    cx, cy, cz = np.cos(a[..., 0]), np.cos(a[..., 1]), np.cos(a[..., 2])
    sx, sy, sz = np.sin(a[..., 0]), np.sin(a[..., 1]), np.sin(a[..., 2])
    r = np.empty(a.shape[:-1] + (3, 3))
    r[..., 0, 0] = cz * cy
    r[..., 0, 1] = cz * sy * sx - sz * cx
    r[..., 0, 2] = cz * sy * cx + sz * sx
    r[..., 1, 0] = sz * cy
    r[..., 1, 1] = sz * sy * sx + cz * cx
    r[..., 1, 2] = sz * sy * cx - cz * sx
    r[..., 2, 0] = -sy
    r[..., 2, 1] = cy * sx
    r[..., 2, 2] = cy * cx
    return r


def angles_from_matrices(matrices: np.ndarray) -> np.ndarray:
    """Angles ``rx ry rz`` (radians) with ``R = Rz(rz)·Ry(ry)·Rx(rx)``.

    Parameters
    ----------
    matrices : (..., 3, 3) float
        Rotation matrices (column-vector convention).

    Returns
    -------
    (..., 3) float64
        ``ry = atan2(-R[2,0], hypot(R[0,0], R[1,0]))`` in ``[-pi/2, pi/2]``,
        ``rx = atan2(R[2,1], R[2,2])``, ``rz = atan2(R[1,0], R[0,0])``.  At
        gimbal lock (``cos ry`` below 1e-9: rx and rz turn about the same
        axis) ``rz = 0`` and ``rx`` carries the whole turn.  The matrix is
        reproduced; the angles need not equal the ones that made it.
    """
    r = np.asarray(matrices, dtype=np.float64)
    cy = np.hypot(r[..., 0, 0], r[..., 1, 0])
    ry = np.arctan2(-r[..., 2, 0], cy)
    locked = cy < 1e-9
    rx = np.where(locked, np.arctan2(-r[..., 1, 2], r[..., 1, 1]), np.arctan2(r[..., 2, 1], r[..., 2, 2]))
    rz = np.where(locked, 0.0, np.arctan2(r[..., 1, 0], r[..., 0, 0]))
    return np.stack([rx, ry, rz], axis=-1)


def quaternions_from_angles(angles: np.ndarray) -> np.ndarray:
    """Unit quaternions of ``R = Rz(rz)·Ry(ry)·Rx(rx)``.

    Parameters
    ----------
    angles : (n, 3) float, radians
        ``rx ry rz`` per instance.

    Returns
    -------
    (n, 4) float64
        ``x, y, z, w`` (the glTF order), the Hamilton product ``qz ⊗ qy ⊗ qx``
        (pyrr's ``quaternion.cross``), normalised, sign chosen so ``w >= 0``.
    """
    from pyrr import quaternion

    a = np.asarray(angles, dtype=np.float64).reshape(-1, 3)
    half = 0.5 * a
    s, c = np.sin(half), np.cos(half)
    zero = np.zeros(len(a))
    # pyrr quaternions are (x, y, z, w); quaternion.cross unpacks the first
    # axis, so (4, n) arrays multiply n quaternions at once
    qx = np.stack([s[:, 0], zero, zero, c[:, 0]])
    qy = np.stack([zero, s[:, 1], zero, c[:, 1]])
    qz = np.stack([zero, zero, s[:, 2], c[:, 2]])
    q = quaternion.cross(qz, quaternion.cross(qy, qx)).T
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 3] < 0] *= -1.0
    return q


def matrices_from_quaternions(quats: np.ndarray) -> np.ndarray:
    """Rotation matrices (column-vector convention, ``v -> R @ v``) of unit
    quaternions ``(n, 4)`` in ``x, y, z, w`` order: ``(n, 3, 3)`` float64."""
    q = np.asarray(quats, dtype=np.float64).reshape(-1, 4)
    with np.errstate(invalid="ignore", divide="ignore"):  # a zero quaternion gives NaN: checked by the caller
        q = q / np.linalg.norm(q, axis=1, keepdims=True)
    x, y, z, w = q.T
    r = np.empty((len(q), 3, 3))
    r[:, 0, 0] = 1 - 2 * (y * y + z * z)
    r[:, 0, 1] = 2 * (x * y - z * w)
    r[:, 0, 2] = 2 * (x * z + y * w)
    r[:, 1, 0] = 2 * (x * y + z * w)
    r[:, 1, 1] = 1 - 2 * (x * x + z * z)
    r[:, 1, 2] = 2 * (y * z - x * w)
    r[:, 2, 0] = 2 * (x * z - y * w)
    r[:, 2, 1] = 2 * (y * z + x * w)
    r[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def matrices_from_rotation_vectors(w: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3) float64`` of rotation vectors ``w : (..., 3)`` (axis times
    angle, radians), by Rodrigues' formula (exact first order below 1e-12 rad)."""
    w = np.asarray(w, dtype=np.float64)
    theta = np.linalg.norm(w, axis=-1)
    k = np.zeros(w.shape[:-1] + (3, 3))
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    k[..., 1, 0], k[..., 2, 0], k[..., 2, 1] = w[..., 2], -w[..., 1], w[..., 0]
    small = theta < 1e-12
    safe = np.where(small, 1.0, theta)
    kn = k / safe[..., None, None]
    rodrigues = np.eye(3) + np.sin(safe)[..., None, None] * kn + (1.0 - np.cos(safe))[..., None, None] * (kn @ kn)
    return np.where(small[..., None, None], np.eye(3) + k, rodrigues)

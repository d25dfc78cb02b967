"""The CPU reference path: the deformation of the spec in vectorized numpy.

It is the ground truth for the tests (the GPU path must match it) and the
engine behind ``bake --engine cpu``.  Everything is computed in float64 and
returned as float32; work is split into chunks of instances only to bound
memory, never looped per instance or per vertex.
"""

from __future__ import annotations

import numpy as np

from .arrays import as_array
from .axis import ControlAxis
from .params import ANGLES, OFFSETS, POSITION, as_params
from .transforms import rotation_matrices

__all__ = [
    "bernstein",
    "rotation_matrices",
    "axis_offsets",
    "displace",
    "deform_local",
    "deform",
]

_BINOMIAL = {4: np.array([1.0, 4.0, 6.0, 4.0, 1.0]), 3: np.array([1.0, 3.0, 3.0, 1.0])}


def bernstein(t: np.ndarray, degree: int = 4) -> np.ndarray:
    """Bernstein basis ``B_i(t) = C(deg, i) t^i (1-t)^(deg-i)``: (...,) -> (..., deg+1)."""
    t = np.asarray(t, dtype=np.float64)[..., None]
    i = np.arange(degree + 1)
    return _BINOMIAL[degree] * t**i * (1.0 - t) ** (degree - i)


def axis_offsets(axis: ControlAxis, t: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The axis displacement ``D(t)`` and its derivative ``D'(t)`` (2-component, u/v).

    t : (v,) float — curve parameter per vertex.
    offsets : (n, 5, 2) float — control-point offsets per instance.
    Returns ``D`` and ``dD/dt``, each (n, v, 2) float64.
    """
    d = np.asarray(offsets, dtype=np.float64)
    disp = np.einsum("vk,nkc->nvc", bernstein(t, 4), d)
    slope = 4.0 * np.einsum("vk,nkc->nvc", bernstein(t, 3), d[:, 1:] - d[:, :-1])
    return disp, slope


def displace(axis: ControlAxis, positions: np.ndarray, disp: np.ndarray) -> np.ndarray:
    """The bend: ``V' = V + E(D)``, the one place the 2-component axis
    displacement is put into 3-D (``docs/method.md``).

    positions : (v, 3) float — the base mesh.
    disp : (n, v, 2) float — ``D(t)`` per instance and vertex (u, v components).
    Returns ``V'`` : (n, v, 3) float64.
    """
    p = np.asarray(positions, dtype=np.float64)
    disp = np.asarray(disp, dtype=np.float64)
    i, j = axis.perpendicular
    moved = np.broadcast_to(p, disp.shape[:-1] + (3,)).copy()
    moved[..., i] += disp[..., 0]
    moved[..., j] += disp[..., 1]
    return moved


def deform_local(
    axis: ControlAxis, positions: np.ndarray, normals: np.ndarray, offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Bend the base mesh in model space (no rotation or position).

    positions, normals : (v, 3) — the base mesh.
    offsets : (n, 5, 2) — per-instance control-point offsets.
    Returns ``V'`` (n, v, 3) and unit ``n'`` (n, v, 3), float64:
    ``V' = V + E(D(t))`` and ``n' = normalize(n - e_a (D'(t)·n) / L)``.
    """
    p = np.asarray(positions, dtype=np.float64)
    nrm = np.asarray(normals, dtype=np.float64)
    disp, slope = axis_offsets(axis, axis.parameter(p), offsets)
    i, j = axis.perpendicular
    moved = displace(axis, p, disp)
    bent = np.broadcast_to(nrm, moved.shape).copy()
    bent[..., axis.index] -= (slope[..., 0] * nrm[:, i] + slope[..., 1] * nrm[:, j]) / axis.length
    bent /= np.maximum(np.linalg.norm(bent, axis=-1, keepdims=True), 1e-300)
    return moved, bent


def deform(
    axis: ControlAxis,
    positions: np.ndarray,
    normals: np.ndarray,
    params: np.ndarray,
    *,
    chunk_vertices: int = 4_000_000,
    progress=None,
) -> tuple[np.ndarray, np.ndarray]:
    """World-space positions and normals of every instance (the CPU reference).

    axis : ControlAxis of the base mesh.
    positions, normals : (v, 3) float — base mesh, file vertex order.
    params : (n, 16) float — the 16 numbers per instance.
    progress : optional object with ``update(instances_done)`` (a tqdm bar).
    Returns ``W = R·V' + p`` and ``R·n'``, each (n, v, 3) float32.
    """
    params = as_params(params)
    positions = as_array(positions, (None, 3), "positions")
    normals = as_array(normals, (len(positions), 3), "normals")
    n, v = len(params), len(positions)
    out_pos = np.empty((n, v, 3), dtype=np.float32)
    out_nrm = np.empty((n, v, 3), dtype=np.float32)
    step = max(1, chunk_vertices // max(v, 1))
    for a in range(0, n, step):  # chunks bound memory; each chunk is fully vectorized
        block = params[a : a + step].astype(np.float64)
        moved, bent = deform_local(axis, positions, normals, block[:, OFFSETS].reshape(-1, 5, 2))
        rot = rotation_matrices(block[:, ANGLES])
        out_pos[a : a + step] = np.einsum("nij,nvj->nvi", rot, moved) + block[:, None, POSITION]
        out_nrm[a : a + step] = np.einsum("nij,nvj->nvi", rot, bent)
        if progress is not None:
            progress.update(len(block))
    return out_pos, out_nrm

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
from .errors import ArgumentError
from .params import as_params, check_tree_params
from .record import (
    ANGLES,
    EXTENDED_WIDTH,
    EXTRA,
    OFFSETS,
    POSITION,
    SCALE,
    TAPER,
    TWIST,
    split_record,
)
from .transforms import rotation_matrices

__all__ = [
    "bernstein",
    "rotation_matrices",
    "axis_offsets",
    "displace",
    "deform_local",
    "deform_local_extended",
    "bend_model",
    "deform",
    "tree_bend",
    "deform_tree",
]

#: a term's ``t_j`` counts as clamped (no derivative) only beyond ``[−T_SLACK, 1 + T_SLACK]``:
#: a vertex's own axis spans it, and float32 rounding on the GPU must not drop its slope
#: (``AXIAL_T_SLACK`` in ``glsl/axial.glsl``; several axes only)
T_SLACK = 1e-4

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
    if axis.framed:  # E(D) = D_u e_u + D_v e_v
        return p + axis.embed(disp)
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


def deform_local_extended(
    axis: ControlAxis, positions: np.ndarray, normals: np.ndarray, offsets: np.ndarray, extra: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Bend, twist and taper the base mesh in model space, then scale it
    (the extension in ``docs/method.md``; no rotation or position).

    positions, normals : (v, 3) — the base mesh.
    offsets : (n, 5, 2) — per-instance control-point offsets.
    extra : (n, 3) — per-instance ``s tw tp``.
    Returns ``s·V''`` (n, v, 3) and the unit normal ``normalize(cof(J)·n)``
    (n, v, 3), float64, with ``V''`` = the cross-section ``w`` (about the axis
    line through the bounding-box centre) turned by ``θ = tw·t``, scaled by
    ``k = 1 − tp·t``, plus ``E(D(t))``.

    ``cof(J)·n`` is evaluated in closed form: with ``M = k·Rot(θ)`` (the 2×2
    block across the axis) and ``g = ∂V''_across/∂t = D'(t) − tp·Rot·w +
    k·tw·Rot·(−w_v, w_u)``, ``cof(J)·n / k = (k·n_a − g·(Rot·n_across)/L ;
    Rot·n_across)``.  With ``s = 1, tw = tp = 0`` every extra term is an exact
    zero, so the result is bit for bit that of :func:`deform_local`.
    """
    p = np.asarray(positions, dtype=np.float64)
    nrm = np.asarray(normals, dtype=np.float64)
    ex = np.asarray(extra, dtype=np.float64)
    scale, twist, taper = ex[:, 0, None], ex[:, 1, None], ex[:, 2, None]  # (n, 1) each
    t = axis.parameter(p)
    disp, slope = axis_offsets(axis, t, offsets)
    i, j = axis.perpendicular
    center = np.asarray(axis.center, dtype=np.float64)
    w = np.stack([p[:, i] - center[i], p[:, j] - center[j]], axis=-1)  # (v, 2) across the axis line
    theta = twist * t  # (n, v)
    k = 1.0 - taper * t
    c, s = np.cos(theta), np.sin(theta)
    rw = np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1]], axis=-1)  # Rot(θ) w, (n, v, 2)
    shift = k[..., None] * rw - w  # exactly 0 when tw = tp = 0
    moved = np.broadcast_to(p, disp.shape[:2] + (3,)).copy()
    moved[..., i] += shift[..., 0] + disp[..., 0]
    moved[..., j] += shift[..., 1] + disp[..., 1]
    moved *= scale[..., None]
    # the normal: cof(J) n, divided by k > 0 (it is normalized)
    rn = np.stack([c * nrm[:, i] - s * nrm[:, j], s * nrm[:, i] + c * nrm[:, j]], axis=-1)  # Rot(θ) n_across
    turn = np.stack([-rw[..., 1], rw[..., 0]], axis=-1)  # dRot/dθ w
    g = slope + ((k * twist)[..., None] * turn - taper[..., None] * rw)
    bent = np.empty_like(moved)
    bent[..., axis.index] = k * nrm[:, axis.index] - (g[..., 0] * rn[..., 0] + g[..., 1] * rn[..., 1]) / axis.length
    bent[..., i] = rn[..., 0]
    bent[..., j] = rn[..., 1]
    bent /= np.maximum(np.linalg.norm(bent, axis=-1, keepdims=True), 1e-300)
    return moved, bent


def bend_model(axis: ControlAxis, positions: np.ndarray, normals: np.ndarray, offsets: np.ndarray,
               extra: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The bend in model space for any axis frame (no rotation or position).

    An aligned axis is :func:`deform_local` (``extra`` None) or
    :func:`deform_local_extended`, unchanged.  A framed axis bends the local
    coordinates ``ℓ = F·V`` along their first coordinate and goes back by
    ``Fᵀ``: ``V'' = V + Fᵀ·(ℓ'' − ℓ)``, ``n'' = Fᵀ·n''_local``
    (``docs/method.md``, "A chosen axis frame"), so all-zero offsets give
    ``V`` exactly.

    positions, normals : (v, 3); offsets : (n, 5, 2); extra : (n, 3) ``s tw tp`` or None.
    Returns ``s·V''`` and unit ``n''``, each (n, v, 3) float64.
    """
    if not axis.framed:
        if extra is None:
            return deform_local(axis, positions, normals, offsets)
        return deform_local_extended(axis, positions, normals, offsets, extra)
    p = np.asarray(positions, dtype=np.float64)
    lp, ln, la, f = axis.local(p), axis.local(normals), axis.local_axis(), axis.matrix
    if extra is None:
        moved, bent = deform_local(la, lp, ln, offsets)
        scale = None
    else:
        ex = np.array(extra, dtype=np.float64)
        scale, ex[:, 0] = ex[:, 0].copy(), 1.0  # s scales in model space, after the frame
        moved, bent = deform_local_extended(la, lp, ln, offsets, ex)
    moved = p + (moved - lp) @ f
    if scale is not None:
        moved *= scale[:, None, None]
    return moved, bent @ f


def deform(
    axis,
    positions: np.ndarray,
    normals: np.ndarray | None = None,
    params: np.ndarray | None = None,
    *,
    chunk_vertices: int = 4_000_000,
    progress=None,
) -> tuple[np.ndarray, np.ndarray]:
    """World-space positions and normals of every instance (the CPU reference).

    Called as ``deform(mesh, params)`` with a :class:`~axialdeform.core.mesh.BaseMesh` (its axis
    frame and axes included), or ``deform(axis, positions, normals, params)``.

    Parameters
    ----------
    axis : ControlAxis or BaseMesh
        The base mesh's control axis (or the mesh itself).
    positions, normals : (v, 3) float
        The base mesh, file vertex order (or, for a mesh, ``params`` in their place).
    params : (n, 16) float
        The 16 numbers per instance, or (n, 19): extended instances (scale, twist, taper;
        :func:`deform_local_extended`).
    chunk_vertices : int
        Instances are done in pieces of about this many vertices (bounded memory).
    progress : object, optional
        With ``update(instances_done)`` (a tqdm bar).

    Returns
    -------
    positions, normals : (n, v, 3) float32
        ``W = R·V' + p`` and ``R·n'`` (extended: ``W = R·(s·V'') + p`` and ``R·n''``).
    """
    if not isinstance(axis, ControlAxis):  # deform(mesh, params)
        mesh = axis
        if not hasattr(mesh, "axis") or normals is not None or params is not None:
            raise ArgumentError("deform: expected deform(mesh, params) or deform(axis, positions, normals, params)")
        if getattr(mesh, "tree", None) is not None:  # several axes: core/axes.py
            return deform_tree(mesh, positions, progress=progress)
        axis, positions, normals, params = mesh.axis, mesh.positions, mesh.normals, positions
    params = as_params(params)
    positions = as_array(positions, (None, 3), "positions")
    normals = as_array(normals, (len(positions), 3), "normals")

    def bend(rows):
        block = rows.astype(np.float64)
        return block, *bend_model(axis, positions, normals, block[:, OFFSETS].reshape(-1, 5, 2),
                                  block[:, EXTRA] if block.shape[1] >= EXTENDED_WIDTH else None)

    return _to_world(params, len(positions), bend, chunk_vertices, progress)


def _to_world(params, v: int, bend, chunk_vertices: int, progress):
    """``W = R·(s·V'') + p`` and ``R·n''`` (n, v, 3) float32 of ``params``, in
    chunks of instances that bound memory (each fully vectorized):
    ``bend(rows)`` gives a chunk's ``(standard record float64, s·V'', n'')``."""
    n = len(params)
    out_pos = np.empty((n, v, 3), dtype=np.float32)
    out_nrm = np.empty((n, v, 3), dtype=np.float32)
    step = max(1, chunk_vertices // max(v, 1))
    for a in range(0, n, step):
        block, moved, bent = bend(params[a : a + step])
        rot = rotation_matrices(block[:, ANGLES])
        out_pos[a : a + step] = np.einsum("nij,nvj->nvi", rot, moved) + block[:, None, POSITION]
        out_nrm[a : a + step] = np.einsum("nij,nvj->nvi", rot, bent)
        if progress is not None:
            progress.update(len(block))
    return out_pos, out_nrm


def deform_tangents(axis: ControlAxis, positions: np.ndarray, tangents: np.ndarray, params: np.ndarray) -> np.ndarray:
    """World-space unit tangents of every instance (normal mapping), the CPU
    twin of ``axial_world_tangent`` in ``glsl/axial.glsl``.

    A tangent is a differential of the position, so it moves by the Jacobian
    ``J = dV''/dV`` of the (extended) bend -- across the axis
    ``k·Rot(θ)·T_across + g·T_a / L``, along it ``T_a`` (``k``, ``θ``, ``g`` as
    in :func:`deform_local_extended`; for a 16-number instance ``J = I +
    E(D'(t)) e_a^T / L``) -- then by ``R`` (the uniform scale ``s`` drops out
    when normalised).  The normal moves by ``cof(J)``.  Wind moves control
    points: pass the wind-moved parameters (:mod:`axialdeform.core.wind`).

    positions : (v, 3) float; tangents : (v, 3) or (v, 4) float (w, the
    handedness, is dropped: it does not change); params : (n, 16) or (n, 19) float.
    Returns (n, v, 3) float32.
    """
    params = as_params(params).astype(np.float64)
    p = np.asarray(positions, dtype=np.float64)
    tan = np.asarray(tangents, dtype=np.float64)[:, :3]
    frame = axis.matrix if axis.framed else None
    if frame is not None:  # bend in the local coordinates, back by Fᵀ (bend_model)
        p, tan, axis = axis.local(p), axis.local(tan), axis.local_axis()
    t = axis.parameter(p)
    _, slope = axis_offsets(axis, t, params[:, OFFSETS].reshape(-1, 5, 2))
    i, j = axis.perpendicular
    along = tan[:, axis.index] / axis.length  # (v,)
    bent = np.broadcast_to(tan, slope.shape[:2] + (3,)).copy()
    if params.shape[1] >= EXTENDED_WIDTH:
        twist, taper = params[:, TWIST, None], params[:, TAPER, None]  # (n, 1)
        center = np.asarray(axis.center, dtype=np.float64)
        w = np.stack([p[:, i] - center[i], p[:, j] - center[j]], axis=-1)  # (v, 2)
        theta = twist * t
        k = 1.0 - taper * t  # (n, v)
        c, s = np.cos(theta), np.sin(theta)
        rw = np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1]], axis=-1)  # (n, v, 2)
        turn = np.stack([-rw[..., 1], rw[..., 0]], axis=-1)
        g = slope + ((k * twist)[..., None] * turn - taper[..., None] * rw)
        bent[..., i] = k * (c * tan[:, i] - s * tan[:, j]) + g[..., 0] * along
        bent[..., j] = k * (s * tan[:, i] + c * tan[:, j]) + g[..., 1] * along
    else:
        bent[..., i] += slope[..., 0] * along
        bent[..., j] += slope[..., 1] * along
    if frame is not None:
        bent = bent @ frame
    world = np.einsum("nij,nvj->nvi", rotation_matrices(params[:, ANGLES]), bent)
    world /= np.maximum(np.linalg.norm(world, axis=-1, keepdims=True), 1e-300)
    return world.astype(np.float32)


# ------------------------------------------------------------------ several axes (core/axes.py)
def _cofactor_apply(jac: np.ndarray, n: np.ndarray) -> np.ndarray:
    """``cof(J)·n`` for (..., 3, 3) ``J`` and (..., 3) ``n``: columns of cof(J)
    are the cross products of pairs of J's columns."""
    c0, c1, c2 = jac[..., :, 0], jac[..., :, 1], jac[..., :, 2]
    return (n[..., 0, None] * np.cross(c1, c2) + n[..., 1, None] * np.cross(c2, c0)
            + n[..., 2, None] * np.cross(c0, c1))


def tree_bend(tree, positions, normals, offsets, extra=None, *, center=None):
    """The bend of a K-axis mesh in model space (no rotation or position).

    positions, normals : (v, 3); offsets : (n, K, 5, 2); extra : (n, 3) ``s tw tp`` or None;
    center : axis 0's axis line (default its own).
    Returns ``s·V''`` and unit ``n''`` (n, v, 3) float64, and the Jacobian (n, v, 3, 3).
    """
    p = np.asarray(positions, dtype=np.float64)
    nrm = np.asarray(normals, dtype=np.float64)
    offs = np.asarray(offsets, dtype=np.float64)
    n, v = len(offs), len(p)
    weight = tree.weights  # (v, K): 1 on a vertex's chain, 0 off it; a blend's two chains (1 - w, w)
    jac = np.broadcast_to(np.eye(3), (n, v, 3, 3)).copy()
    moved = np.broadcast_to(p, (n, v, 3)).copy()
    root = tree.axes[0]
    f0 = root.matrix
    if extra is not None:  # twist and taper about axis 0's axis line, before the displacements
        ex = np.asarray(extra, dtype=np.float64)
        twist, taper = ex[:, 1, None], ex[:, 2, None]
        local = p @ f0.T
        raw = (local[:, 0] - root.lo) / root.length
        t = np.clip(raw, 0.0, 1.0)
        line = np.asarray(root.line if center is None else center)
        w = local[:, 1:] - line
        theta, k = twist * t, 1.0 - taper * t
        c, s = np.cos(theta), np.sin(theta)
        rw = np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1]], axis=-1)  # (n, v, 2)
        moved += (k[..., None] * rw - w) @ f0[1:]
        inside = ((raw >= -T_SLACK) & (raw <= 1 + T_SLACK)).astype(np.float64)  # beyond the ends k, θ are constant
        g = ((k * twist)[..., None] * np.stack([-rw[..., 1], rw[..., 0]], axis=-1)
             - taper[..., None] * rw) * (inside / root.length)[None, :, None]
        jl = np.zeros((n, v, 3, 3))
        jl[..., 0, 0] = 1.0
        jl[..., 1:, 0] = g
        jl[..., 1, 1], jl[..., 1, 2] = k * c, -k * s
        jl[..., 2, 1], jl[..., 2, 2] = k * s, k * c
        jac = f0.T @ jl @ f0
    for j, axis in enumerate(tree.axes):
        idx = np.flatnonzero(weight[:, j])
        if not len(idx):
            continue
        f = axis.matrix
        raw = (p[idx] @ f[0] - axis.lo) / axis.length
        t = np.clip(raw, 0.0, 1.0)
        disp, slope = axis_offsets(axis, t, offs[:, j])  # (n, |idx|, 2)
        omega = weight[idx, j][None, :, None]  # the offsets weighed (the bend is linear in them)
        moved[:, idx] += (disp * omega) @ f[1:]
        inside = ((raw >= -T_SLACK) & (raw <= 1 + T_SLACK)).astype(np.float64)
        across = (slope * omega * (inside / axis.length)[None, :, None]) @ f[1:]  # (n, |idx|, 3)
        jac[:, idx] += across[..., :, None] * f[0][None, None, None, :]
    bent = _cofactor_apply(jac, np.broadcast_to(nrm, moved.shape))
    bent /= np.maximum(np.linalg.norm(bent, axis=-1, keepdims=True), 1e-300)
    if extra is not None:
        moved *= np.asarray(extra, dtype=np.float64)[:, 0, None, None]
    return moved, bent, jac


def deform_tree(mesh, params, *, chunk_vertices: int = 1_000_000, progress=None):
    """World positions and normals of every instance of a K-axis mesh (the
    CPU reference): ``(n, v, 3)`` float32 each.  ``params``: (n, 10·K + 6)
    (``+ 3`` extended, ``+ 6`` tinted)."""
    tree = mesh.tree
    k = tree.count
    params = check_tree_params(params, k)

    def bend(rows):
        standard, children = split_record(rows, k)
        block = standard.astype(np.float64)
        offsets = np.concatenate([block[:, :10].reshape(-1, 1, 5, 2), children.astype(np.float64)], axis=1)
        extra = block[:, [SCALE, TWIST, TAPER]] if block.shape[1] >= EXTENDED_WIDTH else None
        moved, bent, _ = tree_bend(tree, mesh.positions, mesh.normals, offsets, extra)
        return block, moved, bent

    return _to_world(params, mesh.vertex_count, bend, chunk_vertices, progress)

"""Blended vertices (docs/method.md, "Blended vertices"): a vertex that moves with two axes' chains, its
second axis and weight (``AxisTree.blend``) -- their check, the one number a vertex the GPU receives
(:func:`join_vertex_code`, :func:`split_vertex_code`), and how the skeleton binds the pieces no branch runs
in (rule 5 of :mod:`axialdeform.core.skeleton`, :func:`blend_pieces`): each point of a carried piece (a
crown, a bark mark, a curtain of leaves) blends the two branches nearest it, and a limb piece of its own (a
crown a branch was found in) moves with what it rests on where it touches it.  numpy and scipy."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.spatial import cKDTree

from .errors import MeshError

__all__ = ["BLEND_STEPS", "CONTACT", "SMOOTHING", "check_blend", "join_vertex_code", "split_vertex_code", "blend_pieces"]

#: a blend's weight is q / BLEND_STEPS, q a whole number: the GPU's vertex code holds 11 bits of it
BLEND_STEPS = 2047


def check_blend(blend, v: int, k: int):
    """``blend`` as :class:`AxisTree` holds it: (v, 2) float64, the weights rounded to q / 2047; None where no
    vertex blends."""
    if blend is None:
        return None
    b = np.asarray(blend, dtype=np.float64)
    if b.shape != (v, 2) or not np.all(np.isfinite(b)):
        raise MeshError(f"axes: blend: expected a (v, 2) array of (second axis, weight) for {v} vertices, found shape "
                        f"{b.shape}")
    axis, w = b[:, 0], np.rint(np.clip(b[:, 1], 0.0, 1.0) * BLEND_STEPS) / BLEND_STEPS
    if np.any(axis != np.rint(axis)) or (len(axis) and (axis.min() < 0 or axis.max() >= k)) or np.any(b[:, 1] < 0) \
            or np.any(b[:, 1] > 1):
        raise MeshError(f"axes: blend: expected second axes of 0..{k - 1} and weights in 0..1")
    if not np.any(w > 0):
        return None
    out = np.stack([np.where(w > 0, axis, 0.0), w], axis=1)
    out.flags.writeable = False
    return out


def join_vertex_code(vertex_axis, blend) -> np.ndarray:
    """(v,) int64: each vertex's code ``b + 64·b₁ + 4096·q`` (:attr:`AxisTree.vertex_code`) from its axis and its
    blend ((v, 2): second axis, weight; or None); the inverse of :func:`split_vertex_code`."""
    b = np.asarray(vertex_axis, dtype=np.int64)
    if blend is None:
        return b.copy()
    q = np.rint(np.asarray(blend, dtype=np.float64)[:, 1] * BLEND_STEPS).astype(np.int64)
    return b + 64 * np.asarray(blend)[:, 0].astype(np.int64) * (q > 0) + 4096 * q


def split_vertex_code(code) -> tuple[np.ndarray, np.ndarray | None]:
    """``(vertex_axis, blend)`` from each vertex's code (:attr:`AxisTree.vertex_code`, a GLB's ``_AXIAL_AXIS``):
    ``b = code mod 64``, ``b₁ = (code // 64) mod 64``, ``w = (code // 4096) / 2047``; blend None without one."""
    c = np.rint(np.asarray(code, dtype=np.float64)).astype(np.int64)
    b, b1, q = c % 64, (c // 64) % 64, c // 4096
    if not np.any(q > 0):
        return b.astype(np.int32), None
    return b.astype(np.int32), np.stack([b1, q / BLEND_STEPS], axis=1).astype(np.float64)


#: how many times a carried point's weights are averaged with its neighbours' (half each time): enough that an
#: edge of a crown held by several branches stretches no more than the edges inside one axis do
SMOOTHING = 6


def _smooth(weight, faces, carried) -> np.ndarray:
    """``weight`` (w, H) averaged :data:`SMOOTHING` times, half its own and half its neighbours' mean, over the
    edges of ``faces`` between points both ``carried``."""
    f = np.asarray(faces, dtype=np.int64)
    e = np.vstack([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    e = np.vstack([e, e[:, ::-1]])
    e = e[carried[e[:, 0]] & carried[e[:, 1]]]
    n = len(weight)
    adjacency = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    has = degree > 0
    for _ in range(SMOOTHING):
        around = adjacency @ weight
        weight = np.where(has[:, None], 0.5 * weight + 0.5 * around / np.maximum(degree, 1.0)[:, None], weight)
    return weight


#: a limb piece of its own that lies against another (a crown a branch runs in, resting on the wood) moves with
#: the other within this fraction of its size of it (fully where they touch)
CONTACT = 0.25


def blend_pieces(points, faces, label, axis, keep, limbs, chains) -> np.ndarray | None:
    """(w, 2) float64 or None: each welded point's second axis and weight (``AxisTree.blend``) for the carried
    pieces (crowns, bark marks, a curtain of leaves); ``axis`` (each point's first axis) is set to the nearest
    branch in place.  ``points`` (w, 3); ``label`` each point's piece; ``keep`` the chains kept; ``limbs`` the
    pieces chains run in; ``chains`` the skeleton's (``.piece``).

    A point at distances ``d_a <= d_b`` from the surfaces of the two branches nearest it starts with
    ``d_b / (d_a + d_b)`` of ``a``'s chain and ``d_a / (d_a + d_b)`` of ``b``'s (on a branch, with it alone;
    halfway between two, with both alike); every holder's weight is then averaged with the point's
    neighbours' :data:`SMOOTHING` times over the piece's edges (``faces``, welded), so that no edge spans a
    sudden change of the branches that hold it, and the two largest are kept, renormalized.
    """
    limb = np.isin(label, limbs)
    carried = ~limb
    for p in limbs:  # a limb piece no branch runs in is carried too
        if not any(chains[c].piece == p for c in keep):
            carried |= label == p
    holders = [j for j in range(len(keep)) if np.any(limb & (axis == j))]
    out = np.zeros((len(points), 2))
    mine = np.flatnonzero(carried)
    if len(mine) and len(holders) >= 2:
        d = np.stack([cKDTree(points[limb & (axis == j)]).query(points[mine])[0] for j in holders], axis=1)
        order = np.argsort(d, axis=1, kind="stable")[:, :2]
        da, db = np.take_along_axis(d, order, axis=1).T
        w = np.where(da + db > 0, da / np.where(da + db > 0, da + db, 1.0), 0.5)  # 0 on a, 1/2 halfway
        weight = np.zeros((len(points), len(holders)))  # every holder's weight at every carried point
        weight[mine, order[:, 0]] = 1.0 - w
        weight[mine, order[:, 1]] += w
        weight = _smooth(weight, faces, carried)
        top = np.argsort(-weight[mine], axis=1, kind="stable")[:, :2]
        wa, wb = np.take_along_axis(weight[mine], top, axis=1).T
        axis[mine] = np.asarray(holders)[top[:, 0]]
        out[mine] = np.stack([np.asarray(holders)[top[:, 1]], wb / np.maximum(wa + wb, 1e-300)], axis=1)
    # a limb piece of its own (a crown a branch was found in) where it lies against another limb piece: each
    # point within CONTACT of the piece's size of the other's surface moves with it, fully where they touch
    for p in limbs:
        others = limb & (label != p)
        if not others.any() or p == chains[keep[0]].piece:  # the trunk's piece is what the others rest on
            continue
        own = np.flatnonzero(label == p)
        reach = CONTACT * max(float(np.ptp(points[own], axis=0).max()), 1e-12)
        dist, at = cKDTree(points[others]).query(points[own], distance_upper_bound=reach)
        close = np.isfinite(dist)
        w = 1.0 - dist[close] / reach
        out[own[close]] = np.stack([axis[np.flatnonzero(others)[at[close]]], w], axis=1)
    return out if np.any(out[:, 1] > 0) else None

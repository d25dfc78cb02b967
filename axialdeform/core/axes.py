"""Several axes in a hierarchy (trees): ``docs/method.md``, "Several axes".

A base mesh may carry K ≥ 1 axes: axis 0 is the root, every other axis
``k`` has a parent ``p(k) < k``, its own frame ``F_k`` (a child's ``e_a``
points away from its parent: ``t = 0`` is its root end), ``lo_k``, ``L_k``
from ITS vertices, and its own ten offsets.  Every vertex belongs to one
axis ``b(V)`` and moves by the bend of that axis and of every ancestor,
each evaluated at the vertex itself::

    V' = V + Σ_{j ∈ chain(b(V))} F_jᵀ · E(D_j(t_j(V)))
    J  = I + Σ_j F_jᵀ E(D_j'(t_j)) ⊗ e_a,j / L_j      (terms with a clamped t_j drop)
    n' = normalize(cof(J) · n)

A vertex may blend two chains (``AxisTree.blend``: a second axis ``b₁(V)`` and its
weight ``w``): every sum above then weighs axis ``j`` by ``ω_j = (1 - w)·[j ∈ chain(b)]
+ w·[j ∈ chain(b₁)]`` (an ancestor of both counts once, fully).  The GPU receives
the pair as one number a vertex, ``code = b + 64·b₁ + 4096·q``, ``w = q / 2047``
(:attr:`AxisTree.vertex_code`; without a blend, ``code = b``; :mod:`~axialdeform.core.blend`).

Scale, twist and taper (the extended form) act on the whole mesh about
axis 0's axis line before the displacements.  One instance is ``10·K + 6``
numbers (``+ 3`` extended, ``+ 6`` tinted): axis 0's ten offsets, axis 1's
ten, ..., then ``px py pz rx ry rz [s tw tp [tr tg tb]]``; K = 1 is the
16 (19, 22) numbers exactly.

In this module: the tree itself (:class:`AxisTree`), how a mesh gets one
(:func:`tree_from_spec`, :func:`tree_from_parts`, :func:`tree_from_vertices`);
the wind on every axis is :func:`~axialdeform.core.wind.tree_wind_offsets`.  The record of K axes is in
:mod:`~axialdeform.core.record` (``tree_width``, ``split_record``,
``join_record``) and :func:`~axialdeform.core.params.check_tree_params`; the
CPU reference in :mod:`~axialdeform.core.deform` (``deform_tree``).  Pure numpy.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import numpy as np

from .axis import ControlAxis, stable_bytes
from .blend import check_blend, join_vertex_code
from .errors import MeshError, ParamError, brief_names
from .record import MAX_RECORD_AXES

#: the most axes one mesh may carry: a record's most (core/record.py)
MAX_AXES = MAX_RECORD_AXES
#: the rules a mesh's axes may be found by, by name (``axes="parts"``, ...): one axis per part, the
#: curve skeleton (core/skeleton.py), or whichever of the two fits the model (``BaseMesh.with_axes``)
AXES_RULES = ("parts", "skeleton", "auto")

__all__ = ["AxisTree", "TREE_AXES", "MAX_AXES", "AXES_RULES", "check_parents", "tree_from_spec", "tree_from_parts",
           "tree_from_vertices", "axes_of", "level_bends", "child_offsets"]


@dataclass(frozen=True, eq=False)
class AxisTree:
    """The K axes of a base mesh and which vertex belongs to which.

    Attributes
    ----------
    axes : tuple of K :class:`ControlAxis`
        Axis 0 is the root (the mesh's :attr:`~BaseMesh.axis`).
    parents : tuple of K int
        ``parents[0] == -1``; ``parents[k] < k``.
    vertex_axis : (v,) int32
        The axis ``b(V)`` of each vertex.
    names : tuple of K str
        A name per axis (the part it was made from, or ``axis{k}``).
    blend : (v, 2) float64 or None
        Each vertex's second axis ``b₁`` and its weight ``w`` in [0, 1] (held as ``q / 2047``, what the
        GPU receives): the vertex moves by ``(1 - w)`` times its own chain's bend plus ``w`` times
        ``b₁``'s (:meth:`weights`).  None: every vertex one chain (``w = 0``).
    anchors : tuple of K float
        Where each child axis meets its parent: ``t_a`` in [0, 1] on the child's
        own axis (``anchors[0]`` is 0 and unused).  By default measured from
        the geometry (:func:`joint_anchor`: the point of the child's axis
        segment nearest its parent's); random variation pins the child's bend
        there (:func:`child_offsets`).  Not part of the deformation, so not of
        :attr:`digest`: a parameter file is the same for any anchors.
    """

    axes: tuple
    parents: tuple
    vertex_axis: np.ndarray
    names: tuple = ()
    anchors: tuple = ()
    blend: np.ndarray | None = None

    def __post_init__(self) -> None:
        k = len(self.axes)
        parents = check_parents(self.parents, k)
        va = np.ascontiguousarray(self.vertex_axis, dtype=np.int32)
        if va.ndim != 1 or (len(va) and (va.min() < 0 or va.max() >= k)):
            raise MeshError(f"axes: vertex axis indices: expected a (v,) array of 0..{k - 1}")
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "vertex_axis", va)
        object.__setattr__(self, "blend", check_blend(self.blend, len(va), k))
        object.__setattr__(self, "names", tuple(self.names) or tuple(f"axis{i}" for i in range(k)))
        given = tuple(self.anchors) or (None,) * k
        if len(given) != k:
            raise MeshError(f"axes: anchors: expected one per axis ({k}), found {len(given)}")
        anchors = [0.0]
        for j in range(1, k):
            t = given[j]
            if t is None:
                t = joint_anchor(self.axes[j], self.axes[parents[j]])
            elif isinstance(t, bool) or not isinstance(t, (int, float, np.integer, np.floating)) or not 0 <= t <= 1:
                raise MeshError(f"axes: anchor of axis {j} ({self.names[j]}): expected t in 0..1 on its own axis, "
                                f"found {t!r:.40}")
            anchors.append(float(t))
        object.__setattr__(self, "anchors", tuple(anchors))

    @property
    def count(self) -> int:
        """K, the number of axes."""
        return len(self.axes)

    @property
    def depth(self) -> np.ndarray:
        """(K,) int: each axis's level in the hierarchy (0: the root, 1: its children, ...)."""
        d = np.zeros(self.count, dtype=int)
        for k in range(1, self.count):
            d[k] = d[self.parents[k]] + 1
        return d

    @property
    def chain(self) -> np.ndarray:
        """(K, K) bool: ``chain[b, j]`` is True when axis ``j`` is ``b`` or one of its ancestors."""
        c = np.eye(self.count, dtype=bool)
        for k in range(1, self.count):
            c[k] |= c[self.parents[k]]
        return c

    @property
    def weights(self) -> np.ndarray:
        """(v, K) float64: ``ω[v, j]``, how much axis ``j`` moves vertex ``v`` -- 1 on its chain, 0 off it,
        ``1 - w`` and ``w`` on the two chains a blended vertex mixes (1 where they share an ancestor)."""
        chain = self.chain.astype(np.float64)
        if self.blend is None:
            return chain[self.vertex_axis]
        w = self.blend[:, 1:2]
        return (1.0 - w) * chain[self.vertex_axis] + w * chain[self.blend[:, 0].astype(np.int64)]

    @property
    def vertex_code(self) -> np.ndarray:
        """(v,) float32: each vertex's axes as the GPU receives them (the attribute ``in_axis``, a GLB's
        ``_AXIAL_AXIS``): ``b + 64·b₁ + 4096·q``, below 2²³ so that float32 holds it and a shader's
        ``int(code + 0.5)`` gives it back exactly; ``b`` without a blend."""
        return join_vertex_code(self.vertex_axis, self.blend).astype(np.float32)

    @property
    def digest(self) -> bytes:
        """16 bytes identifying the tree (frames, lo, L, parents, vertex axes): parameter files record it.
        The computed numbers are hashed as :func:`~axialdeform.core.axis.stable_bytes` rounds them (to 1e-9;
        ``lo`` and ``L`` relative to the root's ``L``), so a file written on one machine
        reads on every other whatever BLAS kernel computed the frames."""
        scale = float(self.axes[0].length) or 1.0
        return self._digest(lambda a: stable_bytes(a.matrix) + stable_bytes(np.array([a.lo, a.length]) / scale))

    @property
    def legacy_digest(self) -> bytes:
        """The digest files written before 0.2 record (the float64 bits): still read."""
        return self._digest(lambda a: np.asarray(a.matrix, dtype="<f8").tobytes()
                            + np.asarray([a.lo, a.length], dtype="<f8").tobytes())

    def _digest(self, axis_bytes) -> bytes:
        h = hashlib.sha256()
        for a in self.axes:
            h.update(axis_bytes(a))
        h.update(np.asarray(self.parents, dtype="<i4").tobytes())
        h.update(self.vertex_axis.astype("<i4").tobytes())
        if self.blend is not None:  # a tree without blends keeps the digest files already record
            h.update(self.vertex_code.astype("<f4").tobytes())
        return h.digest()[:16]

    def to_json(self) -> dict:
        """The tree as a loader needs it to bend (the page's config, a GLB's extras and its
        ``AXIALDEFORM_bend``): ``{count, names, parents, frames (rows e_a, e_u, e_v), lo, length, anchors}``;
        each vertex's axis travels separately (``_AXIAL_AXIS``)."""
        return {"count": self.count, "names": [str(n) for n in self.names], "parents": [int(p) for p in self.parents],
                "frames": [np.asarray(a.matrix, dtype=np.float64).tolist() for a in self.axes],
                "lo": [float(a.lo) for a in self.axes], "length": [float(a.length) for a in self.axes],
                "anchors": [float(t) for t in self.anchors]}

    def describe(self) -> str:
        """``K axes (trunk, branch1 <- trunk, frond2 <- trunk @ t=0.35, ...)``: the hierarchy, and
        each child's anchor where it is not its root end; ``; N vertices blend two axes`` where some do."""
        blended = 0 if self.blend is None else int(np.count_nonzero(self.blend[:, 1]))
        return f"{self.count} axes (" + ", ".join(
            f"{n}{'' if p < 0 else ' <- ' + self.names[p]}{f' @ t={a:.2f}' if p >= 0 and a >= 0.005 else ''}"
            for n, p, a in zip(self.names, self.parents, self.anchors)) + ")" + \
            (f"; {blended} vertices blend two axes" if blended else "")


def axes_of(mesh) -> int:
    """K, the number of axes of ``mesh`` (1 without a tree)."""
    tree = getattr(mesh, "tree", None)
    return 1 if tree is None else tree.count


#: the hierarchy of the bundled tree (``load_mesh("tree", axes=TREE_AXES)``; ``tools/make_tree.py``):
#: the trunk along y, every branch and twig along its own oriented box
TREE_AXES = ([{"part": "trunk", "axis": "y"}]
             + [{"part": f"branch{k}", "parent": "trunk", "axis": "oriented"} for k in range(1, 7)]
             + [{"part": f"twig{t}", "parent": f"branch{2 * t - 1}", "axis": "oriented"} for t in range(1, 4)])


# ------------------------------------------------------------------ variation of the child axes
def level_bends(bend, error: type = ParamError) -> tuple[float, ...]:
    """``bend`` as one amplitude per level of a hierarchy (a number: every
    level the same); each a finite fraction of an axis's length >= 0, else ``error``."""
    bends = tuple(bend) if isinstance(bend, (list, tuple, np.ndarray)) else (bend,)
    if not bends or not all(isinstance(b, (int, float, np.integer, np.floating)) and math.isfinite(b) and b >= 0
                            for b in bends):
        raise error(f"bend: expected a finite fraction of L >= 0 (or one per level of the hierarchy), found {bend!r}")
    return tuple(float(b) for b in bends)


def bernstein4(t) -> tuple[np.ndarray, np.ndarray]:
    """The degree-4 Bernstein weights at ``t`` and their derivatives: two ``(..., 5)`` arrays
    (``D(t) = Σ B_i(t) d_{i+1}``, ``D'(t) = Σ B_i'(t) d_{i+1}``)."""
    t = np.asarray(t, dtype=np.float64)[..., None]
    i = np.arange(5)
    binom = np.array([1.0, 4.0, 6.0, 4.0, 1.0])
    b = binom * t**i * (1.0 - t) ** (4 - i)
    # d/dt B_i = 4 (B3_{i-1} - B3_i)
    b3 = np.array([1.0, 3.0, 3.0, 1.0]) * t ** np.arange(4) * (1.0 - t) ** (3 - np.arange(4))
    db = 4.0 * (np.concatenate([np.zeros_like(t), b3], axis=-1) - np.concatenate([b3, np.zeros_like(t)], axis=-1))
    return b, db


def anchor_projection(t_anchor) -> np.ndarray:
    """``(..., 5, 5)``: the orthogonal projection of five control offsets onto those whose
    curve is pinned at ``t_anchor`` with zero slope (``D(t_a) = 0``, ``D'(t_a) = 0``, a clamped
    joint): ``P = I − Aᵀ (A Aᵀ)⁻¹ A`` with ``A`` the rows ``B(t_a)``, ``B'(t_a)``.  At ``t_a = 0``
    it zeroes ``d₁`` and ``d₂``; it never lengthens the offsets."""
    b, db = bernstein4(t_anchor)
    a = np.stack([b, db], axis=-2)  # (..., 2, 5)
    gram = a @ np.swapaxes(a, -1, -2)
    return np.eye(5) - np.swapaxes(a, -1, -2) @ np.linalg.solve(gram, a)


def child_offsets(tree: AxisTree, bends: tuple, uniform: np.ndarray) -> np.ndarray:
    """The child axes' offsets ``(n, K − 1, 5, 2)`` float64 from uniforms in
    [0, 1) of that shape: axis ``j`` uniform in ``±bends[level]·L_j`` (the last
    amplitude for any deeper level), then projected onto the offsets whose
    bend vanishes at the joint with its parent, value and slope
    (:func:`anchor_projection` at ``tree.anchors[j]``): however the child's
    axis runs through the joint -- a branch from its end, a leaf that
    crosses its stem -- the joint stays closed and the child leaves it at
    its rest angle."""
    amp = np.array([bends[min(d, len(bends) - 1)] * a.length for d, a in zip(tree.depth[1:], tree.axes[1:])])
    raw = (2.0 * np.asarray(uniform, dtype=np.float64) - 1.0) * amp[None, :, None, None]
    proj = anchor_projection(np.asarray(tree.anchors[1:], dtype=np.float64))  # (K-1, 5, 5)
    return np.einsum("jab,njbc->njac", proj, raw)


def droop_offsets(tree: AxisTree, droop: float, angles: np.ndarray, up: int = 1) -> np.ndarray:
    """The child axes' sag toward the world's down ``(n, K − 1, 5, 2)`` float64: axis ``j`` of an
    instance turned by ``angles`` ((n, 3), ``R = Rz·Ry·Rx``) bends toward ``down = −e_up`` seen in
    its own frame (the ``(u, v)`` part of ``F_j Rᵀ down``), as a cantilever sags from its joint:
    ``D(t) = droop·L_j·(u, v)·(t − t_a)² / max(t_a², (1 − t_a)²)`` (zero, with zero slope, at
    the anchor; ``droop·L_j`` at the far end of an axis lying across the down direction)."""
    return sag_offsets(tree.axes[1:], tree.anchors[1:], droop, angles, up)


def sag_weights(t_anchor) -> np.ndarray:
    """``(..., 5)``: the control polygon of ``(t − t_a)² / max(t_a², (1 − t_a)²)`` -- zero, with zero
    slope, at the anchor ``t_a`` and 1 at the far end:
    ``[t_a², t_a² − t_a/2, 1/6 − t_a + t_a², 1/2 − 3t_a/2 + t_a², (1 − t_a)²] / norm``
    (``(0, 0, 1/6, 1/2, 1)`` at ``t_a = 0``).  How a child axis droops (:func:`sag_offsets`) and
    how the wind pushes it (:func:`~axialdeform.core.wind.tree_wind_offsets`, ``glsl/axial.glsl``)."""
    a = np.asarray(t_anchor, dtype=np.float64)[..., None]
    t2, t1 = np.array([0.0, 0.0, 1 / 6, 1 / 2, 1.0]), np.array([0.0, 0.25, 0.5, 0.75, 1.0])  # t², t
    return (t2 - 2 * a * t1 + a**2) / np.maximum(a**2, (1 - a) ** 2)


def sag_offsets(axes, anchors, droop: float, angles: np.ndarray, up: int = 1) -> np.ndarray:
    """``(n, len(axes), 5, 2)`` float64: each axis (a :class:`ControlAxis`) of an instance turned by
    ``angles`` sagging toward the world's down from its anchor ``t_a`` (``anchors``, one each),
    ``droop·L·(u, v)·(t − t_a)² / max(t_a², (1 − t_a)²)`` with ``(u, v)`` the down direction in the
    axis's own frame (:func:`droop_offsets` of a tree's children; a single axis: ``random_params``
    and ``scatter``)."""
    from .transforms import rotation_matrices

    world_down = -np.eye(3)[up]
    model_down = np.einsum("nji,j->ni", rotation_matrices(np.asarray(angles, dtype=np.float64)), world_down)  # Rᵀ d
    frames = np.stack([np.asarray(a.matrix, dtype=np.float64) for a in axes])  # (K, 3, 3)
    across = np.einsum("jab,nb->nja", frames, model_down)[..., 1:]  # (n, K, 2): down in each axis's (u, v)
    curve = sag_weights(np.asarray(anchors, dtype=np.float64))  # (K, 5)
    amp = droop * np.array([a.length for a in axes])
    return amp[None, :, None, None] * curve[None, :, :, None] * across[:, :, None, :]


# ------------------------------------------------------------------ building a tree
def _axis_of(positions, name, frame) -> ControlAxis:
    return ControlAxis.from_positions(positions, name=name, frame=frame)


def _segment(axis: ControlAxis) -> tuple[np.ndarray, np.ndarray]:
    """The axis segment's two ends in model space: (t = 0, t = 1)."""
    pts = axis.control_points
    return pts[0], pts[-1]


def _closest_on_segments(a0, a1, b0, b1) -> tuple[float, float]:
    """``(s, t)`` in [0, 1]²: the points ``a0 + s (a1 - a0)`` and ``b0 + t (b1 - b0)`` of two
    segments nearest each other (the usual clamped solve; parallel segments: the middle of their
    overlap, as seen from the first)."""
    u, v, w = a1 - a0, b1 - b0, a0 - b0
    a, b, c, d, e = u @ u, u @ v, v @ v, u @ w, v @ w
    den = a * c - b * b
    s = np.clip((b * e - c * d) / den, 0.0, 1.0) if den > 1e-12 * a * c else 0.5
    t = np.clip((b * s + e) / c, 0.0, 1.0) if c > 0 else 0.0
    s = np.clip((b * t - d) / a, 0.0, 1.0) if a > 0 else 0.0
    return float(s), float(t)


def joint_anchor(child: ControlAxis, parent: ControlAxis) -> float:
    """Where a child axis meets its parent: ``t`` on the child's axis of the point of its
    segment nearest the parent's axis segment (0 for a branch that grows from its parent's line;
    mid-way for a leaf whose axis crosses its stem)."""
    p0, p1 = _segment(parent)
    c0, c1 = _segment(child)
    return _closest_on_segments(c0, c1, p0, p1)[0]


def _point_segment_distance(p, a, b) -> float:
    ab = b - a
    t = np.clip(np.dot(p - a, ab) / max(float(np.dot(ab, ab)), 1e-300), 0.0, 1.0)
    return float(np.linalg.norm(p - (a + t * ab)))


def _rooted(axis: ControlAxis, parent: ControlAxis, positions, name) -> ControlAxis:
    """``axis`` with ``e_a`` negated when its ``t = 1`` end is the nearer one to
    the parent's axis segment (so ``t = 0`` is its root)."""
    a, b = _segment(parent)
    lo_end, hi_end = _segment(axis)
    if _point_segment_distance(hi_end, a, b) < _point_segment_distance(lo_end, a, b):
        m = axis.matrix.copy()
        m[0] = -m[0]
        return _axis_of(positions, name, m)
    return axis


def check_parents(parents, count: int | None = None, name: str = "") -> tuple[int, ...]:
    """``parents`` as a tuple of ints if it is a tree's parent list -- ``-1`` for axis 0 and a parent
    ``p < k`` for every axis ``k`` (so no cycle, no forward or negative parent), 1 to
    :data:`MAX_AXES` of them (``count``, when given, of them) -- else a :class:`MeshError` in words."""
    where = f"{name}: " if name else ""
    if isinstance(parents, (str, bytes)) or not hasattr(parents, "__len__"):
        raise MeshError(f"{where}axes: parents: expected a list of axis indices, found {parents!r:.80}")
    if not 1 <= len(parents) <= MAX_AXES:
        raise MeshError(f"{where}axes: expected 1 to {MAX_AXES} axes, found {len(parents)}")
    if count is not None and len(parents) != count:
        raise MeshError(f"{where}axes: parents: expected one parent per axis ({count}), found {len(parents)}")
    if not all(isinstance(p, (int, np.integer)) and not isinstance(p, bool) for p in parents):
        raise MeshError(f"{where}axes: parents: expected whole numbers, found {tuple(parents)!r:.120}")
    out = tuple(int(p) for p in parents)
    if out[0] != -1 or any(not 0 <= p < i for i, p in enumerate(out) if i):
        raise MeshError(f"{where}axes: parents: expected -1 for axis 0 and a parent p < k for every axis k "
                        f"(no cycle, no forward or negative parent), found {out!r:.120}")
    return out


def tree_from_vertices(mesh, vertex_axis, parents, *, frames=None, names=None, root_children: bool = True,
                       anchors=None, blend=None) -> AxisTree:
    """A tree from per-vertex axis indices ``vertex_axis`` ((v,) int) and a
    parent list (``parents[0] = -1``); ``frames``: one frame rule per axis
    (``"auto"`` default, ``load_mesh(axis=...)``'s values).  Child axes are
    turned so that ``t = 0`` is their end nearer the parent's axis segment.
    ``blend``: each vertex's second axis and weight (:class:`AxisTree`), or None."""
    va = np.asarray(vertex_axis)
    if va.shape != (mesh.vertex_count,) or not np.issubdtype(va.dtype, np.integer):
        raise MeshError(f"{mesh.name}: axes: expected {mesh.vertex_count} integer vertex axis indices, found "
                        f"an array of shape {va.shape} ({va.dtype})")
    parents = check_parents(parents)  # before anything is sized by it (the caller names the file)
    k = len(parents)
    names = tuple(names) if names is not None else tuple(f"axis{i}" for i in range(k))
    frames = ["auto"] * k if frames is None else list(frames)
    if len(frames) != k or len(names) != k:
        raise MeshError(f"{mesh.name}: axes: expected one frame and one name per axis ({k}), "
                        f"found {len(frames)} and {len(names)}")
    axes = []
    for i in range(k):
        pts = mesh.positions[va == i]
        if not len(pts):
            raise MeshError(f"{mesh.name}: axes: axis {i} ({names[i]}) has no vertex; expected every axis to hold some")
        axis = _axis_of(pts, f"{mesh.name}: axis {names[i]}", frames[i])
        if i and root_children:
            axis = _rooted(axis, axes[int(parents[i])], pts, f"{mesh.name}: axis {names[i]}")
        axes.append(axis)
    anchors = (None,) * k if anchors is None else tuple(anchors)
    if len(anchors) != k:
        raise MeshError(f"{mesh.name}: axes: anchors: expected one per axis ({k}), found {len(anchors)}")
    try:
        return AxisTree(tuple(axes), tuple(int(p) for p in parents), va.astype(np.int32), names, anchors, blend)
    except MeshError as exc:
        raise MeshError(f"{mesh.name}: {exc}") from None


def _part_vertices(mesh) -> dict:
    """part name -> its vertex indices (sorted)."""
    return {p.name: np.unique(mesh.faces[p.start:p.start + p.count]) for p in mesh.parts if p.count}


def tree_from_spec(mesh, spec, frame="auto") -> AxisTree:
    """A tree from a list of ``{"part": NAME, "parent": NAME, "axis": FRAME}``
    (the root has no parent and comes first; a parent comes before its
    children).  A vertex shared by two parts belongs to the earlier axis."""
    if not isinstance(spec, (list, tuple)) or not spec:
        raise MeshError(f"{mesh.name}: axes: expected 'parts', per-vertex axes or a list of "
                        "{'part', 'parent', 'axis'} entries, found " + repr(spec)[:80])
    verts = _part_vertices(mesh)
    order, parents, frames, anchors, index_of = [], [], [], [], {}
    for i, entry in enumerate(spec):
        if not isinstance(entry, dict) or "part" not in entry or set(entry) - {"part", "parent", "axis", "anchor"}:
            raise MeshError(f"{mesh.name}: axes entry {i + 1}: expected a table with 'part' and optional "
                            f"'parent', 'axis' and 'anchor', found {entry!r}")
        part = entry["part"]
        if not isinstance(part, str) or part not in verts:
            raise MeshError(f"{mesh.name}: axes entry {i + 1}: no part {str(part)[:40]!r}; expected one of "
                            + brief_names(verts))
        if part in index_of:
            raise MeshError(f"{mesh.name}: axes entry {i + 1}: part {part!r} has an axis already")
        parent = entry.get("parent")
        if (parent is None) != (i == 0):
            raise MeshError(f"{mesh.name}: axes entry {i + 1} ({part}): expected " +
                            ("no parent for the root (the first entry)" if i == 0 else
                             "a parent (only the first entry, the root, has none)"))
        if parent is not None and (not isinstance(parent, str) or parent not in index_of):
            raise MeshError(f"{mesh.name}: axes entry {i + 1} ({part}): parent {parent!r} is not an earlier entry; "
                            "expected a parent listed before its children")
        index_of[part] = len(order)
        order.append(part)
        parents.append(-1 if parent is None else index_of[parent])
        frames.append(entry.get("axis", frame))
        anchor = entry.get("anchor")
        if anchor is not None and (isinstance(anchor, bool) or not isinstance(anchor, (int, float)) or not 0 <= anchor <= 1
                                   or i == 0):
            raise MeshError(f"{mesh.name}: axes entry {i + 1} ({part}): anchor: expected t in 0..1 on the part's own "
                            f"axis where it meets its parent (a child only), found {anchor!r:.40}")
        anchors.append(anchor)
    missing = [n for n in verts if n not in index_of]
    if missing:
        raise MeshError(f"{mesh.name}: axes: part(s) {brief_names(missing)} have no axis; "
                        "expected an entry for every part")
    va = np.full(mesh.vertex_count, -1, dtype=np.int32)
    for i, part in reversed(list(enumerate(order))):  # the earlier axis wins a shared vertex
        va[verts[part]] = i
    if (va < 0).any():  # vertices no triangle uses: the root's
        va[va < 0] = 0
    return tree_from_vertices(mesh, va, parents, frames=frames, names=order, anchors=anchors)


#: a part whose extent along the up axis is below this fraction of its width looks like ground
#: or water (scenery), not like a trunk: never the root of ``axes="parts"``
GROUND_FLATNESS = 0.2
#: a child whose axis segment passes further than this fraction of its length from its parent's
#: (neither crossing nor touching it) is a doubtful attachment: ``axes="parts"`` warns
DOUBTFUL_GAP = 0.25
#: candidate parents about as near as the nearest (within this fraction of the part's length): the
#: one nearer the root wins (a leaf crossing the crown touches its sibling leaves as much as the trunk)
TIE = 0.05


def _segment_distance(a, b) -> float:
    s, t = _closest_on_segments(*a, *b)
    return float(np.linalg.norm(a[0] + s * (a[1] - a[0]) - (b[0] + t * (b[1] - b[0]))))


def tree_from_parts(mesh, frame="auto", up: int = 1) -> AxisTree:
    """One axis per part, the hierarchy found from the structure (a heuristic; the list form,
    :func:`tree_from_spec`, says it exactly):

    * the root (trunk) is the part that starts lowest along ``up`` (the model's y, glTF's up):
      what grows from the ground and the others attach to -- never a flat, wide part (ground,
      water: its height below :data:`GROUND_FLATNESS` of its width), which is attached last and
      warned of (leave it out with ``parts=``);
    * every other part attaches to the part it crosses, touches or grows out of (its nearest
      vertex to the other's axis segment, less that part's radius about its axis), preferring
      the one nearer the root among those about as near (within :data:`TIE` of the part's
      length; then the one whose axis it comes nearest), so a leaf attaches to its stem, not to
      a sibling leaf beside it;
      nearest first, so parents come first;
    * a part further from its parent than :data:`DOUBTFUL_GAP` of its length is warned of
      (:class:`~axialdeform.core.material.AssetWarning`), as is every ground-like part.

    The tree is returned (``mesh.with_axes("parts").tree.describe()`` says it; ``info MESH --axes
    parts`` prints it)."""
    import warnings

    from .material import AssetWarning

    parts = sum(1 for p in mesh.parts if p.count)
    if parts > MAX_AXES:  # said before any work: each part's axis and the attachment search grow with the count
        raise MeshError(f"{mesh.name}: axes='parts': {parts} parts, but a mesh has at most {MAX_AXES} axes; expected "
                        f"at most {MAX_AXES} parts (name the parts to bend in a list of axes instead)")
    verts = _part_vertices(mesh)
    names = list(verts)
    if len(names) < 2:
        raise MeshError(f"{mesh.name}: axes='parts': expected a mesh of several parts, found {len(names)}")
    points = {n: mesh.positions[verts[n]].astype(np.float64) for n in names}
    axes = {n: _axis_of(points[n], f"{mesh.name}: part {n}", frame) for n in names}
    ends = {n: tuple(np.asarray(e, dtype=np.float64) for e in _segment(axes[n])) for n in names}
    across = [i for i in range(3) if i != up]
    height = {n: float(np.ptp(points[n][:, up])) for n in names}
    width = {n: float(np.ptp(points[n][:, across], axis=0).max()) for n in names}
    ground = [n for n in names if height[n] < GROUND_FLATNESS * width[n]]
    candidates = [n for n in names if n not in ground] or names
    # ties go by where a part is (its lowest point, its centre), never by its place in the file
    place = {n: (float(points[n][:, up].min()), *np.round(points[n].mean(axis=0), 9).tolist(), len(points[n]))
             for n in names}
    root = min(candidates, key=lambda n: place[n])
    def to_segment(pts, q) -> np.ndarray:  # each point's distance from q's axis segment
        a0, a1 = ends[q]
        ab = a1 - a0
        t = np.clip((pts - a0) @ ab / max(float(ab @ ab), 1e-300), 0.0, 1.0)
        return np.linalg.norm(pts - (a0 + t[:, None] * ab), axis=1)

    # a part's thickness about its axis (a lower quantile: a tuft at a branch's tip does not make it thick)
    radius = {q: float(np.percentile(to_segment(points[q], q), 25)) for q in names}
    seen: dict = {}

    def contact(n, q) -> tuple[float, float]:
        """How far n is outside q (0: it touches, crosses or enters q: a vertex of n within q's radius of
        q's axis, or n's axis segment within q's radius of q's), and how far the two axes are apart."""
        if (n, q) not in seen:
            vertex_gap = float(to_segment(points[n], q).min()) - radius[q]  # a vertex of n on or in q
            axis_gap = _segment_distance(ends[n], ends[q])  # n's axis through q's (coarse parts: few vertices)
            seen[n, q] = (max(min(vertex_gap, axis_gap - radius[q]), 0.0), axis_gap)
        return seen[n, q]

    order, parents, depth, gaps = [root], [-1], {root: 0}, {}
    while len(order) < len(names):
        best = None
        for n in names:
            if n in order or (n in ground and len(order) < len(names) - len(ground)):
                continue  # ground-like parts last: nothing should grow from the water
            length = max(axes[n].length, 1e-12)
            gaps_to = {q: contact(n, q) for q in order}
            dist = {q: g[0] for q, g in gaps_to.items()}
            near = min(dist.values())
            q = min((q for q in order if dist[q] <= near + TIE * length), key=lambda q: (depth[q], gaps_to[q][1]))
            key = (dist[q] / length, place[n])
            if best is None or key < best[0]:
                best = (key, n, q, dist[q])
        _, n, q, d = best
        order.append(n)
        parents.append(order.index(q))
        depth[n] = depth[q] + 1
        gaps[n] = (q, d)
    doubtful = [f"{n!r} -> {q!r} ({d:.3g} outside it, {d / max(axes[n].length, 1e-12):.0%} of its length)"
                for n, (q, d) in gaps.items() if n not in ground and d > DOUBTFUL_GAP * axes[n].length]
    if ground:
        warnings.warn(f"{mesh.name}: axes='parts': {brief_names(ground)} look like ground or water "
                      "(flat and wide), not a tree's part; leave them out with parts= / --parts", AssetWarning,
                      stacklevel=3)
    if doubtful:
        warnings.warn(f"{mesh.name}: axes='parts': doubtful attachments (the part neither crosses nor touches its "
                      f"parent): {'; '.join(doubtful)}; name the hierarchy in an axes file if it is wrong",
                      AssetWarning, stacklevel=3)
    va = np.full(mesh.vertex_count, -1, dtype=np.int32)
    for i, part in reversed(list(enumerate(order))):
        va[verts[part]] = i
    va[va < 0] = 0
    return tree_from_vertices(mesh, va, parents, frames=[frame] * len(order), names=order)

"""Axes from the model's own shape: a curve skeleton cut into a hierarchy of axes (``axes="skeleton"``).

A model bends at every branch only if it has an axis per branch.  A tree from an asset pack has its
wood as ONE piece (trunk, limbs and branches welded together) and its crown as a few blobs; this
module finds the branches from the shape itself (``docs/method.md``, "Axes from the shape"):

1. **Pieces.** The mesh is welded by position (vertices split for UVs or flat normals become one)
   and cut into connected pieces.  The trunk's piece is the one at least ``min_branch`` of the
   model's size that starts lowest along ``up`` (what grows from the ground, as ``axes="parts"``
   finds the trunk; never flat ground).  Another piece is a *limb* when it spreads at least
   :data:`ELONGATION` times as far along its main direction as across (a frond, a separate
   branch) and its skeleton's longest path is at least :data:`LIMB_RATIO` times the median
   distance of its vertices from it; every other piece (a crown blob, a leaf card, a bark mark, a
   pine's tier of needles, a willow's curtain) is *carried*.
2. **Skeleton.** Each limb gets a curve skeleton: ``skeletor.skeletonize.by_wavefront`` (rings of
   a wave spreading over the surface from its ends, each ring's centre a node), the piece's edges
   split first to at most its size over :data:`EDGE_STEPS` (a low-poly trunk of two rings has no
   rings to find), then simplified to at most :data:`SKELETON_TRIANGLES` triangles.
3. **Chains.** The trunk's skeleton starts at its lowest end.  Every fork continues into the child
   whose subtree reaches furthest (the trunk runs on into its longest limb) and starts a new chain
   for each other child.  Every other limb piece, nearest first, hangs at the end nearest what is
   made on the shallowest chain its ends come about as near as the nearest (within
   :data:`~axialdeform.core.axes.DOUBTFUL_GAP` of its length, measured to the chains' surfaces: a
   frond on the trunk, not on the frond it crosses).  A chain's first points still inside its
   parent are replaced by their foot on the parent's chain: it starts where it leaves its parent.
4. **Pruning.** A chain whose tip stands less than ``min_branch`` times the trunk's chain away from
   its parent's chain (less the parent's radius where it leaves it) is no branch -- a spur, or a
   twin running beside its parent (a leaf's two faces) --: its vertices go to the chains near
   them.  At most ``max_axes`` chains stay, the longest; a chain holding fewer than
   :data:`MIN_VERTICES` vertices goes too.
5. **Binding.** Each vertex of a limb goes to the nearest chain of its own piece (the distance to
   the chain's polyline), except that a branch holds nothing behind where it leaves its parent
   and, within :data:`CROTCH` parent radii of there, nothing further than :data:`BAND` of its own
   radii (the crotch of a fork stays the trunk's); a carried piece goes whole to the branch with
   the most surface within :data:`TOUCHING` of the piece's size of it (else the one its vertices
   come nearest, the one nearer the root among those about as near).
   Vertices at one position get one axis, so split vertices move together.
6. **Axes.** Each chain is one axis of the hierarchy (``core.axes``): its frame's ``e_a`` runs from
   where it leaves its parent to its tip, ``e_u`` the model's up made perpendicular to it; ``lo``
   and ``L`` from its limb's vertices only (a carried crown rides on it, clamped beyond its ends,
   without lengthening it); its anchor the point where it leaves its parent.  Random variation
   and the wind clamp a child's bend there (value and slope zero), so the surface through a joint
   stays whole: the boundary between two axes' vertices lies where the child's own bend vanishes
   to second order.

Rules 1-5 give the branches (:func:`skeleton_branches`, what an axes file of ``[[branch]]`` tables
holds); rules 5-6 make the tree from them (:func:`tree_from_branches`).  Pure numpy, scipy and trimesh
here; ``skeletor`` (it brings pandas and igraph) is imported only when a skeleton is asked for.
"""

from __future__ import annotations

import hashlib
import warnings
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import fast_simplification
import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from .arrays import position_ids
from .axes import DOUBTFUL_GAP, MAX_AXES, TIE, AxisTree
from .axis import ControlAxis
from .blend import blend_pieces
from .errors import MeshError

__all__ = ["skeleton_tree", "skeleton_branches", "tree_from_branches", "RULES_DIGEST", "MIN_BRANCH", "LIMB_RATIO",
           "SKELETON_TRIANGLES", "SKELETON_VERSION"]

#: the default shortest branch, a fraction of the trunk's chain (the root piece's first chain)
MIN_BRANCH = 0.1
#: a piece is a limb (it gets a skeleton and axes) when its skeleton's longest path is at least this many
#: times the median distance of its vertices from the skeleton; a blob, a leaf card or a disc is carried whole
LIMB_RATIO = 3.0
#: a piece other than the trunk's is a limb only if its longest spread is at least this many times its second
#: (a frond, a separate branch); a crown blob, a pine's tier or a willow's curtain is not
ELONGATION = 2.0
#: before its skeleton, a piece's edges are split to at most its size over this many
EDGE_STEPS = 40
#: a piece with more triangles (after the split) is simplified to this many before its skeleton is computed
SKELETON_TRIANGLES = 50000
#: bumped whenever a rule here changes what a mesh gets (a cached tree of another version is not used); the
#: cache key also holds a hash of this file and of skeletor's version, so no edit here reads a stale tree
SKELETON_VERSION = 1
#: near where it leaves its parent (within :data:`CROTCH` times the parent's radius), a branch holds only the
#: points within this many times its own radius of its chain (the surface in a fork's crotch stays the trunk's)
BAND = 1.5
CROTCH = 3.0
#: a carried piece rides the branch with the most surface within this fraction of the piece's size of it
TOUCHING = 0.05
#: a chain binding fewer vertices than this goes to its parent
MIN_VERTICES = 8


@dataclass
class Chain:
    """One branch of the skeleton: ``points`` (m, 3) from where it leaves its parent to its tip."""

    points: np.ndarray
    parent: int  # -1: a root
    piece: int
    depth: int = 0

    @property
    def length(self) -> float:
        return _path_length(self.points)


def weld(positions: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices at one position made one (:func:`~axialdeform.core.arrays.position_ids`): ``(points (w, 3)
    float64, faces (f, 3) int64 of them without degenerate ones, inverse (v,) int64: each vertex's welded
    point)``."""
    inverse = position_ids(positions)
    points = np.empty((int(inverse.max(initial=-1)) + 1, 3), dtype=np.float64)
    points[inverse] = positions
    welded = inverse[np.asarray(faces, dtype=np.int64)]
    ok = (welded[:, 0] != welded[:, 1]) & (welded[:, 1] != welded[:, 2]) & (welded[:, 0] != welded[:, 2])
    return points, welded[ok], inverse


def pieces(count: int, faces: np.ndarray) -> np.ndarray:
    """(count,) int: the connected piece of each welded point (points no triangle uses: their own)."""
    a, b = np.concatenate([faces[:, 0], faces[:, 1], faces[:, 2]]), np.concatenate([faces[:, 1], faces[:, 2], faces[:, 0]])
    graph = coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(count, count))
    return connected_components(graph, directed=False)[1]


def curve_skeleton(points: np.ndarray, faces: np.ndarray, name: str = "<mesh>") -> tuple[np.ndarray, np.ndarray]:
    """The curve skeleton of one piece: ``(nodes (n, 3) float64, edges (e, 2) int64)`` (skeletor's
    wavefront skeleton of the piece, its edges split to its size over :data:`EDGE_STEPS` first and,
    above :data:`SKELETON_TRIANGLES` triangles, simplified)."""
    used = np.unique(faces)
    local = np.searchsorted(used, faces)
    pts = points[used]
    # long thin triangles (a low-poly trunk of two rings) leave the edge graph too coarse to find the
    # branches: edges are split to a fraction of the piece's size first (trimesh), then simplified back
    step = float(np.ptp(pts, axis=0).max()) / EDGE_STEPS
    if step > 0:
        pts, local = trimesh.remesh.subdivide_to_size(pts, local, max_edge=step, max_iter=8)
    if len(local) > SKELETON_TRIANGLES:
        pts, local = fast_simplification.simplify(pts.astype(np.float32), local.astype(np.int32),
                                                  target_count=SKELETON_TRIANGLES)
        pts, local = np.asarray(pts, dtype=np.float64), np.asarray(local, dtype=np.int64)
    try:
        import skeletor  # pandas, igraph and more: only when a skeleton is asked for
    except ImportError as exc:  # pragma: no cover - a dependency
        raise MeshError(f"{name}: axes='skeleton' needs skeletor (pip install skeletor): {exc}") from None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found = skeletor.skeletonize.by_wavefront(trimesh.Trimesh(pts, local, process=False), waves=1, step_size=1,
                                                      progress=False)
        nodes = np.asarray(found.vertices, dtype=np.float64)
        edges = np.asarray(found.edges, dtype=np.int64).reshape(-1, 2)
    except Exception as exc:  # noqa: BLE001  skeletor's own failures, in words
        raise MeshError(f"{name}: axes='skeleton': no curve skeleton for a piece of {len(faces)} triangles "
                        f"({type(exc).__name__}: {str(exc)[:120]})") from None
    edges = edges[edges[:, 0] != edges[:, 1]]
    if not len(nodes):
        return pts.mean(axis=0, keepdims=True), np.zeros((0, 2), dtype=np.int64)
    return nodes, edges


def _tree_of(nodes: np.ndarray, edges: np.ndarray, root: int) -> tuple[np.ndarray, np.ndarray]:
    """The skeleton as a tree from ``root``: ``(order (n,) breadth first, parent (n,) -1 at the root)`` over
    the shortest spanning tree of its edges (a skeleton with a loop -- a handle -- is cut where it is longest)."""
    n = len(nodes)
    w = np.linalg.norm(nodes[edges[:, 0]] - nodes[edges[:, 1]], axis=1) + 1e-12
    mst = minimum_spanning_tree(coo_matrix((w, (edges[:, 0], edges[:, 1])), shape=(n, n)))
    order, parent = breadth_first_order(mst, root, directed=False)
    parent = np.where(parent < 0, -1, parent)
    return order, parent


def _chains_of(nodes, edges, root: int, piece: int, parent_chain: int, start, depth: int, base: int = 0) -> list[Chain]:
    """A piece's skeleton cut into chains from ``root``: at each fork the chain goes on into the child
    whose subtree reaches furthest; each other child starts a chain.  ``base``: the index the first chain will
    have in the caller's list (the parents of the others count from it)."""
    order, parent = _tree_of(nodes, edges, root)
    n = len(nodes)
    step = np.zeros(n)
    has = parent >= 0
    step[has] = np.linalg.norm(nodes[has] - nodes[parent[has]], axis=1)
    reach = np.zeros(n)  # the longest way from a node down to a tip of its subtree
    for v in order[::-1]:  # the skeleton's nodes (a few hundred), not the mesh's vertices
        p = parent[v]
        if p >= 0:
            reach[p] = max(reach[p], reach[v] + step[v])
    children: dict = {}
    for v in order[1:]:
        children.setdefault(int(parent[v]), []).append(int(v))
    chains: list[Chain] = []
    todo = [(root, parent_chain, None if start is None else np.asarray(start, dtype=np.float64), depth)]
    while todo:
        v, up_chain, first, level = todo.pop(0)
        path = [first] if first is not None and not np.allclose(first, nodes[v]) else []
        me = base + len(chains)
        while True:
            path.append(nodes[v])
            kids = sorted(children.get(v, []), key=lambda c: (-(reach[c] + step[c]), c))
            if not kids:
                break
            for other in kids[1:]:
                todo.append((other, me, nodes[v], level + 1))
            v = kids[0]
        chains.append(Chain(np.asarray(path), up_chain, piece, level))
    return chains


def _distance_to_chains(points: np.ndarray, chains: list[Chain], which) -> np.ndarray:
    """(p, len(which)): each point's distance from each chain's polyline."""
    out = np.full((len(points), len(which)), np.inf)
    for j, c in enumerate(which):
        seg = chains[c].points
        if len(seg) == 1:
            out[:, j] = np.linalg.norm(points - seg[0], axis=1)
            continue
        a, b = seg[:-1], seg[1:]
        ab = b - a
        den = np.maximum((ab * ab).sum(axis=1), 1e-300)
        for lo in range(0, len(points), 4096):  # a few MB at a time
            p = points[lo:lo + 4096, None, :]
            t = np.clip(((p - a) * ab).sum(axis=2) / den, 0.0, 1.0)
            d = np.linalg.norm(p - (a + t[..., None] * ab), axis=2)
            out[lo:lo + 4096, j] = d.min(axis=1)
    return out


def _hang(points: np.ndarray, chains: list[Chain], candidates, size: float) -> int:
    """The chain a piece sits on: the one its points come nearest, the shallower among those within
    :data:`~axialdeform.core.axes.TIE` of ``size`` of the nearest."""
    d = _distance_to_chains(points, chains, candidates).min(axis=0)
    near = d.min() + TIE * size
    return min((c for c, dc in zip(candidates, d) if dc <= near), key=lambda c: (chains[c].depth, d[candidates.index(c)], c))


def _frame(points: np.ndarray, up: int) -> np.ndarray:
    """Rows ``e_a`` (first point to last), ``e_u`` (the model's up made perpendicular), ``e_v = e_a × e_u``."""
    e_a = points[-1] - points[0]
    if not np.linalg.norm(e_a) > 0:
        e_a = np.eye(3)[up]
    e_a = e_a / np.linalg.norm(e_a)
    for guess in (np.eye(3)[up], np.eye(3)[(up + 1) % 3]):
        e_u = guess - (guess @ e_a) * e_a
        if np.linalg.norm(e_u) > 1e-3:
            break
    e_u = e_u / np.linalg.norm(e_u)
    e_v = np.cross(e_a, e_u)
    frame = np.vstack([e_a, e_u, e_v / np.linalg.norm(e_v)])
    u, _, vt = np.linalg.svd(frame)  # exactly orthonormal
    return u @ vt


def skeleton_branches(mesh, *, min_branch: float = MIN_BRANCH, up: int = 1, max_axes: int = MAX_AXES) -> list[dict]:
    """The branches of ``mesh``'s skeleton (the module's rules 1-5): ``[{"name", "parent", "points"}]``, the
    trunk first (no parent), a parent before its children, ``points`` (m, 3) float64 from where a branch
    leaves its parent to its tip -- what an axes file of branches holds (:func:`tree_from_branches`).

    Parameters
    ----------
    mesh : BaseMesh
    min_branch : float
        The shortest branch, a fraction of the trunk's chain (default :data:`MIN_BRANCH`).
    up : int
        The model's up coordinate (1: y, glTF's up).
    max_axes : int
        At most this many axes (1 to :data:`~axialdeform.core.axes.MAX_AXES`).

    Returns
    -------
    list of dict
        Names ``trunk``, ``branch1``, ...
    """
    if not (isinstance(min_branch, (int, float)) and not isinstance(min_branch, bool) and 0 < min_branch < 1):
        raise MeshError(f"{mesh.name}: axes='skeleton': min_branch: expected a fraction of the trunk in (0, 1), "
                        f"found {min_branch!r:.40}")
    if not (isinstance(max_axes, int) and 1 <= max_axes <= MAX_AXES):
        raise MeshError(f"{mesh.name}: axes='skeleton': max_axes: expected 1 to {MAX_AXES}, found {max_axes!r:.40}")
    points, faces, _ = weld(mesh.positions, mesh.faces)
    label = pieces(len(points), faces)
    face_piece = label[faces[:, 0]]
    size = float(np.ptp(points, axis=0).max()) or 1.0
    ids = np.unique(face_piece)
    across = [i for i in range(3) if i != up]
    candidates = []
    for p in ids:  # the pieces (tens), not the vertices
        pts = points[label == p]
        extent = np.ptp(pts, axis=0)
        if extent.max() >= min_branch * size and np.count_nonzero(face_piece == p) >= 8:
            candidates.append(p)
    if not candidates:  # nothing long enough to be a branch: the largest piece is the one axis
        candidates = [int(np.argmax(np.bincount(face_piece)))]
    grounded = [p for p in candidates if np.ptp(points[label == p][:, up]) >= 0.2 * np.ptp(points[label == p][:, across],
                                                                                            axis=0).max()] or candidates
    # the trunk's piece: the one that starts lowest (what grows from the ground), never flat ground or water
    root = min(grounded, key=lambda p: (float(points[label == p][:, up].min()), float(points[label == p].sum())))
    skeletons, limbs = {root: curve_skeleton(points, faces[face_piece == root], mesh.name)}, [root]
    for p in candidates:
        if p != root and _elongated(points[label == p]):
            nodes, edges = skeletons[p] = curve_skeleton(points, faces[face_piece == p], mesh.name)
            far = nodes[_longest_path(nodes, edges)]
            thick = float(np.median(_distance_to_chains(points[label == p], [Chain(far, -1, p)], [0])))
            if _path_length(far) >= LIMB_RATIO * max(thick, 1e-12 * size):
                limbs.append(p)
    chains: list[Chain] = []
    nodes, edges = skeletons[root]
    ends = _ends(nodes, edges)
    start = min(ends, key=lambda v: (nodes[v, up], v))
    chains += _chains_of(nodes, edges, start, root, -1, None, 0)
    rest = [p for p in limbs if p != root]
    # each waiting piece's ends against each chain's surface: a (ends, chains) table that grows by the columns of
    # each piece hung (every surface point is compared with every end once, not once a round)
    gaps = {p: (_ends(*skeletons[p]), np.zeros((len(_ends(*skeletons[p])), 0))) for p in rest}

    def add_surface(p, first):
        mine = points[label == p]
        own = list(range(first, len(chains)))
        owner = np.asarray(own)[np.argmin(_distance_to_chains(mine, chains, own), axis=1)]
        for q in rest:
            ends, gap = gaps[q]
            d = np.linalg.norm(skeletons[q][0][ends][:, None, :] - mine[None], axis=2)
            cols = np.full((len(ends), len(own)), np.inf)
            for j, c in enumerate(own):
                if (owner == c).any():
                    cols[:, j] = d[:, owner == c].min(axis=1)
            gaps[q] = (ends, np.hstack([gap, cols]))

    add_surface(root, 0)
    while rest:  # nearest first: a piece hangs on what is already made
        p = min(rest, key=lambda q: (float(gaps[q][1].min()), float(skeletons[q][0].sum())))
        nodes, edges = skeletons[p]
        ends, gap = gaps[p]
        length = _path_length(nodes[_longest_path(nodes, edges)]) or size
        # it grows from the shallowest chain its ends come about as near as the nearest: a frond from the trunk,
        # not from the frond it crosses
        near = np.argwhere(gap <= gap.min() + DOUBTFUL_GAP * length)
        e, on = min(((int(i), int(c)) for i, c in near), key=lambda ic: (chains[ic[1]].depth, gap[ic], ic[1], ic[0]))
        end = ends[e]
        first = len(chains)
        chains += _chains_of(nodes, edges, end, p, on, _foot(nodes[end], chains[on].points), chains[on].depth + 1,
                             len(chains))
        rest.remove(p)
        add_surface(p, first)
    _leave(chains, points, label)
    keep = _prune(chains, points, label, min_branch, max_axes)
    limb_point = np.isin(label, limbs)
    while True:  # a chain that holds (almost) no vertex of its own is no axis: its vertices go to the chains near them
        welded_axis = _bind(points, label, chains, keep, limbs)
        counts = np.bincount(welded_axis[limb_point], minlength=len(keep))
        empty = {keep[k] for k in range(1, len(keep)) if counts[k] < MIN_VERTICES}
        if not empty:
            break
        keep = [c for c in keep if c not in empty]
    names = ["trunk"] + [f"branch{i}" for i in range(1, len(keep))]
    return [{"name": names[i], "parent": None if i == 0 else names[keep.index(_kept_parent(chains, c, keep))],
             "points": chains[c].points.copy()} for i, c in enumerate(keep)]


def skeleton_tree(mesh, *, min_branch: float = MIN_BRANCH, up: int = 1, max_axes: int = MAX_AXES,
                  blend: bool = True) -> AxisTree:
    """The axes of ``mesh`` from its own shape: :func:`tree_from_branches` of :func:`skeleton_branches`
    (the parameters are theirs).  Names ``trunk``, ``branch1``, ...; ``describe()`` says the hierarchy."""
    return tree_from_branches(mesh, skeleton_branches(mesh, min_branch=min_branch, up=up, max_axes=max_axes), up=up,
                              blend=blend)


def tree_from_branches(mesh, branches, up: int = 1, blend: bool = True) -> AxisTree:
    """The axes of ``mesh`` from its branches (rule 6 on rule 5's binding): ``branches`` as
    :func:`skeleton_branches` gives them or an axes file of ``[[branch]]`` tables holds them (edited by
    hand: a branch moved or left out).  Each branch belongs to the piece its points lie nearest.  A piece
    holding none is carried: with ``blend`` (the default) each of its points moves with the two branches
    nearest it, weighed by nearness, and a limb piece of its own moves with what it rests on where it
    touches it (:func:`~axialdeform.core.blend.blend_pieces`, ``AxisTree.blend``); without, the piece rides
    whole the branch it sits on."""
    points, faces, inverse = weld(mesh.positions, mesh.faces)
    label = pieces(len(points), faces)
    chains = _check_branches(mesh, branches, points, label)
    keep = list(range(len(chains)))
    limbs = sorted({c.piece for c in chains})
    limb_point = np.isin(label, limbs)
    welded_axis = _bind(points, label, chains, keep, limbs)
    mixed = blend_pieces(points, faces, label, welded_axis, keep, limbs, chains) if blend else None
    names = tuple(str(b["name"]) for b in branches)
    parents = tuple(c.parent for c in chains)
    axes, anchors = [], [0.0]
    for i, c in enumerate(chains):  # each axis's box from its limb's points only: a carried crown rides on it
        own = points[limb_point & (welded_axis == i)]
        if not len(own):
            raise MeshError(f"{mesh.name}: axes: branch {names[i]!r} holds no vertex; expected every branch to run "
                            "inside the mesh, nearest some of its vertices")
        axis = ControlAxis.from_positions(own, name=f"{mesh.name}: axis {names[i]}", frame=_frame(c.points, up))
        axes.append(axis)
        if i:
            at = float(np.asarray(axis.matrix)[0] @ c.points[0])
            anchors.append(float(np.clip((at - axis.lo) / axis.length, 0.0, 1.0)))
    return AxisTree(tuple(axes), parents, welded_axis[inverse].astype(np.int32), names, tuple(anchors),
                    None if mixed is None else mixed[inverse])


def _check_branches(mesh, branches, points, label) -> list[Chain]:
    """``branches`` as chains, each in the piece its points lie nearest; a branch list that is not one is a
    :class:`MeshError` naming the branch and what was expected."""
    if isinstance(branches, (str, bytes)) or not hasattr(branches, "__len__") or not 1 <= len(branches) <= MAX_AXES:
        raise MeshError(f"{mesh.name}: axes: expected 1 to {MAX_AXES} branches, found {branches!r:.80}")
    nearest = cKDTree(points)
    chains, index = [], {}
    for i, b in enumerate(branches):
        where = f"{mesh.name}: axes: branch {i + 1}"
        if not isinstance(b, dict) or not {"name", "points"} <= set(b) or set(b) - {"name", "parent", "points"}:
            raise MeshError(f"{where}: expected name, points and (except the first) parent, found {b!r:.80}")
        name, parent = b["name"], b.get("parent")
        if not isinstance(name, str) or not name or name in index:
            raise MeshError(f"{where}: name: expected a name no other branch has, found {name!r:.40}")
        if (parent is None) != (i == 0) or (parent is not None and parent not in index):
            raise MeshError(f"{where} ({name}): parent: expected " + ("none for the trunk (the first branch)" if i == 0
                            else f"the name of an earlier branch, found {parent!r:.40}"))
        try:
            pts = np.asarray(b["points"], dtype=np.float64)
        except (TypeError, ValueError):
            pts = np.zeros((0, 0))
        if pts.ndim != 2 or pts.shape[1:] != (3,) or len(pts) < 2 or not np.isfinite(pts).all():
            raise MeshError(f"{where} ({name}): points: expected two or more points of three finite numbers, "
                            f"found {b['points']!r:.80}")
        piece = int(np.bincount(label[nearest.query(pts)[1]]).argmax())  # where most of its points lie nearest
        up_chain = -1 if parent is None else index[parent]
        index[name] = len(chains)
        chains.append(Chain(pts, up_chain, piece, 0 if up_chain < 0 else chains[up_chain].depth + 1))
    return chains


def _radius(chain: Chain, surface: np.ndarray) -> float:
    """A chain's thickness: the median distance of its piece's surface points nearest it (a limb's radius)."""
    d = _distance_to_chains(surface, [chain], [0])[:, 0]
    return float(np.median(np.sort(d)[:max(8, len(d) // 8)]))


def _elongated(points: np.ndarray) -> bool:
    """True when the points spread at least :data:`ELONGATION` times as far along their main direction as
    across it (singular values of the centred points)."""
    sv = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    return len(sv) > 1 and sv[0] >= ELONGATION * sv[1]


def _ends(nodes, edges) -> list[int]:
    if not len(edges):
        return [0]
    deg = np.bincount(edges.ravel(), minlength=len(nodes))
    ends = [int(v) for v in np.flatnonzero(deg == 1)]
    return ends or [int(np.argmin(deg))]


def _path_length(points) -> float:
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum()) if len(points) > 1 else 0.0


def _longest_path(nodes, edges) -> np.ndarray:
    """The node indices of the skeleton's longest path (twice the furthest node)."""
    if not len(edges):
        return np.array([0])
    far = 0
    for _ in range(2):
        order, parent = _tree_of(nodes, edges, far)
        dist = np.zeros(len(nodes))
        for v in order[1:]:
            dist[v] = dist[parent[v]] + np.linalg.norm(nodes[v] - nodes[parent[v]])
        far = int(np.argmax(dist))
    path = [far]
    while parent[path[-1]] >= 0:
        path.append(int(parent[path[-1]]))
    return np.array(path)


def _foot(point, polyline) -> np.ndarray:
    """The point of ``polyline`` nearest ``point``."""
    if len(polyline) == 1:
        return polyline[0].copy()
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    t = np.clip(((point - a) * ab).sum(axis=1) / np.maximum((ab * ab).sum(axis=1), 1e-300), 0.0, 1.0)
    q = a + t[:, None] * ab
    return q[int(np.argmin(np.linalg.norm(q - point, axis=1)))]


def _leave(chains, points, label) -> None:
    """Each child chain starts where it leaves its parent: its first points still inside the parent (nearer
    the parent's chain than the parent's radius: a skeleton's fork sits a little up or down the trunk) are
    cut off and replaced by their foot on the parent's chain."""
    radii: dict = {}
    for c in chains:
        if c.parent < 0 or len(c.points) < 2:
            continue
        parent = chains[c.parent]
        if c.parent not in radii:
            radii[c.parent] = _radius(parent, points[label == parent.piece])
        d = _distance_to_chains(c.points, chains, [c.parent])[:, 0]
        outside = np.flatnonzero(d > radii[c.parent])
        if not len(outside):
            continue
        first = int(outside[0])
        c.points = np.vstack([_foot(c.points[first], parent.points)[None], c.points[first:]])


def _kept_parent(chains, c, keep) -> int:
    """The nearest ancestor of chain ``c`` that is an axis."""
    p = chains[c].parent
    while p >= 0 and p not in keep:
        p = chains[p].parent
    return max(p, 0)


def _prune(chains, points, label, min_branch, max_axes) -> list[int]:
    """The chains that are branches -- reaching at least ``min_branch`` of the trunk (the first chain) away
    from their parent's chain, less the parent's radius where they leave it (a piece's first chain always is
    one) -- at most ``max_axes`` of them, the longest, parents first."""
    shortest = min_branch * chains[0].length
    keep = []
    for i, c in enumerate(chains):  # a parent comes before its children
        if c.parent >= 0 and c.piece == chains[c.parent].piece:
            if c.parent not in keep:
                continue
            surface = points[label == c.piece]
            radius = float(np.linalg.norm(surface - c.points[0], axis=1).min())
            reach = float(_distance_to_chains(c.points, chains, [c.parent]).max())
            if reach - radius < shortest:  # a spur, or a twin running beside its parent (a leaf's two faces)
                continue
        keep.append(i)
    if len(keep) > max_axes:
        ranked = sorted(keep, key=lambda i: (-chains[i].length, i))[:max_axes]
        keep = [i for i in keep if i in ranked]
        keep = [i for i in keep if _line_in(chains, i, keep)]
    return keep


def _line_in(chains, i, keep) -> bool:
    """True when every ancestor of chain ``i`` in its own piece is in ``keep``."""
    p = chains[i].parent
    while p >= 0 and chains[p].piece == chains[i].piece:
        if p not in keep:
            return False
        p = chains[p].parent
    return True


def _bind(points, label, chains, keep, limbs) -> np.ndarray:
    """(w,) int: each welded point's axis (an index into ``keep``): a limb's point the nearest axis of its
    own piece, a carried piece whole the axis it sits on."""
    out = np.zeros(len(points), dtype=np.int64)
    index = {c: i for i, c in enumerate(keep)}
    for p in np.unique(label):
        mine = np.flatnonzero(label == p)
        own = [c for c in keep if chains[c].piece == p] if p in limbs else []
        if own:
            d = _distance_to_chains(points[mine], chains, own)
            near = d.copy()
            for j, c in enumerate(own):  # a branch holds nothing behind where it leaves its parent (the boundary
                ch = chains[c]           # lies at its anchor, where its own bend vanishes), nor what lies further
                if ch.parent >= 0 and chains[ch.parent].piece == p and len(ch.points) > 1:  # than twice its radius
                    behind = (points[mine] - ch.points[0]) @ (ch.points[1] - ch.points[0]) <= 0
                    crotch = np.linalg.norm(points[mine] - ch.points[0], axis=1) < CROTCH * _radius(chains[ch.parent], points[mine])
                    near[behind | (crotch & (d[:, j] > BAND * _radius(ch, points[mine]))), j] = np.inf
            pick = np.where(np.isfinite(near).any(axis=1), np.argmin(near, axis=1), np.argmin(d, axis=1))
            out[mine] = np.asarray([index[c] for c in own])[pick]
    limb = np.isin(label, limbs)
    for p in np.unique(label):  # then each carried piece, whole, on the branch whose surface touches it most
        mine = np.flatnonzero(label == p)
        if p in limbs and any(chains[c].piece == p for c in keep):
            continue
        extent = max(float(np.ptp(points[mine], axis=0).max()), 1e-12)
        near = cKDTree(points[mine]).query(points[limb], distance_upper_bound=TOUCHING * extent)[0]
        touching = np.bincount(out[limb][np.isfinite(near)], minlength=len(keep))
        out[mine] = int(np.argmax(touching)) if touching.any() else index[_hang(points[mine], chains, keep, extent)]
    return out


def _rules_hash() -> str:
    try:
        skeletor_version = version("skeletor")
    except PackageNotFoundError:  # pragma: no cover - a dependency
        skeletor_version = "?"
    rules = Path(__file__).read_bytes() + Path(__file__).with_name("blend.py").read_bytes()
    return hashlib.sha256(rules + skeletor_version.encode()).hexdigest()[:8]


#: the rules' digest: a tree cached by an earlier version of these rules is not read
RULES_DIGEST = _rules_hash()

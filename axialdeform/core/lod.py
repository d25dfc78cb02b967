"""Levels of detail of a base mesh (pure numpy + fast-simplification + trimesh).

Every level is a quadric simplification (``fast_simplification``, the
maintained binding of Fast-Quadric-Mesh-Simplification) of the base mesh,
PART BY PART: each part (:attr:`BaseMesh.parts`) is simplified on its own and
keeps its material, so a level has the same parts, in the same order, as the
base mesh.  A part with fewer than :data:`MIN_LOD_TRIANGLES` triangles is not
simplified: every level carries it at full resolution.

The per-vertex attributes (normals, UVs, vertex colours, tangents) are
carried to the simplified vertices with the collapse history
(``simplify(..., return_collapses=True)``; :func:`collapse_mapping` reads
from it which simplified vertex every original vertex was collapsed into --
``replay_simplification``'s ``indice_mapping``, without the replay, whose
working arrays fast-simplification keeps for the life of the process): a simplified vertex is
projected to the closest point of the original triangles around the vertices
collapsed into it, and takes the barycentric interpolation of their
attributes there (normals renormalised; tangents made orthogonal to the
normal, unit, with the handedness of the interpolated ``w``).  So a flat
card with an affine texture map keeps exactly that map at every level, and
a colour is never averaged across the surface.  UV seams: the base mesh has
its vertices split at a seam (one copy per side), so the simplifier sees a
seam as an open border of the part; a collapse never joins the two sides
(they share no edge), so each simplified vertex takes its UV from one side
only -- no UV is ever averaged across a seam.  Both sides are simplified
independently, so the seam may open by up to twice the level's geometric
error (measured below; the screen-space rule keeps it under 2 x ``lod_error``
pixels); docs/culling.md says why the seams are not welded.

All levels are deformed with the BASE mesh's control axis (``mesh.axis``:
axis, ``lo``, ``L`` computed from the full mesh), so an instance bends the
same way at every level.  Each level carries its geometric error in model
units: the symmetric Hausdorff distance between it and the full mesh,
measured from the vertices of each to the surface of the other, both sampled
densely (vertices plus 2048 surface points each; the nearest sampled point
stands in for the nearest surface point, which can only over-estimate the
error by the sampling spacing).  The renderer picks a level per instance
from that error projected to pixels (docs/culling.md).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .errors import ParamError
from .material import Part
from .mesh import area_weighted_normals, unique_edges
from .surface import face_areas, sample_faces

__all__ = [
    "LodLevel", "build_lod_levels", "collapse_mapping", "spatial_chunks", "LOD_CHUNK_TRIANGLES", "LOD_REDUCTIONS",
    "MIN_LOD_TRIANGLES", "check_lod_error",
]

#: fraction of the triangles removed for levels 1, 2, 3 (level 0 is the full mesh)
LOD_REDUCTIONS = (0.5, 0.8, 0.93)
#: a part with fewer triangles is not simplified (a mesh none of whose parts
#: has that many keeps one level, with a warning)
MIN_LOD_TRIANGLES = 48
#: a part of more triangles is simplified in spatial chunks of at most this many,
#: each on its own (fast-simplification keeps ~290 bytes a triangle of its largest
#: input for the life of the process: a 1 M-triangle part cost 290 MB at once)
LOD_CHUNK_TRIANGLES = 1 << 17
_SAMPLE = 2048
_PAIRS = 1 << 18  # (vertex, triangle) candidate pairs per closest-point chunk


@dataclass(frozen=True, eq=False)
class LodLevel:
    """One level of detail, drawn like a base mesh (same attribute names).

    positions : (n, 3) float32
    normals : (n, 3) float32 (unit)
    faces : (m, 3) uint32
    error : float -- geometric error in model units (0 for the full mesh)
    uvs : (n, 2) float32 or None; colors : (n, 4) float32 or None;
    tangents : (n, 4) float32 or None -- where the base mesh has them
    parts : tuple of Part -- the base mesh's parts, in its order, with the
        same materials, as ranges of this level's ``faces``
    """

    positions: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    error: float
    uvs: np.ndarray | None = None
    colors: np.ndarray | None = None
    tangents: np.ndarray | None = None
    parts: tuple = ()
    vertex_axis: np.ndarray | None = None  # several axes: each vertex's axis, or its code when blended (in_axis)

    @classmethod
    def of(cls, mesh) -> LodLevel:
        """Level 0: the base mesh itself (its arrays, not copies)."""
        tree = getattr(mesh, "tree", None)
        return cls(mesh.positions, mesh.normals, mesh.faces, 0.0, mesh.uvs, mesh.colors, mesh.tangents,
                   tuple(mesh.parts), None if tree is None else tree.vertex_axis if tree.blend is None else tree.vertex_code)

    @property
    def vertex_count(self) -> int:
        return len(self.positions)

    @cached_property
    def edges(self) -> np.ndarray:
        """(k, 2) uint32 unique undirected edges (for wireframe)."""
        return faces_edges(self.faces)

    def part_edges(self, indices) -> np.ndarray:
        """(k, 2) uint32 unique edges of the parts ``indices`` (positions in :attr:`parts`)."""
        return faces_edges(np.concatenate([self.faces[p.start:p.start + p.count]
                                           for p in (self.parts[i] for i in indices)]))


def faces_edges(faces: np.ndarray) -> np.ndarray:
    """(k, 2) uint32 unique undirected edges of ``faces : (m, 3) int``
    (:func:`axialdeform.core.mesh.unique_edges`)."""
    faces = np.asarray(faces)
    return unique_edges(faces, int(faces.max()) + 1 if faces.size else 0)


def check_lod_error(pixels) -> float:
    """The allowed screen-space error in pixels: a finite number > 0, else ParamError."""
    try:
        value = float(pixels)
    except (TypeError, ValueError):
        raise ParamError(f"lod_error: expected a number of pixels > 0, found {pixels!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise ParamError(f"lod_error: expected a number of pixels > 0, found {pixels!r}")
    return value


def _surface_points(positions: np.ndarray, faces: np.ndarray, count: int, seed: int) -> np.ndarray:
    """The vertices (n, 3) plus ``count`` points sampled on the triangles (area-
    uniform: :func:`~axialdeform.core.surface.sample_faces`, trimesh's
    ``sample_surface`` without its per-face arrays): (k, 3) float64."""

    positions = np.asarray(positions, dtype=np.float64)
    points, _ = sample_faces(positions, faces, np.cumsum(face_areas(positions, faces)), count,
                             np.random.default_rng(seed))
    cloud = np.vstack([positions, points])
    if len(cloud) > 2 * count:
        cloud = cloud[np.random.default_rng(seed).choice(len(cloud), 2 * count, replace=False)]
    return cloud


def _one_sided(points: np.ndarray, targets: np.ndarray) -> float:
    """Largest distance from a point of ``points`` (k, 3) to its nearest point of ``targets`` (j, 3)."""
    worst = 0.0
    t2 = np.einsum("ij,ij->i", targets, targets)
    for a in range(0, len(points), 512):
        p = points[a:a + 512]
        d2 = np.einsum("ij,ij->i", p, p)[:, None] - 2.0 * p @ targets.T + t2[None, :]
        worst = max(worst, float(np.sqrt(max(d2.min(axis=1).max(), 0.0))))
    return worst


def _unique_ints(values: np.ndarray) -> np.ndarray:
    """Sorted unique values of an int64 array (a sort: many times faster here
    than ``np.unique``'s hashing for millions of keys)."""
    values = np.sort(values)
    return values[np.r_[True, values[1:] != values[:-1]]] if len(values) else values


def _used_vertices(faces: np.ndarray, n: int) -> np.ndarray:
    """(k,) int64 sorted indices below ``n`` that ``faces`` uses."""
    return np.flatnonzero(np.bincount(faces.ravel(), minlength=n)).astype(np.int64)


def _attributes(mesh):
    """The per-vertex attributes carried to a level: name -> (n, k) float64 (normals first)."""
    out = {"normals": mesh.normals.astype(np.float64)}
    for key in ("uvs", "colors", "tangents"):
        value = getattr(mesh, key)
        if value is not None:
            out[key] = value.astype(np.float64)
    tree = getattr(mesh, "tree", None)
    if tree is not None and tree.blend is not None:  # blended vertices: the code of the nearest corner
        out["code"] = tree.vertex_code[:, None].astype(np.float64)
    elif tree is not None:  # several axes: each simplified vertex takes the axis of where it lies
        out["axis"] = tree.vertex_axis[:, None].astype(np.float64)
    return out


def _transfer(positions, faces, attrs, new_positions, mapping):
    """Attributes of the simplified vertices, by closest-point barycentric interpolation.

    positions : (v, 3) float64 and faces : (m, 3) int64 of the original part;
    attrs : name -> (v, k) float64; new_positions : (w, 3) float64;
    mapping : (v,) int64, the simplified vertex each original vertex went into
    (-1: none).  Each simplified vertex is projected onto the original
    triangles that touch a vertex collapsed into it (candidates: one pair per
    triangle corner, all pairs at once) and the nearest projection wins.
    """
    import trimesh

    m = len(faces)
    target = mapping[faces.ravel()]
    face = np.repeat(np.arange(m, dtype=np.int64), 3)
    ok = target >= 0
    key = _unique_ints(target[ok] * m + face[ok])  # unique (simplified vertex, original triangle) pairs
    del target, face, ok
    j, f = key // m, key % m
    del key
    # the distance of every pair, in chunks: the (pairs, 3, 3) triangles and their
    # closest points exist one chunk at a time (about 200 bytes a pair at once before)
    dist = np.empty(len(j))
    for a in range(0, len(j), _PAIRS):
        with np.errstate(invalid="ignore", divide="ignore"):
            near = trimesh.triangles.closest_point(positions[faces[f[a:a + _PAIRS]]], new_positions[j[a:a + _PAIRS]])
        dist[a:a + _PAIRS] = np.linalg.norm(near - new_positions[j[a:a + _PAIRS]], axis=1)
    dist[~np.isfinite(dist)] = np.inf
    order = np.lexsort((dist, j))  # by vertex, nearest first
    del dist
    js = j[order]
    first = order[np.r_[True, js[1:] != js[:-1]]]
    del order, js
    best_j, best_f = j[first], f[first]
    del j, f
    tri = positions[faces[best_f]]
    close = np.empty((len(best_j), 3))
    for a in range(0, len(best_j), _PAIRS):  # the nearest pairs' closest points again (the same numbers)
        with np.errstate(invalid="ignore", divide="ignore"):
            close[a:a + _PAIRS] = trimesh.triangles.closest_point(tri[a:a + _PAIRS], new_positions[best_j[a:a + _PAIRS]])
    with np.errstate(invalid="ignore", divide="ignore"):
        bary = trimesh.triangles.points_to_barycentric(tri, close)
    bary = np.clip(np.nan_to_num(bary, nan=-1.0), 0.0, None)
    total = bary.sum(axis=1)
    bad = ~(total > 1e-12)  # a degenerate triangle: take its first corner
    bary[bad] = (1.0, 0.0, 0.0)
    bary /= bary.sum(axis=1, keepdims=True)
    corners = faces[best_f]
    out = {}
    for name, values in attrs.items():
        full = np.zeros((len(new_positions), values.shape[1]))
        if name == "code":  # a blended vertex's axes' code is no quantity to interpolate: the nearest corner's
            full[best_j] = values[corners[np.arange(len(corners)), np.argmax(bary, axis=1)]]
        else:
            full[best_j] = np.einsum("ic,ick->ik", bary, values[corners])
        out[name] = full
    return out


def _finish(attrs, positions, faces):
    """Renormalise interpolated normals/tangents: (n, 3)/(n, 4) float32, colours clipped."""
    normals = attrs["normals"]
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    fallback = area_weighted_normals(positions, faces).astype(np.float64)
    normals = np.where(length > 1e-8, normals / np.maximum(length, 1e-30), fallback)
    out = {"normals": normals.astype(np.float32)}
    if "axis" in attrs:  # interpolated inside one axis's triangles: whole; at a joint: the nearer axis
        out["axis"] = np.rint(attrs["axis"][:, 0]).astype(np.int32)
    if "code" in attrs:  # blended: each vertex's code (AxisTree.vertex_code), what in_axis takes
        out["axis"] = attrs["code"][:, 0].astype(np.float32)
    if "uvs" in attrs:
        out["uvs"] = attrs["uvs"].astype(np.float32)
    if "colors" in attrs:
        out["colors"] = np.clip(attrs["colors"], 0.0, 1.0).astype(np.float32)
    if "tangents" in attrs:
        t = attrs["tangents"]
        xyz = t[:, :3] - np.einsum("ij,ij->i", t[:, :3], normals)[:, None] * normals
        size = np.linalg.norm(xyz, axis=1, keepdims=True)
        # a tangent parallel to the normal: any unit vector orthogonal to it
        other = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        alt = np.cross(normals, other)
        xyz = np.where(size > 1e-8, xyz / np.maximum(size, 1e-30), alt / np.linalg.norm(alt, axis=1, keepdims=True))
        w = np.where(t[:, 3:] < 0.0, -1.0, 1.0)
        out["tangents"] = np.hstack([xyz, w]).astype(np.float32)
    return out


def collapse_mapping(n: int, faces: np.ndarray, collapses: np.ndarray, new_faces: np.ndarray):
    """The simplified vertex each of ``n`` original vertices went into, from the
    collapse history -- what ``fast_simplification.replay_simplification`` returns
    as ``indice_mapping``, without replaying the simplification.

    faces : (m, 3) int64, the original triangles; collapses : (k, 2) int, row
    ``(i0, i1)``: vertex ``i1`` was collapsed into ``i0``, in order;
    new_faces : (m', 3) int64, the simplified triangles.  Returns (n,) int64
    (-1: a vertex of no simplified triangle: unreferenced, or of a piece that
    vanished), or None when the history does not reproduce ``new_faces``
    (the caller then asks the library's replay).

    A vertex ends in the root of its collapse chain; a triangle survives when
    its corners' roots are three different vertices; the simplified vertices
    are the roots of surviving triangles in increasing order (the simplifier's
    final compaction), and the surviving triangles, in order, must be exactly
    ``new_faces``.  A root left without a triangle follows the edges of the
    collapsed triangles to a root with one (as the replay does)."""
    root = np.arange(n, dtype=np.int64)
    c = np.asarray(collapses, dtype=np.int64).reshape(-1, 2)
    if len(c) and (c.min() < 0 or c.max() >= n):
        return None
    root[c[:, 1]] = c[:, 0]  # last wins, as in the replay
    for _ in range(64):  # pointer jumping: depth halves each round
        nxt = root[root]
        if np.array_equal(nxt, root):
            break
        root = nxt
    else:
        return None  # a cycle: not a history
    rf = root[faces]
    d01, d12, d02 = rf[:, 0] != rf[:, 1], rf[:, 1] != rf[:, 2], rf[:, 0] != rf[:, 2]
    alive = d01 & d12 & d02
    kept = np.zeros(n, dtype=bool)
    kept[rf[alive].ravel()] = True
    rank = np.cumsum(kept) - 1
    if not np.array_equal(rank[rf[alive]], np.asarray(new_faces).reshape(-1, 3)):
        return None
    collapsed = rf[~alive & (d01 | d12 | d02)]  # triangles reduced to an edge
    edges = np.concatenate([collapsed[:, [0, 1]], collapsed[:, [1, 2]], collapsed[:, [0, 2]]])
    edges = edges[edges[:, 0] != edges[:, 1]]
    target = np.where(kept, np.arange(n), -1)
    a, b = edges[:, 0], edges[:, 1]
    for _ in range(n):  # rounds: one step along the edges each (bounded by the longest chain)
        fill_a = (target[a] < 0) & (target[b] >= 0)
        fill_b = (target[b] < 0) & (target[a] >= 0)
        if not (fill_a.any() or fill_b.any()):
            break
        new = target.copy()
        new[a[fill_a]] = target[b[fill_a]]
        new[b[fill_b]] = target[a[fill_b]]
        target = new
    t = target[root]
    return np.where(t >= 0, rank[np.maximum(t, 0)], -1)


def _part_piece(mesh, attributes, part, reduction):
    """One part at one reduction: (positions (v, 3) float64, faces (m, 3) int64,
    attributes name -> (v, k)); ``attributes``: :func:`_attributes` of the mesh;
    ``reduction`` None: the part as it is.  A part of more than
    :data:`LOD_CHUNK_TRIANGLES` triangles is simplified in spatial chunks
    (:func:`spatial_chunks`), each on its own like a part."""
    faces = mesh.faces[part.start:part.start + part.count].astype(np.int64)
    if reduction is None or part.count < MIN_LOD_TRIANGLES or part.count <= LOD_CHUNK_TRIANGLES:
        return _simplified(mesh, attributes, faces, reduction, part.name)
    centroids = (mesh.positions[faces[:, 0]] + mesh.positions[faces[:, 1]] + mesh.positions[faces[:, 2]]) / 3
    pieces = []
    for chunk in spatial_chunks(centroids, LOD_CHUNK_TRIANGLES):
        pieces.append(_simplified(mesh, attributes, faces[chunk], reduction, part.name))
    offsets = np.cumsum([0] + [len(p) for p, _, _ in pieces])
    return (np.concatenate([p for p, _, _ in pieces]),
            np.concatenate([f + o for (_, f, _), o in zip(pieces, offsets)]),
            {name: np.concatenate([a[name] for _, _, a in pieces]) for name in pieces[0][2]})


def spatial_chunks(points: np.ndarray, most: int) -> list:
    """Split ``points`` (m, 3) into groups of at most ``most`` by halving at
    the median along the longest side of each group's box, until every group
    fits: a list of (k,) int64 index arrays, neighbours in space together.
    One Python step per group (about 2 m / ``most`` of them), none per point."""
    points = np.asarray(points, dtype=np.float64)
    done, todo = [], [np.arange(len(points), dtype=np.int64)]
    while todo:
        index = todo.pop()
        if len(index) <= most:
            done.append(np.sort(index))
            continue
        p = points[index]
        side = int(np.argmax(p.max(axis=0) - p.min(axis=0)))
        half = len(index) // 2
        split = np.argpartition(p[:, side], half)
        todo += [index[split[:half]], index[split[half:]]]
    return done


def _simplified(mesh, attributes, faces, reduction, name):
    """The triangles ``faces`` (m, 3) int64 of ``mesh`` at one reduction (None: as
    they are): (positions (v, 3) float64, faces (m', 3) int64 local to them,
    attributes name -> (v, k))."""
    import fast_simplification

    used = _used_vertices(faces, mesh.vertex_count)
    local = np.searchsorted(used, faces)
    positions = mesh.positions[used].astype(np.float64)
    attrs = {key: value[used] for key, value in attributes.items()}
    if reduction is None or len(faces) < MIN_LOD_TRIANGLES:
        return positions, local, attrs
    points, new_faces, collapses = fast_simplification.simplify(positions, local, target_reduction=float(reduction),
                                                                return_collapses=True)
    new_faces = np.asarray(new_faces, dtype=np.int64).reshape(-1, 3)
    if len(new_faces) == 0:  # simplified away entirely: keep the triangles as they are
        return positions, local, attrs
    # which simplified vertex each original vertex was collapsed into: from the
    # collapse history (no replay: fast-simplification keeps its working arrays,
    # ~320 bytes a triangle, for the life of the process after a replay)
    mapping = collapse_mapping(len(positions), local, collapses, new_faces)
    if mapping is None:  # the history does not explain the result: ask the library's replay
        _, replayed, mapping = fast_simplification.replay_simplification(positions.astype(np.float32),
                                                                         local.astype(np.int32), collapses)
        replayed = np.asarray(replayed, dtype=np.int64).reshape(-1, 3)
        if not np.array_equal(replayed, new_faces):  # never seen; carry attributes by the mapping anyway
            warnings.warn(f"{mesh.name}: part {name!r}: the replayed simplification differs from the "
                          "simplification; attributes follow the replay's vertex mapping", RuntimeWarning,
                          stacklevel=4)
    keep = _used_vertices(new_faces, len(points))  # drop vertices no triangle uses
    remap = np.full(len(points), -1, dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    mapping = np.asarray(mapping, dtype=np.int64)
    mapping = np.where((mapping >= 0) & (mapping < len(points)), remap[np.clip(mapping, 0, len(points) - 1)], -1)
    points = np.asarray(points, dtype=np.float64)[keep]
    new_faces = remap[new_faces]
    return points, new_faces, _transfer(positions, local, attrs, points, mapping)


def build_lod_levels(mesh, reductions=LOD_REDUCTIONS) -> list[LodLevel]:
    """Level 0 (the base mesh itself) and up to ``len(reductions)`` simplified levels.

    Each part with at least :data:`MIN_LOD_TRIANGLES` triangles is simplified
    on its own (``reduction`` of its triangles removed), smaller parts are
    carried unchanged.  A mesh without such a part keeps one level and says
    so (a ``UserWarning``); a level that removes less than a fifth of the
    previous level's triangles, or keeps fewer than 4, is dropped.
    """
    base = LodLevel.of(mesh)
    if not any(p.count >= MIN_LOD_TRIANGLES for p in mesh.parts):
        largest = max(p.count for p in mesh.parts)
        warnings.warn(f"{mesh.name}: {len(mesh.faces)} triangles are too few to simplify (LOD needs a part of at "
                      f"least {MIN_LOD_TRIANGLES}; the largest has {largest}); drawing one level",
                      UserWarning, stacklevel=2)
        return [base]

    full_cloud = _surface_points(mesh.positions, mesh.faces, _SAMPLE, 1)
    attributes = _attributes(mesh)
    levels = [base]
    for reduction in reductions:
        pieces = [_part_piece(mesh, attributes, part, reduction) for part in mesh.parts]
        total = sum(len(f) for _, f, _ in pieces)
        if total < 4 or total > 0.8 * len(levels[-1].faces):
            continue
        offsets = np.cumsum([0] + [len(p) for p, _, _ in pieces])
        starts = np.cumsum([0] + [len(f) for _, f, _ in pieces])
        points = np.concatenate([p for p, _, _ in pieces])
        faces = np.concatenate([f + o for (_, f, _), o in zip(pieces, offsets)])
        attrs = {name: np.concatenate([a[name] for _, _, a in pieces]) for name in pieces[0][2]}
        attrs = _finish(attrs, points, faces)
        parts = tuple(Part(p.name, int(s), len(f), p.material)
                      for p, s, (_, f, _) in zip(mesh.parts, starts, pieces))
        simple_cloud = _surface_points(points, faces, _SAMPLE, 2)
        error = max(_one_sided(full_cloud, simple_cloud), _one_sided(simple_cloud, full_cloud))
        levels.append(LodLevel(points.astype(np.float32), attrs["normals"], faces.astype(np.uint32),
                               max(error, levels[-1].error), attrs.get("uvs"), attrs.get("colors"),
                               attrs.get("tangents"), parts, attrs.get("axis")))
    if len(levels) == 1:
        warnings.warn(f"{mesh.name}: simplification removed too few triangles; drawing one level",
                      UserWarning, stacklevel=2)
    return levels

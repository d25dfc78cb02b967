"""Step 1 of the data flow: the base mesh.

A :class:`BaseMesh` is what every later step needs from a mesh file:
positions, unit vertex normals and triangles, in the file's own vertex order,
plus its appearance (UVs, vertex colours, parts with materials).
Files are read with trimesh (OBJ, PLY, STL, OFF, GLB/glTF) with
``process=False`` so nothing is merged or reordered.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from .arrays import as_array, position_ids
from .axis import ControlAxis
from .errors import MeshError, brief_names
from .material import Part

__all__ = ['BaseMesh', 'area_weighted_normals', "check_float32_range", "anchor_point"]


@dataclass(frozen=True, eq=False)
class BaseMesh:
    """One triangle mesh, ready to be deformed and drawn.

    Attributes
    ----------
    positions : (n, 3) float32
        Vertex positions in model units, in the file's vertex order.
    normals : (n, 3) float32
        Unit vertex normals: the file's own where it has them, else
        area-weighted normals of the faces around each vertex.
    faces : (m, 3) uint32
        Triangles as indices into ``positions`` (n-gons are triangulated).
    name : str
        Where the mesh came from (a file path or a bundled mesh name).
    normals_from_file : bool
        True when ``normals`` were read from the file.
    uvs : (n, 2) float32 or None
        Texture coordinates (OBJ convention: ``v = 0`` is the image's bottom).
    colors : (n, 4) float32 or None
        Linear RGBA vertex colours.
    tangents : (n, 4) float32 or None
        Unit tangent (xyz) and handedness (w = ±1): a glTF file's own
        ``TANGENT`` where it has one (:func:`gltf_attributes`), else computed
        (:func:`~axialdeform.core.material.compute_tangents`) where a part
        has a normal map; None otherwise.
    parts : tuple of Part
        Ranges of ``faces`` each drawn with its own material (one part
        covering every face by default).  All parts share ONE control axis.
    source_index : (n,) int64
        For each vertex, the index of the vertex in the file it came from
        (``-1`` where none could be matched).  The identity unless the
        reader split or dropped vertices: trimesh splits an OBJ's ``v``
        at UV and normal seams and drops the ones no face uses.
    source_count : int
        How many vertices the file itself lists (OBJ: its ``v`` lines).
    grid : (rows, cols) or None
        A height map's grid (its wireframe edges are made from it,
        :func:`grid_edges`), else None.
    axis_frame : {"auto", "aligned", "oriented"} or (3, 3) rows
        How the control axis is chosen (:meth:`with_axis` sets it); ``_axis`` holds the one found.
    tree : AxisTree or None
        Several axes in a hierarchy (:func:`~axialdeform.core.io.mesh.with_axes`), else None.
    sources : tuple of Path
        Every file the mesh was read from (its own, a material library, textures, buffers): what an
        output must never replace; empty for a mesh made in memory.
    """

    positions: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    name: str = "<mesh>"
    normals_from_file: bool = False
    uvs: np.ndarray | None = None
    colors: np.ndarray | None = None
    tangents: np.ndarray | None = None
    parts: tuple = ()
    source_index: np.ndarray | None = None
    source_count: int | None = None
    _axis: ControlAxis | None = field(default=None, repr=False)
    grid: tuple | None = field(default=None, repr=False)
    axis_frame: object = field(default="auto", repr=False)
    tree: object = field(default=None, repr=False)
    #: every file the mesh was read from (its own, a material library, textures, buffers): what an
    #: output must never replace; empty for a mesh made in memory
    sources: tuple = field(default=(), repr=False)

    @classmethod
    def from_arrays(cls, vertices, faces, normals=None, *, name: str = "<arrays>") -> BaseMesh:
        """A mesh from arrays: ``vertices : (n, 3) float``, ``faces : (m, 3) int``
        and optional unit ``normals : (n, 3) float`` (else area-weighted ones); ``name`` names it in
        messages."""

        vertices = as_array(vertices, (None, 3), f"{name}: vertices", error=MeshError)
        faces = as_array(faces, (None, 3), f"{name}: faces", np.int64, error=MeshError)
        if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
            raise MeshError(f"{name}: faces: expected indices 0..{len(vertices) - 1}, found {int(faces.min())}..{int(faces.max())}")
        if normals is None:
            if not np.isfinite(vertices).all():
                bad = int(np.argwhere(~np.isfinite(vertices).all(axis=1))[0, 0])
                raise MeshError(f"{name}: vertex {bad} has a non-finite coordinate {vertices[bad].tolist()}; expected finite numbers")
            normals = area_weighted_normals(vertices, faces)
        else:
            normals = as_array(normals, (len(vertices), 3), f"{name}: normals", error=MeshError)
        return cls(vertices, normals, faces, name=name, normals_from_file=False)

    def __repr__(self) -> str:
        return (f"BaseMesh({self.name!r}, {self.vertex_count} vertices, {len(self.faces)} triangles, "
                f"axis {self.axis.name}, L={self.axis.length:.6g})")

    def __post_init__(self) -> None:
        with np.errstate(over="ignore", invalid="ignore"):  # out-of-range coordinates are refused below
            pos = np.ascontiguousarray(self.positions, dtype=np.float32)
        nrm = np.ascontiguousarray(self.normals, dtype=np.float32)
        faces = np.ascontiguousarray(self.faces, dtype=np.uint32)
        if pos.ndim != 2 or pos.shape[1] != 3 or len(pos) == 0:
            raise MeshError(f"{self.name}: expected vertex positions of shape (n, 3) with n > 0, found {pos.shape}")
        if nrm.shape != pos.shape:
            raise MeshError(f"{self.name}: expected normals of shape {pos.shape}, found {nrm.shape}")
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
            raise MeshError(f"{self.name}: expected at least one triangle (faces of shape (m, 3)), found {faces.shape}")
        check_float32_range(np.asarray(self.positions, dtype=np.float64), self.name)
        if not np.isfinite(pos).all():
            bad = int(np.argwhere(~np.isfinite(pos).all(axis=1))[0, 0])
            raise MeshError(f"{self.name}: vertex {bad} has a non-finite coordinate {pos[bad].tolist()}; expected finite numbers")
        if faces.max() >= len(pos):
            raise MeshError(f"{self.name}: a face refers to vertex {int(faces.max())}, but the mesh has {len(pos)} vertices")
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "normals", nrm)
        object.__setattr__(self, "faces", faces)
        if self.source_index is None:
            index = np.arange(len(pos), dtype=np.int64)
        else:
            index = np.ascontiguousarray(self.source_index, dtype=np.int64)
            if index.shape != (len(pos),):
                raise MeshError(f"{self.name}: expected source_index of shape ({len(pos)},), found {index.shape}")
        object.__setattr__(self, "source_index", index)
        count = int(index.max()) + 1 if self.source_count is None else int(self.source_count)
        if count <= index.max():
            raise MeshError(f"{self.name}: source_index refers to file vertex {int(index.max())}, but source_count is {count}")
        object.__setattr__(self, "source_count", count)
        _check_appearance(self, len(pos), len(faces))
        # raises MeshError on a zero extent
        if self.tree is not None:  # several axes: axis 0 is the root (core/axes.py)
            if len(self.tree.vertex_axis) != len(pos):
                raise MeshError(f"{self.name}: axes: expected {len(pos)} vertex axis indices, found {len(self.tree.vertex_axis)}")
            object.__setattr__(self, "_axis", self.tree.axes[0])
        else:
            object.__setattr__(self, "_axis", ControlAxis.from_positions(pos, name=self.name, frame=self.axis_frame))

    def with_axis(self, axis="auto") -> BaseMesh:
        """This mesh with another axis frame (``docs/method.md``, "A chosen axis
        frame"): ``"auto"``, ``"x"``, ``"y"``, ``"z"``, ``"oriented"`` or a 3×3
        matrix whose rows are ``e_a, e_u, e_v``.  Positions, faces and the
        fingerprint stay; parameter files record the frame."""
        if isinstance(axis, str) and axis == self.axis_frame and self.tree is None:
            return self  # the frame it has
        return dataclasses.replace(self, axis_frame=axis, _axis=None, tree=None)

    def with_parts(self, names) -> BaseMesh:
        """This mesh with only the parts ``names`` (in the file's order; the file's names, any
        script): what a tree file's scenery (an island, a water plane) is left out with, before
        anything is made from the mesh -- its axis, axes, bounds, framing, spacing, export.  The
        vertices no kept face uses are dropped (the rest keep their order and ``source_index``),
        so the fingerprint is the smaller mesh's.

        names : iterable of str
        """
        names = [names] if isinstance(names, str) else list(names)
        have = {p.name for p in self.parts}
        wanted = set(names)
        unknown = [n for n in names if n not in have]
        if unknown or not names:
            raise MeshError(f"{self.name}: parts: no part {brief_names(unknown) or '(none given)'}; "
                            f"expected some of {brief_names(p.name for p in self.parts)}")
        keep = [p for p in self.parts if p.name in wanted]
        faces = np.concatenate([self.faces[p.start:p.start + p.count] for p in keep])
        used = np.zeros(self.vertex_count, dtype=bool)
        used[faces.ravel()] = True
        new_index = np.cumsum(used) - 1
        parts, start = [], 0
        for p in keep:
            parts.append(dataclasses.replace(p, start=start))
            start += p.count
        def pick(a):
            return None if a is None else np.ascontiguousarray(a[used])

        source_index = pick(self.source_index)
        return dataclasses.replace(
            self, positions=pick(self.positions), normals=pick(self.normals),
            faces=new_index[faces].astype(self.faces.dtype), uvs=pick(self.uvs), colors=pick(self.colors),
            tangents=pick(self.tangents), parts=tuple(parts), source_index=source_index, grid=None, _axis=None,
            tree=None)

    def with_control_axis(self, axis: ControlAxis) -> BaseMesh:
        """This mesh with exactly ``axis`` (the numbers a file records: its frame, ``lo``, ``length``
        and axis line), not the one its points give."""
        out = dataclasses.replace(self, axis_frame=axis.matrix if axis.framed else "xyz"[axis.index], _axis=None,
                                  tree=None)
        object.__setattr__(out, "_axis", axis)
        return out

    def with_axes(self, axes, axis="auto") -> BaseMesh:
        """This mesh with several axes in a hierarchy (``docs/method.md``,
        "Several axes"; :mod:`axialdeform.core.axes`):

        * ``"parts"`` -- one axis per part, the root the largest part, each
          other part's parent the axis nearest its root end;
        * ``"skeleton"`` -- the axes from the model's own shape, a curve skeleton cut into
          branches (:func:`~axialdeform.core.skeleton.skeleton_tree`; cached by the mesh's
          fingerprint);
        * ``"auto"`` -- ``"parts"`` when the mesh's parts are its limbs (two or more parts, and no
          part branches: :func:`~axialdeform.core.shape_axes.parts_are_limbs`), else ``"skeleton"``;
        * a list of ``{"part": NAME, "parent": NAME, "axis": FRAME}`` (the root
          first, without a parent; a parent before its children);
        * ``{"branches": [{"name", "parent", "points"}, ...]}`` -- the branches of a skeleton (an axes
          file of ``[[branch]]`` tables, :func:`~axialdeform.core.skeleton.tree_from_branches`);
        * ``{"vertex_axis": (v,) int, "parents": [-1, ...], "frames": [...]}``
          -- per-vertex axis indices and a parent list;
        * None or 1 -- one axis again.

        ``axis``: the frame rule of every axis without its own (``"auto"``, ...).
        """
        from .axes import AXES_RULES, AxisTree, tree_from_parts, tree_from_spec, tree_from_vertices
        from .shape_axes import shape_tree
        from .skeleton import tree_from_branches

        if axes is None or (isinstance(axes, int) and axes == 1):
            return self.with_axis(axis)
        if isinstance(axes, AxisTree):
            tree = axes
        elif isinstance(axes, str):
            if axes not in AXES_RULES:
                raise MeshError(f"{self.name}: axes: expected one of {', '.join(map(repr, AXES_RULES))}, a list of "
                                f"{{part, parent, axis}} entries or per-vertex axes, found {axes!r:.80}")
            tree = tree_from_parts(self, axis) if axes == "parts" else shape_tree(self, axes, axis)
        elif isinstance(axes, dict) and set(axes) == {"branches"}:  # an axes file of [[branch]] tables
            tree = tree_from_branches(self, axes["branches"])
        elif isinstance(axes, dict):
            if set(axes) - {"vertex_axis", "parents", "frames", "names"} or not {"vertex_axis", "parents"} <= set(axes):
                raise MeshError(f"{self.name}: axes: expected keys vertex_axis and parents (and optional frames, "
                                f"names), found {', '.join(map(str, axes))}")
            tree = tree_from_vertices(self, axes["vertex_axis"], axes["parents"],
                                      frames=axes.get("frames") or [axis] * len(axes["parents"]), names=axes.get("names"))
        else:
            tree = tree_from_spec(self, axes, axis)
        if tree.count == 1:
            return dataclasses.replace(self, axis_frame=tree.axes[0].matrix if tree.axes[0].framed else
                                       "xyz"[tree.axes[0].index], _axis=None, tree=None)
        return dataclasses.replace(self, _axis=None, tree=tree)

    @property
    def axis_count(self) -> int:
        """K, the number of axes (1 unless :meth:`with_axes` gave it several)."""
        return 1 if self.tree is None else self.tree.count

    @property
    def axis(self) -> ControlAxis:
        """The control axis of this mesh (see :mod:`axialdeform.core.axis`)."""
        assert self._axis is not None
        return self._axis

    def part(self, name: str):
        """The :class:`~axialdeform.core.material.Part` called ``name``
        (:class:`MeshError` listing the names if there is none)."""
        for p in self.parts:
            if p.name == name:
                return p
        raise MeshError(f"{self.name}: no part {str(name)[:40]!r}; expected one of {brief_names(p.name for p in self.parts)}")

    @property
    def part_names(self) -> tuple:
        return tuple(p.name for p in self.parts)

    @property
    def has_appearance(self) -> bool:
        """True when the mesh carries UVs, colours, several parts or a non-default material."""
        return (self.uvs is not None or self.colors is not None or len(self.parts) > 1
                or not self.parts[0].material.is_default)

    @property
    def vertex_count(self) -> int:
        return len(self.positions)

    @cached_property
    def fingerprint(self) -> bytes:
        """32-byte SHA-256 of the positions (float32) and faces (uint32),
        little-endian: identifies the base mesh a parameter file was made for."""
        h = hashlib.sha256()
        h.update(self.positions.astype("<f4").tobytes())
        h.update(self.faces.astype("<u4").tobytes())
        return h.digest()

    @cached_property
    def edges(self) -> np.ndarray:
        """(k, 2) uint32 unique undirected edges of the triangles (for wireframe):
        a height map's from its grid (:attr:`grid`, :func:`grid_edges`), else
        searched in the triangles (:func:`unique_edges`)."""
        grid = getattr(self, "grid", None)
        if grid is not None:
            return grid_edges(*grid)
        return unique_edges(self.faces, len(self.positions))

    @cached_property
    def is_volume(self) -> bool:
        """True when the mesh bounds a volume with outward-facing triangles,
        as ``trimesh.Trimesh.is_volume`` means it: after merging vertices at
        equal positions, every directed edge occurs once and its reverse once
        (closed, consistently wound), and the signed volume is positive
        (counter-clockwise seen from outside).

        Only then can back faces be culled without changing the picture;
        :class:`~axialdeform.gl.renderer.AxialRenderer` does that by default.
        """
        ids = position_ids(self.positions)
        f = ids[self.faces]
        if ((f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 2] == f[:, 0])).any():
            return False
        n = int(f.max()) + 1
        a, b = f.ravel(), f[:, [1, 2, 0]].ravel()  # directed edges a -> b
        forward = np.sort(a * n + b)
        if (forward[1:] == forward[:-1]).any():
            return False
        reverse = np.sort(b * n + a)
        if not np.array_equal(forward, reverse):
            return False
        # signed volume: sum of det(v0, v1, v2) / 6, by columns (np.cross on (m, 3) is slow)
        p = self.positions.astype(np.float64)
        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        i, j, k = self.faces[:, 0], self.faces[:, 1], self.faces[:, 2]
        volume = float(np.sum(x[i] * (y[j] * z[k] - z[j] * y[k]) + y[i] * (z[j] * x[k] - x[j] * z[k])
                              + z[i] * (x[j] * y[k] - y[j] * x[k]))) / 6.0
        return bool(volume > 0.0)

    def to_trimesh(self, positions: np.ndarray | None = None, normals: np.ndarray | None = None):
        """A ``trimesh.Trimesh`` with these faces and the given (or own) positions/normals."""
        import trimesh

        return trimesh.Trimesh(
            vertices=self.positions if positions is None else positions,
            faces=self.faces,
            vertex_normals=self.normals if normals is None else normals,
            process=False,
        )


_F32_MAX = float(np.finfo(np.float32).max)


def grid_edge_count(rows: int, cols: int) -> int:
    """How many edges :func:`grid_edges` gives (without making them)."""
    return (int(rows) - 1) * (3 * int(cols) - 2) + int(cols) - 1


def grid_edge_pieces(rows: int, cols: int, piece_rows: int = 64):
    """:func:`grid_edges` in pieces of ``piece_rows`` grid rows, a generator of
    ``(first edge, (k, 2) uint32)``: concatenated they are exactly
    :func:`grid_edges`, but memory holds one piece (a GL buffer written piece
    by piece never needs the whole 54 MB of a 1 500 x 1 500 map)."""
    rows, cols, step = int(rows), int(cols), max(1, int(piece_rows))
    per_row = 3 * cols - 2  # right, down-left (not at column 0), down: the edges a row starts
    for r0 in range(0, rows - 1, step):
        r1 = min(rows - 1, r0 + step)
        sub = grid_edges(r1 - r0 + 1, cols)[: (r1 - r0) * per_row]  # rows r0 .. r1 - 1 as a small grid
        yield r0 * per_row, sub + np.uint32(r0 * cols)
    last = np.uint32((rows - 1) * cols)  # the last row: right edges only
    c = np.arange(cols - 1, dtype=np.uint32)
    yield (rows - 1) * per_row, np.stack([c + last, c + 1 + last], axis=1)


def grid_edges(rows: int, cols: int) -> np.ndarray:
    """(k, 2) uint32 edges of a ``rows`` x ``cols`` height-map grid (vertex
    ``r * cols + c``, each cell split by the diagonal from ``(r, c + 1)`` to
    ``(r + 1, c)``, as :func:`axialdeform.core.surface.load_surface` makes
    it): exactly :func:`unique_edges` of its triangles, in the same order,
    made without sorting (a 1 500 x 1 500 map: 6.7 M edges, 54 MB, where
    sorting them needs 3x that)."""
    rows, cols = int(rows), int(cols)
    # one row's edges, vertex by vertex (right, down-left, down where they exist), relative to its first vertex
    c = np.arange(cols, dtype=np.uint32)
    offsets = [np.ones(cols, bool), c > 0, np.ones(cols, bool)]
    offsets[0][-1] = False  # no right edge at the last column
    ends = np.stack([c + 1, c + cols - 1, c + cols], axis=1)
    valid = np.stack(offsets, axis=1)
    row = np.stack([np.broadcast_to(c[:, None], ends.shape)[valid], ends[valid]], axis=1)  # (3 cols - 2, 2)
    inner = (rows - 1) * len(row)
    out = np.empty((inner + cols - 1, 2), dtype=np.uint32)
    np.add(row[None], (np.arange(rows - 1, dtype=np.uint32) * np.uint32(cols))[:, None, None],
           out=out[:inner].reshape(rows - 1, len(row), 2))
    last = np.uint32((rows - 1) * cols)  # the last row: right edges only
    out[inner:, 0] = c[:-1] + last
    out[inner:, 1] = c[1:] + last
    return out


def unique_edges(faces: np.ndarray, vertex_count: int) -> np.ndarray:
    """(k, 2) uint32 unique undirected edges of ``faces`` (m, 3) int, sorted by
    their lower vertex, then the higher (what ``np.unique(np.sort(pairs, axis=1),
    axis=0)`` gives).  One int64 key per edge, made column by column into one
    array and sorted in place: ~40 bytes a triangle at once (a 1 M-triangle
    mesh: 171 MB before, with a (3 m, 2) int64 copy and its temporaries)."""
    f = np.asarray(faces)
    m, n = len(f), np.int64(vertex_count)
    key = np.empty(3 * m, dtype=np.int64)
    for c, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
        a, b = f[:, i].astype(np.int64), f[:, j].astype(np.int64)
        np.minimum(a, b, out=key[c * m:(c + 1) * m])
        key[c * m:(c + 1) * m] *= n
        key[c * m:(c + 1) * m] += np.maximum(a, b, out=a)
        del a, b
    key.sort()
    if len(key):
        key = key[np.r_[True, key[1:] != key[:-1]]]
    out = np.empty((len(key), 2), dtype=np.uint32)
    out[:, 0] = key // n
    out[:, 1] = key % n
    return out


def check_float32_range(positions: np.ndarray, name: str) -> None:
    """Raise :class:`MeshError` if a finite float64 coordinate does not fit in float32
    (the GPU and every buffer hold float32)."""
    p = np.asarray(positions, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        big = np.isfinite(p) & (np.abs(p) > _F32_MAX)
    if big.any():
        bad = int(np.argwhere(big.any(axis=1))[0, 0])
        raise MeshError(
            f"{name}: vertex {bad} has coordinate {float(p[bad][big[bad]][0]):.6g}, which does not fit in float32; "
            f"expected magnitudes up to {_F32_MAX:.6g} (scale the mesh down)"
        )


#: faces per block of :func:`area_weighted_normals` (bounds its temporaries; rows per
#: block of its unit step)
_NORMAL_BLOCK = 1 << 17


def area_weighted_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit vertex normals, each the area-weighted mean of its faces' normals.

    positions : (n, 3) float; faces : (m, 3) int.  Returns (n, 3) float32.
    A vertex with no face area around it gets ``(0, 0, 1)``.
    """
    p = np.asarray(positions, dtype=np.float64)
    f = np.asarray(faces)
    # scale to unit size first: the result does not depend on the scale, and
    # neither 1e-30 (cross products underflow the cut-off) nor 1e30 meshes lose normals
    center = p.mean(axis=0) if len(p) else np.zeros(3)
    scale = float(np.max([np.max(np.abs(p[:, c] - center[c])) for c in range(3)])) if len(p) else 0.0
    # by columns and by blocks of faces: gathers of (block,) arrays, no (m, 3, 3)
    # temporaries nor a scaled copy of the positions, so the temporaries stay ~16 MB
    # whatever the mesh (a 1 M-triangle mesh: 168 MB at once before); one block gives
    # the same bits as one sum over all faces, several the same float32 normals
    # (checked on random meshes of up to 900 000 faces), up to rounding order
    unit = np.isfinite(scale) and scale > 0

    def coord(c, index):  # column c of the scaled positions at ``index``, gathered (elementwise as a scaled copy)
        return (p[index, c] - center[c]) / scale if unit else p[index, c]

    n = len(p)
    vn = np.zeros((n, 3))
    for start in range(0, len(f), _NORMAL_BLOCK):
        i, j, k = (f[start:start + _NORMAL_BLOCK, c].astype(np.int64) for c in range(3))
        (xi, yi, zi), (xj, yj, zj), (xk, yk, zk) = ((coord(0, v), coord(1, v), coord(2, v)) for v in (i, j, k))
        ax, ay, az = xj - xi, yj - yi, zj - zi
        bx, by, bz = xk - xi, yk - yi, zk - zi
        del xi, yi, zi, xj, yj, zj, xk, yk, zk
        # the cross product's length is twice the triangle's area: area weighting
        fn = (ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx)
        del ax, ay, az, bx, by, bz
        for c in range(3):
            part = np.bincount(i, weights=fn[c], minlength=n)
            part += np.bincount(j, weights=fn[c], minlength=n)
            part += np.bincount(k, weights=fn[c], minlength=n)
            if start:
                vn[:, c] += part
            else:  # assigned, not added to 0: the same bits (-0.0 too) as one bincount sum
                vn[:, c] = part
    return _unit_or_default(vn)


def _unit_or_default(v: np.ndarray) -> np.ndarray:
    """(n, 3) float -> (n, 3) float32 unit rows ((0, 0, 1) where a row is ~0), over
    blocks of rows: no (n, 3) float64 temporaries besides ``v`` itself."""
    out = np.empty((len(v), 3), dtype=np.float32)
    for start in range(0, len(v), _NORMAL_BLOCK):
        b = v[start:start + _NORMAL_BLOCK]
        length = np.linalg.norm(b, axis=1)
        ok = length > 1e-30
        unit = np.zeros_like(b, dtype=np.float64)
        unit[ok] = b[ok] / length[ok, None]
        unit[~ok] = (0.0, 0.0, 1.0)
        out[start:start + _NORMAL_BLOCK] = unit
    return out


def _check_appearance(mesh: BaseMesh, n: int, m: int) -> None:
    """Validate and normalise uvs/colors/tangents/parts of a BaseMesh in place."""

    for key, width in (("uvs", 2), ("colors", 4), ("tangents", 4)):
        value = getattr(mesh, key)
        if value is None:
            continue
        arr = np.ascontiguousarray(value, dtype=np.float32)
        if key == "colors" and arr.ndim == 2 and arr.shape[1] == 3:
            arr = np.hstack([arr, np.ones((len(arr), 1), np.float32)])
        if arr.ndim != 2 or arr.shape != (n, width):
            what = {"uvs": "texture coordinates", "colors": "vertex colours", "tangents": "tangents"}[key]
            raise MeshError(f"{mesh.name}: {arr.shape[0] if arr.ndim else 0} {what} for {n} vertices; "
                            f"expected shape ({n}, {width})")
        if not np.isfinite(arr).all():
            raise MeshError(f"{mesh.name}: {key}: expected finite numbers")
        object.__setattr__(mesh, key, arr)
    parts = tuple(mesh.parts) or (Part(name=Path(str(mesh.name)).stem or "mesh", start=0, count=m),)
    end = 0
    for p in parts:
        if p.start != end or p.count < 0:
            raise MeshError(f"{mesh.name}: part {p.name!r} covers faces {p.start}..{p.start + p.count - 1}; "
                            f"expected parts in order without gaps, starting at face {end}")
        end = p.start + p.count
    if end != m:
        raise MeshError(f"{mesh.name}: the parts cover {end} faces; expected all {m}")
    object.__setattr__(mesh, "parts", parts)


def anchor_point(base, anchor: str, u: int) -> np.ndarray:
    """(3,) float64: the point of the base mesh that sits on the surface (model space): ``bottom``, the
    centre of its bounding box's face at the lowest coordinate ``u`` (up); ``center``; ``origin``."""
    if anchor == "origin":
        return np.zeros(3)
    lo, hi = base.positions.min(axis=0), base.positions.max(axis=0)
    a = (lo + hi) / 2.0
    if anchor == "bottom":
        a[u] = lo[u]
    return a.astype(np.float64)

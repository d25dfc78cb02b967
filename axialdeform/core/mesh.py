"""Step 1 of the data flow: the base mesh.

A :class:`BaseMesh` is what every later step needs from a mesh file:
positions, unit vertex normals and triangles, in the file's own vertex order,
plus its appearance (UVs, vertex colours, parts with materials).
Files are read with trimesh (OBJ, PLY, STL, OFF, GLB/glTF) with
``process=False`` so nothing is merged or reordered.
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, field
from functools import cached_property
from importlib import resources
from pathlib import Path

import numpy as np

from .axis import ControlAxis
from .errors import AxialDeformError, MeshError

__all__ = ["BaseMesh", "load_mesh", "mesh_source_path", "bundled_mesh_path", "BUNDLED_MESHES", "MESH_SUFFIXES",
           "area_weighted_normals", "gltf_attributes"]

#: Names of the meshes shipped in the wheel (``axialdeform/meshes/NAME.obj``,
#: or ``NAME.glb`` for the textured leaf card of ``tools/make_leaf_card.py``).
BUNDLED_MESHES = ("stone", "leaf", "leafcard")

#: File name suffixes of the mesh files this library reads (base meshes, fit variants).
MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")


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

    @classmethod
    def from_arrays(cls, vertices, faces, normals=None, *, name: str = "<arrays>") -> "BaseMesh":
        """A mesh from arrays: ``vertices : (n, 3) float``, ``faces : (m, 3) int``
        and optional unit ``normals : (n, 3) float`` (else area-weighted ones)."""
        from .arrays import as_array

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
                f"axis {'xyz'[self.axis.index]}, L={self.axis.length:.6g})")

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
        _check_float32_range(np.asarray(self.positions, dtype=np.float64), self.name)
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
        object.__setattr__(self, "_axis", ControlAxis.from_positions(pos, name=self.name))

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
        raise MeshError(f"{self.name}: no part {name!r}; expected one of {', '.join(repr(p.name) for p in self.parts)}")

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
        """(k, 2) uint32 unique undirected edges of the triangles (for wireframe)."""
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
        ids = _position_ids(self.positions)
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


def _position_ids(positions: np.ndarray) -> np.ndarray:
    """(n,) int64: one id per distinct position (equal rows share it), the
    same grouping as ``np.unique(positions, axis=0, return_inverse=True)``
    but by one lexsort, many times faster on millions of vertices."""
    p = np.asarray(positions)
    if len(p) == 0:
        return np.zeros(0, dtype=np.int64)
    order = np.lexsort((p[:, 2], p[:, 1], p[:, 0]))
    q = p[order]
    new = np.empty(len(p), dtype=bool)
    new[0] = True
    new[1:] = (q[1:] != q[:-1]).any(axis=1)
    ids = np.empty(len(p), dtype=np.int64)
    ids[order] = np.cumsum(new) - 1
    return ids


def _check_float32_range(positions: np.ndarray, name: str) -> None:
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


def bundled_mesh_path(name: str) -> Path:
    """Path of a mesh shipped with the package: ``"stone"``, ``"leaf"`` or ``"leafcard"``."""
    if name not in BUNDLED_MESHES:
        raise MeshError(f"unknown bundled mesh {name!r}; expected one of {', '.join(BUNDLED_MESHES)}")
    suffix = ".glb" if name == "leafcard" else ".obj"
    return Path(str(resources.files("axialdeform.meshes").joinpath(f"{name}{suffix}")))


def mesh_source_path(source: str | os.PathLike) -> Path:
    """The file :func:`load_mesh` reads for ``source`` (a bundled mesh's name
    becomes its file in the package): for comparing outputs with inputs."""
    if isinstance(source, str) and source in BUNDLED_MESHES and not os.path.exists(source):
        return bundled_mesh_path(source)
    return Path(source)


def load_mesh(source) -> BaseMesh:
    """Read a base mesh from a file, a bundled mesh by name (``"stone"``,
    ``"leaf"``), or take a ``trimesh.Trimesh`` (or a ``trimesh.Scene`` with one
    mesh) already in memory.

    A file with several meshes (glTF nodes/primitives, STL bodies, OBJ ``o``
    objects or ``usemtl`` groups) becomes ONE base mesh with several
    :attr:`BaseMesh.parts` (node transforms applied, the file's vertex order
    kept); UVs, vertex colours and materials come along
    (:mod:`axialdeform.core.material`).

    Raises :class:`MeshError` (naming the file) for a missing or unreadable
    file, no faces, non-finite coordinates, UVs or colours whose count does
    not match the vertices, or a longest extent of zero.  A texture that
    cannot be read is an :class:`~axialdeform.core.material.AssetWarning`.
    ``source_index`` maps each vertex to the file's own vertex order
    (``docs/parameter-files.md``, "Vertex order").
    """
    if isinstance(source, BaseMesh):
        return source
    if type(source).__module__.startswith("trimesh"):
        name = f"<{type(source).__name__}>"
        return _from_loaded(source, name)
    if not isinstance(source, (str, os.PathLike)):
        raise MeshError(f"load_mesh: expected a file path, a bundled mesh name ({', '.join(BUNDLED_MESHES)}), "
                        f"a trimesh.Trimesh or a BaseMesh, found {type(source).__name__}")
    if isinstance(source, str) and source in BUNDLED_MESHES and not os.path.exists(source):
        path = bundled_mesh_path(source)
    else:
        path = Path(source)
    name = str(source)
    if not os.path.lexists(path):
        raise MeshError(f"{name}: no such mesh file")
    if path.is_dir():
        raise MeshError(f"{name}: is a folder; expected a mesh file ({', '.join(MESH_SUFFIXES)})")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise MeshError(f"{name}: unsupported mesh file type {path.suffix!r}; expected one of {', '.join(MESH_SUFFIXES)}")
    from .material import SafeResolver, gltf_references
    from .safeio import memory_available, read_regular

    # a regular file (never a FIFO or a device), read with a bound; every
    # file it refers to goes through the same check (SafeResolver)
    data = read_regular(path, max(memory_available() // 2, 1 << 20), f"a mesh file ({', '.join(MESH_SUFFIXES)})",
                        MeshError)
    kind = path.suffix.lower().lstrip(".")
    # each file a glTF refers to is read with the bound it declares (a buffer's byteLength)
    declared = gltf_references(data, kind, name) if kind in ("gltf", "glb") else {}
    resolver = SafeResolver(path.parent, declared=declared, referrer=path.name)
    try:
        import io

        import trimesh

        from .safeio import quiet_numpy

        data = bytes(data)  # trimesh decodes text only from bytes (not bytearray)
        with quiet_numpy():  # trimesh's casts of hostile numbers warn; the results are checked below
            loaded = trimesh.load(io.BytesIO(data), file_type=kind, resolver=resolver, process=False)
            if kind == "obj" and isinstance(loaded, trimesh.Trimesh) and _obj_object_count(data) > 1:
                loaded = _obj_objects(loaded, trimesh.load(io.BytesIO(data), file_type=kind, process=False,
                                                           resolver=SafeResolver(path.parent, referrer=path.name),
                                                           split_objects=True))
        # a material library or buffer that is a FIFO, a device, too large or
        # not its declared size refuses the mesh; such a texture only loses
        # its picture (AssetWarning)
        _refuse(name, resolver, declared)
    except MeshError:
        raise
    except Exception as exc:  # trimesh raises many kinds of errors on bad files
        _refuse(name, resolver, declared)  # a refused buffer is the reason: say it plainly
        raise MeshError(f"{name}: could not read the mesh file ({type(exc).__name__}: {exc})") from None
    file_positions = _obj_positions(data) if path.suffix.lower() == ".obj" else None  # the bytes read above
    dropped = gltf_attributes(data, kind, SafeResolver(path.parent)) if kind in ("glb", "gltf") else []
    del data
    return _from_loaded(loaded, name, file_positions, resolver.failed, dropped)


def _refuse(name: str, resolver, declared: dict) -> None:
    """Raise :class:`MeshError` for the first file the resolver refused that is not a picture."""
    refused = [msg for ref, msg in resolver.refused
               if not (_is_image_name(ref) or declared.get(ref, ("", 0))[1] is None)]
    if refused:
        raise MeshError(f"{name}: {refused[0]}")


def _is_image_name(name: str) -> bool:
    """True for a referenced file that is a picture (a texture), by its suffix."""
    from .material import is_image_name

    return is_image_name(name)


def gltf_attributes(data: bytes, kind: str, resolver=None) -> list:
    """What trimesh drops of a glTF file's triangle primitives: ``TANGENT``
    always, ``TEXCOORD_0`` of a primitive without a material.  A list of
    ``(positions (k, 3) float32, {"TANGENT": (k, 4) float32, "TEXCOORD_0":
    (k, 2) float32})`` (the keys the primitive has), one per primitive with
    either, in the file's vertex order, read by pygltflib and
    :func:`axialdeform.core.export.read_accessor`.  ``kind``: ``"glb"`` or
    ``"gltf"``; ``resolver``: reads a ``.gltf``'s external buffer (a
    :class:`~axialdeform.core.material.SafeResolver`).  Only buffer 0 is read
    (the GLB chunk, a data URI or one ``.bin``); what cannot be read is left
    out (tangents are then computed where a normal map needs them)."""
    import pygltflib

    from .errors import GltfError
    from .export import read_accessor

    try:
        if kind == "glb":
            gltf = pygltflib.GLTF2.load_from_bytes(bytes(data))
            blob = gltf.binary_blob() or b""
        else:
            gltf = pygltflib.GLTF2.from_json(bytes(data).decode("utf-8"))
            uri = gltf.buffers[0].uri if gltf.buffers else None
            if not uri:
                return []
            if uri.startswith("data:"):
                blob = gltf.decode_data_uri(uri)
            elif resolver is not None:
                blob = resolver.get(uri)
            else:
                return []
    except Exception:  # trimesh has read (or refused) the file already: nothing more, not a second error
        return []
    out = []
    for m in gltf.meshes or []:
        for prim in m.primitives or []:
            a = prim.attributes
            wanted = {"TANGENT": a.TANGENT}
            if prim.material is None:
                wanted["TEXCOORD_0"] = a.TEXCOORD_0
            wanted = {k: v for k, v in wanted.items() if v is not None}
            if not wanted or a.POSITION is None or prim.mode not in (None, 4):
                continue
            try:
                views = [gltf.bufferViews[gltf.accessors[i].bufferView] for i in (a.POSITION, *wanted.values())]
                if any(v.buffer != 0 for v in views):
                    continue
                pos = read_accessor(gltf, blob, a.POSITION, "POSITION", "")
                found = {k: read_accessor(gltf, blob, i, k, "").astype(np.float32) for k, i in wanted.items()}
            except (GltfError, IndexError, TypeError, ValueError):
                continue
            widths = {"TANGENT": 4, "TEXCOORD_0": 2}
            found = {k: v for k, v in found.items() if v.shape == (len(pos), widths[k])}
            if pos.ndim == 2 and pos.shape[1] == 3 and found:
                out.append((pos.astype(np.float32), found))
    return out


def _file_attributes_of(mesh, entries: list, used: set) -> dict:
    """The file's dropped attributes (:func:`gltf_attributes`) of one loaded
    geometry: those of the first unused primitive whose positions equal its
    vertices exactly ({} if none)."""
    v = np.asarray(mesh.vertices)
    for k, (pos, found) in enumerate(entries):
        if k not in used and pos.shape == v.shape and np.array_equal(pos.astype(np.float64), v):
            used.add(k)
            return found
    return {}


def _transform_tangents(tangents: np.ndarray, transform: np.ndarray) -> np.ndarray:
    """File tangents (k, 4) under a node transform: xyz by its linear part
    (a tangent is a difference of positions), renormalised; w flips where the
    transform mirrors the frame (bitangent = w · n × t, with n by the inverse
    transpose)."""
    m = transform[:3, :3]
    t = tangents[:, :3] @ m.T
    out = tangents.copy()
    out[:, :3] = t / np.maximum(np.linalg.norm(t, axis=1), 1e-30)[:, None]
    if np.linalg.det(m) < 0:
        out[:, 3] = -out[:, 3]
    return out


def _from_loaded(loaded, name: str, file_positions=None, failed=(), dropped=()) -> BaseMesh:
    """One BaseMesh from what trimesh loaded (a Trimesh, or a Scene whose
    meshes become parts, node transforms applied); ``dropped``: what
    :func:`gltf_attributes` read from the file (tangents, UVs), used where
    its positions match a geometry's."""
    from .material import compute_tangents, gather_parts

    gathered = gather_parts(loaded, name, failed=failed)
    all_positions, all_faces, all_normals, raw_positions = [], [], [], []
    all_tangents, used = [], set()
    uv_list = list(gathered["uv_list"])
    offset = 0
    for g, (mesh, transform) in enumerate(gathered["geometries"]):
        positions = np.asarray(mesh.vertices, dtype=np.float64)
        faces = np.asarray(getattr(mesh, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
        if not np.isfinite(positions).all():
            bad = int(np.argwhere(~np.isfinite(positions).all(axis=1))[0, 0]) + offset
            raise MeshError(f"{name}: vertex {bad} has a non-finite coordinate {positions[bad - offset].tolist()}; expected finite numbers")
        _check_float32_range(positions, name)
        if len(faces) and (faces.min() < 0 or faces.max() >= len(positions)):
            raise MeshError(
                f"{name}: a face refers to vertex {int(faces.min() if faces.min() < 0 else faces.max())}, "
                f"but the mesh has {len(positions)} vertices; expected indices 0..{len(positions) - 1}"
            )
        raw_positions.append(positions)
        file_normals = _file_vertex_normals(mesh, len(positions))
        found = _file_attributes_of(mesh, dropped, used) if dropped else {}
        tangents = found["TANGENT"].astype(np.float64) if "TANGENT" in found else None
        if uv_list[g] is None and "TEXCOORD_0" in found:  # glTF's v points down the image: ours up
            uv_list[g] = np.column_stack([found["TEXCOORD_0"][:, 0], 1.0 - found["TEXCOORD_0"][:, 1]])
        if transform is not None:
            positions = positions @ transform[:3, :3].T + transform[:3, 3]
            if file_normals is not None:
                file_normals = file_normals @ np.linalg.inv(transform[:3, :3])  # inverse transpose
            if tangents is not None:
                tangents = _transform_tangents(tangents, transform)
        all_tangents.append(tangents if tangents is not None else np.full((len(positions), 4), np.nan))
        all_positions.append(positions)
        all_faces.append(faces + offset)
        all_normals.append(file_normals if file_normals is not None else np.full((len(positions), 3), np.nan))
        offset += len(positions)
    positions = np.concatenate(all_positions)
    faces = np.concatenate(all_faces)
    if len(positions) == 0 or len(faces) == 0:
        raise MeshError(f"{name}: the mesh has {len(positions)} vertices and {len(faces)} faces; expected triangles")
    if any(t is not None for _, t in gathered["geometries"]):
        _check_float32_range(positions, name)  # a node transform can push a coordinate out of range
    source_index, source_count = _source_index(np.concatenate(raw_positions), file_positions)
    file_normals = np.concatenate(all_normals)
    has_file_normals = bool(np.isfinite(file_normals).all(axis=1).any())
    if has_file_normals:
        length = np.linalg.norm(file_normals, axis=1)
        usable = np.isfinite(length) & (length > 1e-12)
        computed = area_weighted_normals(positions, faces) if not usable.all() else None
        normals = np.where(usable[:, None], file_normals / np.where(usable, length, 1.0)[:, None], computed if computed is not None else 0.0)
    else:
        normals = area_weighted_normals(positions, faces)
    uvs, colors, parts = gathered["uvs"], gathered["colors"], gathered["parts"]
    if any(u is not None and g is None for u, g in zip(uv_list, gathered["uv_list"])):
        uvs = np.concatenate([u if u is not None else np.zeros((len(m.vertices), 2))
                              for u, (m, _) in zip(uv_list, gathered["geometries"])])
        if not np.isfinite(uvs).all():
            raise MeshError(f"{name}: a texture coordinate is not a finite number")
    # the file's own tangents where it has them (unit xyz, w = ±1); computed
    # for the other vertices, or for all where a normal map asks and the file has none
    tangents = np.concatenate(all_tangents)
    usable = (np.isfinite(tangents).all(axis=1) & (np.abs(np.linalg.norm(tangents[:, :3], axis=1) - 1.0) < 1e-3)
              & (np.abs(np.abs(tangents[:, 3]) - 1.0) < 1e-6))
    if usable.any():
        if not usable.all():
            computed = (compute_tangents(positions, normals, uvs, faces) if uvs is not None
                        else compute_tangents(positions, normals, np.zeros((len(positions), 2)), faces))
            tangents = np.where(usable[:, None], tangents, computed)
    elif uvs is not None and any(p.material.normal_texture is not None for p in parts):
        tangents = compute_tangents(positions, normals, uvs, faces)
    else:
        tangents = None
    return BaseMesh(positions, normals, faces, name=name, normals_from_file=has_file_normals,
                    uvs=uvs, colors=colors, tangents=tangents, parts=tuple(parts),
                    source_index=source_index, source_count=source_count)


def _obj_positions(data: bytes) -> np.ndarray | None:
    """The ``v`` lines of an OBJ file's bytes, ``(k, 3) float64`` in file order (None if unreadable)."""
    try:
        rows = re.findall(rb"^[ \t]*v[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)", data, re.M)
        return np.array(rows, dtype=np.float64).reshape(-1, 3)
    except (OSError, ValueError):
        return None


def _source_index(positions: np.ndarray, file_positions: np.ndarray | None) -> tuple[np.ndarray | None, int | None]:
    """For each loaded vertex the first file vertex at exactly its position
    (-1 if none), and the file's vertex count; (None, None) without a file list."""
    if file_positions is None or len(file_positions) == 0:
        return None, None
    k = len(file_positions)
    if k == len(positions) and np.array_equal(file_positions, positions):
        return np.arange(k, dtype=np.int64), k
    _, ids = np.unique(np.concatenate([file_positions, positions]), axis=0, return_inverse=True)
    ids = ids.reshape(-1)
    first = np.full(int(ids.max()) + 1, -1, dtype=np.int64)
    first[ids[:k][::-1]] = np.arange(k - 1, -1, -1)  # the smallest file index wins
    return first[ids[k:]], k


def _obj_object_count(data: bytes) -> int:
    """How many ``o NAME`` lines an OBJ file's bytes have (a byte scan, so only
    files with several objects pay for the second, splitting load)."""
    import re

    return len(re.findall(rb"(?m)^[ \t]*o[ \t]", data))


def _obj_objects(merged, split):
    """An OBJ's ``o`` objects as the parts of a scene, in the order that keeps
    the merged mesh's vertex and face order (so its fingerprint does not
    change); ``merged`` itself when they cannot be put in that order."""
    import trimesh

    if not isinstance(split, trimesh.Scene):
        return merged
    nodes = [n for n in split.graph.nodes_geometry if isinstance(split.geometry.get(split.graph[n][1]), trimesh.Trimesh)]
    if len(nodes) < 2:
        return merged
    verts = np.asarray(merged.vertices)

    def first_index(node):
        g = split.geometry[split.graph[node][1]]
        gv = np.asarray(g.vertices)
        if not len(gv):
            return -1
        for o in np.flatnonzero((verts == gv[0]).all(axis=1)):  # where its vertices sit in the merged mesh
            if o + len(gv) <= len(verts) and np.array_equal(verts[o:o + len(gv)], gv):
                return int(o)
        return -1

    nodes.sort(key=first_index)
    geoms = [split.geometry[split.graph[n][1]] for n in nodes]
    offsets = np.cumsum([0] + [len(g.vertices) for g in geoms])[:-1]
    v = np.concatenate([np.asarray(g.vertices) for g in geoms])
    f = np.concatenate([np.asarray(g.faces) + o for g, o in zip(geoms, offsets)])
    if v.shape != verts.shape or not np.array_equal(v, verts) or not np.array_equal(f, np.asarray(merged.faces)):
        return merged
    scene = trimesh.Scene()
    for node, g in zip(nodes, geoms):
        scene.add_geometry(g, node_name=str(node), geom_name=str(node))
    return scene


def _file_vertex_normals(mesh, n: int) -> np.ndarray | None:
    """The vertex normals the file itself supplied, or None.

    trimesh keeps normals given at load time in its cache under
    ``vertex_normals``; asking ``mesh.vertex_normals`` otherwise computes them,
    which is not what we want here."""
    cache = getattr(mesh, "_cache", None)
    if cache is None or "vertex_normals" not in cache:
        return None
    vn = np.asarray(cache["vertex_normals"], dtype=np.float64)
    if vn.shape != (n, 3):
        return None
    return vn


def _check_appearance(mesh: "BaseMesh", n: int, m: int) -> None:
    """Validate and normalise uvs/colors/tangents/parts of a BaseMesh in place."""
    from .material import Part

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

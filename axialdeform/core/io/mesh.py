"""Reading mesh files (OBJ, PLY, STL, OFF, glTF/GLB) through trimesh into a
:class:`~axialdeform.core.mesh.BaseMesh`: the file's vertex order and normals
kept, its parts and materials, every byte read through the bounded reader."""

from __future__ import annotations

import dataclasses
import difflib
import json
import os
import re
import warnings
from importlib import resources
from pathlib import Path

import numpy as np

from ..axes import AXES_RULES
from ..errors import AxialDeformError, MeshError
from ..material import AssetWarning, compute_tangents, gather_parts, texture_decoding
from ..mesh import BaseMesh, area_weighted_normals, check_float32_range
from . import safeio
from .atomic import atomic_write_text
from .gltf import gltf_attributes
from .resolver import (
    SafeResolver,
    error_in_words,
    gltf_json,
    gltf_references,
    is_image_name,
    unsupported_features,
)
from .safeio import read_regular

__all__ = ['BUNDLED_MESHES', 'MESH_SUFFIXES', 'bundled_mesh_path', 'load_mesh', 'mesh_source_path', 'with_axes',
           'write_axes_file']


#: Names of the meshes shipped in the wheel (``axialdeform/meshes/NAME.obj``,
#: or ``NAME.glb`` for the textured leaf card of ``tools/make_leaf_card.py``).
BUNDLED_MESHES = ("stone", "leaf", "leafcard", "tree")


#: File name suffixes of the mesh files this library reads (base meshes, fit variants).
MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")


def bundled_mesh_path(name: str) -> Path:
    """Path of a mesh shipped with the package: ``"stone"``, ``"leaf"``, ``"leafcard"`` or ``"tree"``
    (``tools/make_tree.py``: a trunk, six branches and three twigs as parts; its
    hierarchy is :data:`~axialdeform.core.axes.TREE_AXES`)."""
    if name not in BUNDLED_MESHES:
        raise MeshError(f"unknown bundled mesh {name!r}; expected one of {', '.join(BUNDLED_MESHES)}")
    suffix = ".glb" if name in ("leafcard", "tree") else ".obj"
    return Path(str(resources.files("axialdeform.meshes").joinpath(f"{name}{suffix}")))


def mesh_source_path(source: str | os.PathLike) -> Path:
    """The file :func:`load_mesh` reads for ``source`` (a bundled mesh's name
    becomes its file in the package): for comparing outputs with inputs."""
    if isinstance(source, str) and source in BUNDLED_MESHES and not os.path.exists(source):
        return bundled_mesh_path(source)
    return Path(source)


def read_axes_file(path) -> list:
    """A hierarchy of axes from a small TOML file: ``[[axis]]`` tables with
    ``part``, ``parent`` (none for the root, the first) and ``axis`` (a frame:
    ``"auto"``, ``"x"``, ``"y"``, ``"z"``, ``"oriented"`` or three rows of three
    numbers); or ``[[branch]]`` tables (``name``, ``parent``, ``points``: a skeleton's branches,
    :func:`write_axes_file`).  Returns what :meth:`BaseMesh.with_axes` takes; a file that is
    not one is a :class:`MeshError` naming the file and the entry."""
    import tomllib

    path = Path(path)
    data = read_regular(path, 1 << 20, "an axes file (.toml)", MeshError)
    try:
        doc = tomllib.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise MeshError(f"{path}: not a TOML axes file: {exc}") from None
    if set(doc) == {"branch"} and isinstance(doc["branch"], list):  # the branches of a skeleton (write_axes_file)
        return {"branches": doc["branch"]}
    entries = doc.get("axis")
    if set(doc) != {"axis"} or not isinstance(entries, list) or not entries:
        raise MeshError(f"{path}: expected [[axis]] tables (part, parent, axis) or [[branch]] tables (name, parent, "
                        "points) and nothing else, found keys "
                        f"{', '.join(doc) or 'none'}")
    out = []
    for i, entry in enumerate(entries, 1):
        extra = set(entry) - {"part", "parent", "axis", "anchor"}
        if extra or not isinstance(entry.get("part"), str):
            raise MeshError(f"{path}: axis {i}: expected a table with a part name, an optional parent, axis and anchor, "
                            f"found {', '.join(sorted(entry))}")
        if "axis" in entry and not isinstance(entry["axis"], str):
            try:
                entry = {**entry, "axis": np.asarray(entry["axis"], dtype=np.float64)}
            except (TypeError, ValueError):
                raise MeshError(f"{path}: axis {i} ({entry['part']}): axis: expected a frame name or nine numbers "
                                f"(three rows), found {entry['axis']!r:.80}") from None
        out.append(entry)
    return out


def write_axes_file(path, branches, mesh_name: str = "") -> Path:
    """The branches of a skeleton (:func:`~axialdeform.core.skeleton.skeleton_branches`) as an axes file
    of ``[[branch]]`` tables, to edit by hand and load again (``axes="FILE.toml"``); written atomically."""
    lines = [f"# the axes of {mesh_name or 'a mesh'} from its own shape (axialdeform info MESH --axes skeleton "
             "--save-axes):", "# one [[branch]] a branch, its points from where it leaves its parent to its tip. "
             "Move a point,", "# leave a branch out (its vertices go to the branches near them), then load it: "
             "--axes THIS.toml", ""]
    for b in branches:
        lines.append("[[branch]]")
        lines.append(f'name = {json.dumps(str(b["name"]))}')  # a TOML basic string is a JSON string
        if b.get("parent") is not None:
            lines.append(f'parent = {json.dumps(str(b["parent"]))}')
        pts = ", ".join("[" + ", ".join(repr(float(x)) for x in p) + "]" for p in np.asarray(b["points"], dtype=np.float64))
        lines += [f"points = [{pts}]", ""]
    path = Path(path)
    atomic_write_text(path, "\n".join(lines))
    return path


def axes_argument(value):
    """``axes=`` as a user gives it: None, a rule (``"parts"``, ``"skeleton"``, ``"auto"``), a path to a TOML
    axes file (:func:`read_axes_file`), or what :meth:`BaseMesh.with_axes` takes."""
    if isinstance(value, (str, os.PathLike)) and str(value) not in AXES_RULES:
        return read_axes_file(value)
    return value


def with_axes(mesh: BaseMesh, axes, axis="auto") -> BaseMesh:
    """``mesh.with_axes`` of ``axes`` as a user gives it (:func:`axes_argument`); what is wrong with
    an axes file's entries names the file."""
    spec = axes_argument(axes)
    try:
        return mesh.with_axes(spec, axis)
    except AxialDeformError as exc:
        if spec is axes or str(axes) in str(exc):
            raise
        raise type(exc)(f"{axes}: {exc}") from None


def load_mesh(source, *, textures: bool = True, axis="auto", axes=None, parts=None) -> BaseMesh:
    """Read a base mesh.

    Parameters
    ----------
    source : str, PathLike, trimesh.Trimesh or trimesh.Scene
        A file (OBJ, PLY, STL, OFF, glTF/GLB), a bundled mesh by name (``"stone"``, ``"leaf"``,
        ``"leafcard"``, ``"tree"``), or a mesh already in memory (a scene of one mesh).
    textures : bool
        False decodes no texture (for work that neither draws nor writes one: making parameters,
        fitting, scattering); the parts keep their names and base colours, and the positions,
        vertex order and fingerprint are those of the same file loaded with its textures.
    axis : str or (3, 3) float
        The axis frame (``docs/method.md``, "A chosen axis frame"): ``"auto"`` (the longest
        axis-aligned extent), ``"x"``, ``"y"``, ``"z"`` (forced), ``"oriented"`` (the
        minimum-volume oriented bounding box, for a model lying diagonally) or a 3×3 orthogonal
        matrix whose rows are ``e_a, e_u, e_v``.
    axes : optional
        Several axes in a hierarchy (a tree's trunk and branches): ``"skeleton"`` (from the model's
        own shape), ``"parts"`` (one axis per part), ``"auto"`` (whichever fits), a list of
        ``{"part", "parent", "axis"}``, a TOML file of them (:func:`read_axes_file`) or per-vertex
        axes (:meth:`BaseMesh.with_axes`); ``axis`` is then the frame rule of each axis that names
        none.
    parts : list of str, optional
        Keep only these parts (:meth:`BaseMesh.with_parts`): a file's scenery left out before the
        axis, the axes and everything after are made.

    Returns
    -------
    BaseMesh
        A file with several meshes (glTF nodes/primitives, STL bodies, OBJ ``o`` objects or
        ``usemtl`` groups) becomes ONE base mesh with several :attr:`BaseMesh.parts` (node
        transforms applied, the file's vertex order kept); UVs, vertex colours and materials come
        along (:mod:`axialdeform.core.material`).  ``source_index`` maps each vertex to the file's
        own vertex order (``docs/parameter-files.md``, "Vertex order").

    Notes
    -----
    Raises :class:`MeshError` (naming the file) for a missing or unreadable file, no faces,
    non-finite coordinates, UVs or colours whose count does not match the vertices, or a longest
    extent of zero.  A texture that cannot be read is an
    :class:`~axialdeform.core.material.AssetWarning`.
    """
    with texture_decoding(textures):
        mesh = _load_mesh(source)
    if parts is not None:
        mesh = mesh.with_parts(parts)
    if axes is not None:
        return with_axes(mesh, axes, axis)
    return mesh.with_axis(axis) if not (isinstance(axis, str) and axis == "auto") else mesh


def _load_mesh(source) -> BaseMesh:
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
        near = difflib.get_close_matches(str(source), BUNDLED_MESHES, n=1, cutoff=0.6) if not path.suffix else []
        hint = (f"; did you mean the bundled mesh {near[0]!r}? (bundled: {', '.join(BUNDLED_MESHES)})" if near else
                f"; expected a mesh file or a bundled mesh ({', '.join(BUNDLED_MESHES)})" if not path.suffix else "")
        raise MeshError(f"{name}: no such mesh file{hint}")
    if path.is_dir():
        raise MeshError(f"{name}: is a folder; expected a mesh file ({', '.join(MESH_SUFFIXES)})")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise MeshError(f"{name}: unsupported mesh file type {path.suffix!r}; expected one of {', '.join(MESH_SUFFIXES)}")

    # a regular file (never a FIFO or a device), read with a bound; every
    # file it refers to goes through the same check (SafeResolver)
    data = read_regular(path, max(safeio.memory_available() // 2, 1 << 20), f"a mesh file ({', '.join(MESH_SUFFIXES)})",
                        MeshError)
    kind = path.suffix.lower().lstrip(".")
    # each file a glTF refers to is read with the bound it declares (a buffer's byteLength)
    declared, rest = {}, []
    if kind in ("gltf", "glb"):
        tree = gltf_json(data, kind, name)  # read once; a file that is not glTF is said here, in words
        declared = gltf_references(tree, name)
        rest = unsupported_features(tree)
        del tree
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
        raise MeshError(f"{name}: could not read the mesh file: {error_in_words(exc, kind)}") from None
    file_positions = _obj_positions(data) if path.suffix.lower() == ".obj" else None  # the bytes read above
    dropped = gltf_attributes(data, kind, SafeResolver(path.parent)) if kind in ("glb", "gltf") else []
    del data
    mesh = _from_loaded(loaded, name, file_positions, resolver.failed, dropped)
    if rest:  # said once, in our words (trimesh drops them silently), and only of a mesh that loads
        warnings.warn(AssetWarning(f"{name}: {', '.join(rest)} are not supported; the mesh is drawn in its rest "
                                   "pose"), stacklevel=3)
    # every file the mesh was made from (its own, a material library, textures, buffers)
    return dataclasses.replace(mesh, sources=(str(path), *dict.fromkeys(resolver.read)))


def _refuse(name: str, resolver, declared: dict) -> None:
    """Raise :class:`MeshError` for the first file the resolver refused that is not a picture."""
    refused = [msg for ref, msg in resolver.refused
               if not (_is_image_name(ref) or declared.get(ref, ("", 0))[1] is None)]
    if refused:
        raise MeshError(f"{name}: {refused[0]}")


def _is_image_name(name: str) -> bool:
    """True for a referenced file that is a picture (a texture), by its suffix."""

    return is_image_name(name)


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
        check_float32_range(positions, name)
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
        check_float32_range(positions, name)  # a node transform can push a coordinate out of range
    source_index, source_count = _source_index(np.concatenate(raw_positions), file_positions)
    file_normals = np.concatenate(all_normals)
    has_file_normals = bool(np.isfinite(file_normals).all(axis=1).any())
    if has_file_normals:
        length = np.linalg.norm(file_normals, axis=1)
        usable = np.isfinite(length) & (length > 1e-12)
        computed = area_weighted_normals(positions, faces) if not usable.all() else None
        normals = np.where(usable[:, None], file_normals / np.where(usable, length, 1.0)[:, None],
                           computed if computed is not None else 0.0)
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
    firsts = [np.asarray(split.geometry[split.graph[n][1]].vertices) for n in nodes]
    # where each object's first vertex occurs in the merged mesh: one sort of every row (not a scan an object)
    heads = np.array([g[0] if len(g) else np.full(3, np.nan) for g in firsts], dtype=verts.dtype).reshape(-1, 3)
    _, ids = np.unique(np.concatenate([verts, heads]) + 0.0, axis=0, return_inverse=True)
    ids = ids.ravel()
    vid, hid = ids[:len(verts)], ids[len(verts):]
    order = np.argsort(vid, kind="stable")
    sorted_ids = vid[order]
    lo, hi = np.searchsorted(sorted_ids, hid, "left"), np.searchsorted(sorted_ids, hid, "right")

    def first_index(k):
        gv = firsts[k]
        if not len(gv):
            return -1
        for o in order[lo[k]:hi[k]]:  # where its vertices sit in the merged mesh
            if o + len(gv) <= len(verts) and np.array_equal(verts[o:o + len(gv)], gv):
                return int(o)
        return -1

    place = [first_index(k) for k in range(len(nodes))]
    nodes = [nodes[k] for k in sorted(range(len(nodes)), key=place.__getitem__)]
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

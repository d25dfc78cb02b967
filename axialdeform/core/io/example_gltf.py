"""glTF scenes as examples to learn scenery from (``axialdeform learn``, docs/learn.md "What it reads"): every
placed object of a scene -- the instances of each ``EXT_mesh_gpu_instancing`` node, their TRS under the
node's world matrix, and every other node that has a mesh, as editors export a hand-placed patch --, its
place, size, turn and up, its kind from its node's name, and this library's records where every node carries
them.  A node whose mesh spans a large part of the scene and is no taller than it is wide is the ground the
objects stand on, not one of them (:func:`ground_nodes`): left out, its footprint the example's default
window.  :mod:`~axialdeform.core.io.example` reads the other examples and writes what was learned.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import trimesh

from ..bounds import box_corners
from ..errors import AxialDeformError, ExampleError
from ..marks import standard_records, turn_and_up
from ..record import join_record
from ..transforms import matrices_from_quaternions
from .glb import INSTANCING, load_glb, read_accessor
from .gltf_read import child_offsets, instance_columns, instance_records

__all__ = ["glb_objects", "gltf_objects", "ground_nodes", "GROUND_SHARE"]

#: a node whose mesh covers at least this share of the scene's footprint (and is no taller than it is wide) is
#: the ground, not an object on it
GROUND_SHARE = 0.25


def _trs(t, r, s) -> np.ndarray:
    """(n, 4, 4) matrices (column vectors) of translations (n, 3), quaternions (n, 4, xyzw) and scales (n, 3)."""
    m = np.zeros((len(t), 4, 4))
    m[:, :3, :3] = matrices_from_quaternions(r) * np.asarray(s, np.float64)[:, None, :]
    m[:, :3, 3], m[:, 3, 3] = t, 1.0
    return m


def _node_matrix(node) -> np.ndarray:
    if node.matrix is not None and len(node.matrix) == 16:
        return np.asarray(node.matrix, np.float64).reshape(4, 4).T  # glTF stores it column after column
    return _trs([node.translation or (0, 0, 0)], [node.rotation or (0, 0, 0, 1)], [node.scale or (1, 1, 1)])[0]


def glb_objects(path: Path, vertices: bool = False) -> dict:
    """Every placed object of a GLB: the instances of each ``EXT_mesh_gpu_instancing`` node (their TRS composed
    with the node's world matrix) and every other node that has a mesh (its world matrix), less the ground
    (:func:`ground_nodes`): a dict of ``xz``, ``size``, ``yaw``, ``up``, ``kind``, ``records``, ``ground`` (its
    footprint or None) and, with ``vertices``, each object's world ``vertices`` and node ``names``."""
    gltf = load_glb(path)
    try:
        return _placed_in(gltf, str(path), vertices)
    except (TypeError, ValueError, IndexError, KeyError, AttributeError) as exc:  # a hostile file's odd JSON
        if isinstance(exc, AxialDeformError):  # already in words: the file, the node, the field
            raise
        raise ExampleError(f"{path}: not a glTF scene of placed objects this reader understands ({type(exc).__name__}: "
                           f"{str(exc)[:80]})") from None


def _placed_in(gltf, where: str, vertices: bool = False) -> dict:
    blob = gltf.binary_blob() or b""
    world, mats, names, records, shapes, boxes = {}, [], [], [], [], []
    roots = gltf.scenes[gltf.scene or 0].nodes if gltf.scenes else range(len(gltf.nodes))
    stack = [(int(i), np.eye(4)) for i in reversed(roots or ())]
    while stack:  # the node tree, parents first, in the file's order (a node seen twice is a cycle: refused)
        i, parent = stack.pop()
        if not 0 <= i < len(gltf.nodes) or i in world:
            raise ExampleError(f"{where}: node {i}: expected each node once in the scene's tree")
        node = gltf.nodes[i]
        world[i] = m = parent @ _node_matrix(node)
        stack += [(int(c), m) for c in reversed(node.children or ())]
        inst = (node.extensions or {}).get("EXT_mesh_gpu_instancing")
        if node.mesh is None:
            continue
        if isinstance(inst, dict) and isinstance(inst.get("attributes"), dict):
            attrs, at = inst["attributes"], f"{where}: node {node.name or i}"
            ours = all(k in attrs for k in ("_AXIAL_D12", "_AXIAL_D34", "_AXIAL_D5"))  # this library's records
            if ours:  # every attribute read once, the instances' places among them
                read, n = instance_columns(gltf, blob, attrs, at)
            else:
                read = {k: read_accessor(gltf, blob, attrs[k], k, at) for k in ("TRANSLATION", "ROTATION", "SCALE") if k in attrs}
                n = max((len(v) for v in read.values()), default=0)
            t = read.get("TRANSLATION", np.zeros((n, 3)))
            r = read.get("ROTATION", np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)))
            sc = read.get("SCALE", np.ones((n, 3)))
            if not (len(t) == len(r) == len(sc) == n):
                raise ExampleError(f"{at}: EXT_mesh_gpu_instancing: expected its attributes to have one value an instance each")
            mats.append(m[None] @ _trs(t, r, sc))
            records.append(_records_of(read, n, at) if ours else None)
            shapes += [None] * n
            boxes.append(np.repeat(mats[-1][:, None, :3, 3], 2, axis=1))  # an instance is never the ground
        else:
            mats.append(m[None])
            records.append(None)
            boxes.append(_mesh_box(gltf, blob, node, m, f"{where}: node {node.name or i}")[None])
            if vertices:  # its own geometry in the world, to fit (one node an object)
                shapes.append(_world_vertices(gltf, blob, node, m, f"{where}: node {node.name or i}"))
        mesh = gltf.meshes[node.mesh] if isinstance(node.mesh, int) and 0 <= node.mesh < len(gltf.meshes) else None
        names += [node.name or (mesh.name if mesh is not None else None) or f"mesh{node.mesh}"] * len(mats[-1])
    if not mats:
        raise ExampleError(f"{where}: no placed objects; expected EXT_mesh_gpu_instancing nodes or nodes with a mesh")
    box = np.concatenate(boxes)
    ground = ground_nodes(box)
    if ground.all():
        raise ExampleError(f"{where}: {_all_ground(names)}")
    if ground.any():  # the ground is a node of its own (an instance is a point, never the ground): its group left out
        keep = ~ground[np.cumsum([0] + [len(g) for g in mats[:-1]])]
        mats, records = [g for g, c in zip(mats, keep) if c], [r for r, c in zip(records, keep) if c]
        names, shapes = [v for v, g in zip(names, ground) if not g], [v for v, g in zip(shapes, ground) if not g]
    rec = None
    if all(r is not None for r in records):  # every object has its record: its marks are learned too
        if len({r.shape[1] for r in records}) > 1:  # nodes of other widths: axis 0's records, as far as all have them
            records = [standard_records(r) for r in records]
        width = min(r.shape[1] for r in records)
        rec = np.concatenate([r[:, :width] for r in records])
    out = {**_placed(np.concatenate(mats)), "kind": _kinds(names), "records": rec, "ground": _footprint(box[ground])}
    return {**out, "vertices": shapes, "names": names} if vertices else out


def _mesh_box(gltf, blob, node, m: np.ndarray, where: str) -> np.ndarray:
    """The world box (2, 3) (lo, hi) of a node's mesh under its world matrix ``m``: its POSITION accessors' min
    and max (the vertices read where a file leaves them out), the box's eight corners moved; NaN without any."""
    lo, hi = [], []
    for prim in gltf.meshes[node.mesh].primitives or ():
        a = getattr(prim.attributes, "POSITION", None)
        acc = gltf.accessors[a] if isinstance(a, int) and 0 <= a < len(gltf.accessors) else None
        if acc is not None and acc.min is not None and acc.max is not None and len(acc.min) == len(acc.max) == 3:
            lo.append(acc.min)
            hi.append(acc.max)
        elif a is not None:
            v = read_accessor(gltf, blob, a, "POSITION", where)
            if len(v):
                lo.append(v.min(axis=0))
                hi.append(v.max(axis=0))
    if not lo:
        return np.full((2, 3), np.nan)
    return _moved_box(np.min(np.asarray(lo, np.float64), axis=0), np.max(np.asarray(hi, np.float64), axis=0), m)


def _moved_box(lo: np.ndarray, hi: np.ndarray, m: np.ndarray) -> np.ndarray:
    """The world box (2, 3) of the box ``lo``, ``hi`` (3,) moved by the matrix ``m`` (4, 4): its eight corners'."""
    w = box_corners(lo, hi) @ m[:3, :3].T + m[:3, 3]
    return np.stack([w.min(axis=0), w.max(axis=0)])


def _geometry_box(geometry, m: np.ndarray) -> np.ndarray:
    """The world box (2, 3) of a trimesh geometry under ``m``; NaN where it has no finite bounds (an empty one)."""
    b = getattr(geometry, "bounds", None)
    try:
        b = np.asarray(b, np.float64)
    except (TypeError, ValueError):
        return np.full((2, 3), np.nan)
    return _moved_box(b[0], b[1], m) if b.shape == (2, 3) and np.isfinite(b).all() else np.full((2, 3), np.nan)


def ground_nodes(boxes: np.ndarray) -> np.ndarray:
    """Which placed objects are the ground they stand on, (n,) bool, of their world boxes ``boxes`` (n, 2, 3)
    (lo, hi; an instance's a point, NaN where unknown): a box that covers at least :data:`GROUND_SHARE` of the
    footprint of them all (x and z) and is no taller than it is wide -- an editor's terrain exported beside the
    objects on it."""
    b = np.asarray(boxes, np.float64)
    known = np.isfinite(b).all(axis=(1, 2))
    if not known.any():
        return known
    lo, hi = b[known, 0][:, [0, 2]].min(axis=0), b[known, 1][:, [0, 2]].max(axis=0)
    area = float(np.prod(hi - lo))
    size = np.where(known[:, None], b[:, 1] - b[:, 0], 0.0)
    return known & (area > 0) & (size[:, 0] * size[:, 2] >= GROUND_SHARE * area) & (size[:, 1] <= size[:, [0, 2]].max(axis=1))


def _all_ground(names: list) -> str:
    """The words of a scene whose every node is ground (:func:`ground_nodes`)."""
    shown = ", ".join(dict.fromkeys(str(n) for n in names[:3])) + (", ..." if len(names) > 3 else "")
    return (f"no placed objects beside the ground: every node ({shown}) covers a quarter of the scene or more; "
            "expected objects standing on it (one node an object, or instances)")


def _footprint(boxes: np.ndarray) -> tuple | None:
    """The ground's footprint (x0, z0, x1, z1) of the boxes (k, 2, 3) of its nodes; None without any."""
    if not len(boxes):
        return None
    return (float(boxes[:, 0, 0].min()), float(boxes[:, 0, 2].min()), float(boxes[:, 1, 0].max()), float(boxes[:, 1, 2].max()))


def _world_vertices(gltf, blob, node, m: np.ndarray, where: str) -> np.ndarray:
    """A node's mesh's vertices (each POSITION accessor once, in the order its primitives first name them: a
    part's primitives may share one) under the node's world matrix ``m``: (v, 3)."""
    mesh = gltf.meshes[node.mesh]
    seen, parts = [], []
    for prim in mesh.primitives or ():
        a = getattr(prim.attributes, "POSITION", None)
        if a is not None and a not in seen:
            seen.append(a)
            parts.append(read_accessor(gltf, blob, a, "POSITION", where))
    if not parts:
        raise ExampleError(f"{where}: mesh {node.mesh}: expected POSITION to fit it, found none")
    v = np.concatenate(parts).astype(np.float64) @ m[:3, :3].T + m[:3, 3]
    if not np.isfinite(v).all():
        raise ExampleError(f"{where}: mesh {node.mesh}: POSITION: expected finite vertices (under the node's matrix)")
    return v


def _records_of(cols: dict, n: int, where: str) -> np.ndarray:
    """The records of an instancing node's ``n`` instances written by this library, of its attributes ``cols``
    (:func:`~axialdeform.core.io.gltf_read.instance_columns`: ``_AXIAL_D12``, ``_AXIAL_D34``, ``_AXIAL_D5``, and
    ``_AXIAL_TWIST_TAPER``, ``_COLOR_0``, a tree's child axes' ``_AXIAL_A{k}_*`` where written)."""
    rec = instance_records(cols, n, where).astype(np.float64)
    axes = 1 + sum(1 for name in cols if re.fullmatch(r"_AXIAL_A[1-9][0-9]*_D12", str(name)))
    if axes > 1:  # a tree's child axes, between axis 0's offsets and its position
        rec = join_record(rec, child_offsets(cols, n, axes, where).reshape(n, axes - 1, 5, 2)).astype(np.float64)
    if not np.isfinite(rec).all():
        raise ExampleError(f"{where}: {INSTANCING}: expected finite records, found a value that is not")
    return rec


def _kinds(names: list) -> np.ndarray | None:
    """Each object's kind from its node's name as editors write duplicates (``Pine.003``, ``rock_12``: the
    name less a trailing number); None when every object is of one kind."""
    kinds = np.array([re.sub(r"[._\- ]*\d+$", "", str(n)) or str(n) for n in names], dtype=object)
    return kinds if len(set(kinds)) > 1 else None


def _placed(m: np.ndarray) -> dict:
    """Where objects of world matrices ``m`` (n, 4, 4) stand, their size (the mean scale), their turn about up
    and their up (:func:`~axialdeform.core.marks.turn_and_up`)."""
    s = np.linalg.norm(m[:, :3, :3], axis=1)  # each column's length: the scale along x, y, z
    yaw, up = turn_and_up(m[:, :3, :3])
    return {"xz": m[:, [0, 2], 3], "size": s.mean(axis=1), "yaw": yaw, "up": up}


def gltf_objects(path: Path) -> dict:
    """A text glTF (``.gltf``): one object a node that has a mesh, through trimesh's scene graph, less the
    ground (:func:`ground_nodes`)."""
    try:
        scene = trimesh.load(str(path), force="scene")
    except Exception as exc:  # noqa: BLE001 - any reader failure on a hostile file
        raise ExampleError(f"{path}: could not read the glTF scene ({type(exc).__name__}: {exc})") from None
    nodes = list(scene.graph.nodes_geometry)
    placed = [scene.graph.get(node) for node in nodes]
    mats = [np.asarray(m, np.float64) for m, _ in placed]
    if not mats:
        raise ExampleError(f"{path}: no placed objects; expected nodes with a mesh")
    box = np.stack([_geometry_box(scene.geometry.get(g), m) for m, (_, g) in zip(mats, placed)])
    ground = ground_nodes(box)
    if ground.all():
        raise ExampleError(f"{path}: {_all_ground(nodes)}")
    keep = ~ground
    return {**_placed(np.stack(mats)[keep]), "kind": _kinds([n for n, k in zip(nodes, keep) if k]),
            "ground": _footprint(box[ground])}

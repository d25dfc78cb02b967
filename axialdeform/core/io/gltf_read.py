"""Reading an instanced GLB back: the instances of an ``EXT_mesh_gpu_instancing`` node with their
bend (``AXIALDEFORM_bend``, and this library's ``extras``), and the ``extras`` of a file."""

from __future__ import annotations

import dataclasses
import io
import json
import math
import os
import re
from pathlib import Path

import numpy as np
from PIL import Image

from ..axis import PERPENDICULAR, ControlAxis, axis_frame_matrix
from ..errors import AxialDeformError, GltfError, MeshMismatchError
from ..material import DEFAULT_MATERIAL, Material, Part
from ..mesh import BaseMesh, area_weighted_normals
from ..params import as_params
from ..record import (
    ANGLES,
    GLTF_INSTANCE_TYPES,
    GLTF_TINT_ATTRIBUTE,
    MAX_RECORD_AXES,
    POSITION,
    SCALE,
    WIDTHS,
    is_record_width,
    join_record,
    tree_shape,
)
from ..transforms import (
    angles_from_matrices,
    matrices_from_quaternions,
)
from .glb import (
    ATTRIBUTES,
    AXIS_ATTRIBUTE,
    BEND_EXTENSION,
    COMPONENTS,
    EXTENDED_ATTRIBUTES,
    EXTRAS_KEY,
    INSTANCING,
    TRIANGLES,
    child_columns,
    load_glb,
    read_accessor,
)

__all__ = ["read_instanced_glb", "read_extras", "instance_columns", "instance_records", "child_offsets"]


def read_instanced_glb(path: str | os.PathLike, node: str | None = None, *, fallback: bool = False):
    """Read a GLB written by :func:`export_instanced` back (or, with ``node``,
    the instanced node of that name: a layer of :func:`export_scene`'s
    instanced layout).

    Returns
    -------
    mesh : BaseMesh
        The base mesh (positions, normals, triangles exactly as written).
    params : (n, 16) float32, or (n, 19) for extended instances, (n, 22) for tinted ones
        The numbers per instance, bit for bit as exported: offsets from
        ``_AXIAL_D12/_AXIAL_D34/_AXIAL_D5``, position from ``TRANSLATION``,
        angles from ``_AXIAL_ANGLES`` (or, if a file lacks it, from the
        ``ROTATION`` quaternion: same rotation, angles possibly different).

    A node in the generated form (``AXIALDEFORM_bend`` ``generate``: a generated layer written as its
    recipe) is a :class:`GltfError` saying so -- its instances are the recipe's, read it with
    :func:`~axialdeform.core.io.gltf_generate.read_generated_glb` -- unless ``fallback`` asks for the
    small plain fallback it also carries.

    Raises :class:`GltfError` for a file without an instanced node, and
    :class:`MeshMismatchError` if the recorded fingerprint does not match
    the base mesh in the file.
    """
    path = Path(path)
    where = str(path)
    gltf = load_glb(path)
    blob = gltf.binary_blob() or b""
    nodes = [nd for nd in gltf.nodes if (nd.extensions or {}).get(INSTANCING) and nd.mesh is not None]
    if node is not None:
        named = [nd for nd in nodes if nd.name == node]
        if len(named) != 1:
            raise GltfError(f"{where}: expected one node {node!r} with {INSTANCING}, found {len(named)}; "
                            f"the instanced nodes are {', '.join(repr(nd.name) for nd in nodes) or 'none'}")
        nodes = named
    if len(nodes) != 1:
        raise GltfError(f"{where}: expected exactly one node with {INSTANCING}, found {len(nodes)}"
                        + (f" ({', '.join(repr(nd.name) for nd in nodes)}: name one with node=)" if nodes else ""))
    node = nodes[0]
    gen = ((node.extensions or {}).get(BEND_EXTENSION) or {}).get("generate") if isinstance(
        (node.extensions or {}).get(BEND_EXTENSION), dict) else None
    if gen is not None and not fallback:
        raise GltfError(f"{where}: node {node.name or '0'} is a generated layer ({BEND_EXTENSION} generate): its instances "
                        "are made from its recipe, not listed; read it with read_generated_glb, or its small "
                        "fallback with fallback=True (export --instanced writes the instances)")
    attrs = node.extensions[INSTANCING].get("attributes", {})
    missing = [k for k in ("_AXIAL_D12", "_AXIAL_D34", "_AXIAL_D5") if k not in attrs]
    if missing or ("_AXIAL_ANGLES" not in attrs and "ROTATION" not in attrs):
        raise GltfError(f"{where}: {INSTANCING} attributes: expected {', '.join(ATTRIBUTES)} (TRANSLATION optional); "
                        f"missing {', '.join(missing) or '_AXIAL_ANGLES'}")
    cols, n = instance_columns(gltf, blob, attrs, where)
    params = instance_records(cols, n, where)
    mesh_def = gltf.meshes[node.mesh]
    if not mesh_def.primitives:
        raise GltfError(f"{where}: mesh {node.mesh}: expected at least one primitive, found none")
    prim = mesh_def.primitives[0]
    for other in mesh_def.primitives:  # one primitive per part, all over the same vertices
        if other.mode not in (None, TRIANGLES) or other.indices is None:
            raise GltfError(f"{where}: mesh {node.mesh}: expected indexed triangles (mode 4)")
        if other.attributes.POSITION != prim.attributes.POSITION:
            raise GltfError(f"{where}: mesh {node.mesh}: expected every primitive to share one POSITION accessor")
    positions = read_accessor(gltf, blob, prim.attributes.POSITION, "POSITION", where)
    faces = np.concatenate([read_accessor(gltf, blob, q.indices, "indices", where).reshape(-1, 3)
                            for q in mesh_def.primitives])
    if prim.attributes.NORMAL is not None:
        normals = read_accessor(gltf, blob, prim.attributes.NORMAL, "NORMAL", where)
        from_file = True
    else:

        normals, from_file = area_weighted_normals(positions, faces), False
    uvs, colors, parts = _appearance(gltf, blob, mesh_def, where)
    mesh = BaseMesh(positions, normals, faces, name=where, normals_from_file=from_file, uvs=uvs, colors=colors,
                    parts=parts)
    extras = (node.extras or {}).get(EXTRAS_KEY, {})
    if not isinstance(extras, dict):
        extras = {}
    ext = (node.extensions or {}).get(BEND_EXTENSION)
    if ext is not None:  # the open extension is the record; this library's extras at most a cache
        return _read_bend(gltf, blob, prim, ext, extras, cols, mesh, params, f"{where}: node {node.name or '0'} "
                          f"{BEND_EXTENSION}")
    recorded = extras.get("mesh_fingerprint")
    if recorded is not None and not isinstance(recorded, str):
        raise GltfError(f"{where}: extras mesh_fingerprint: expected a hex string, found {recorded!r:.40}")
    if recorded is not None and recorded != mesh.fingerprint.hex():
        raise MeshMismatchError(f"{where}: extras mesh_fingerprint {recorded[:16]} does not match the base mesh in the "
                                f"file ({mesh.fingerprint.hex()[:16]}); the file was altered")
    recorded_axis = extras.get("axis")
    if isinstance(recorded_axis, dict):  # the frame the file was made with (an axis the auto rule would not pick)
        frame = recorded_axis.get("frame") if recorded_axis.get("index") == -1 else \
            dict(enumerate("xyz")).get(recorded_axis.get("index"))
        if frame is None:
            raise GltfError(f"{where}: extras axis: expected index 0, 1, 2 or -1 with a frame (3 rows of 3 numbers), "
                            f"found {recorded_axis!r}")
        try:
            mesh = mesh.with_axis(frame)
        except AxialDeformError as exc:
            raise GltfError(f"{where}: extras axis: {exc}") from None
    if "axes" in extras:  # several axes: the tree, each vertex's axis, every child axis's offsets
        mesh, params = _read_tree(gltf, blob, prim, extras["axes"], cols, mesh, params, where)
        return mesh, params
    return mesh, as_params(params, name=where)


def _appearance(gltf, blob, mesh_def, where: str):
    """``(uvs, colors, parts)`` of an instanced node's mesh: TEXCOORD_0 and COLOR_0 of its vertices (or None),
    and each primitive as a part (in order: the faces are the primitives' indices one after another) with
    its material's base colour, texture, alpha mode and sides -- what the writer's ``appearance`` wrote."""
    prim = mesh_def.primitives[0]
    uvs = colors = None
    if prim.attributes.TEXCOORD_0 is not None:
        uv = read_accessor(gltf, blob, prim.attributes.TEXCOORD_0, "TEXCOORD_0", where).astype(np.float32)
        uvs = np.column_stack([uv[:, 0], 1.0 - uv[:, 1]]).astype(np.float32)  # BaseMesh's: v = 0 at the bottom
    if prim.attributes.COLOR_0 is not None:
        c = read_accessor(gltf, blob, prim.attributes.COLOR_0, "COLOR_0", where).astype(np.float32)
        colors = np.concatenate([c, np.ones((len(c), 1), np.float32)], axis=1) if c.shape[1] == 3 else c
    parts, start = [], 0
    for i, q in enumerate(mesh_def.primitives):
        count = int(gltf.accessors[q.indices].count) // 3
        material = _material(gltf, blob, q.material, f"{where}: mesh primitive {i}") if q.material is not None \
            else DEFAULT_MATERIAL
        name = material.name if q.material is not None and material.name not in {p.name for p in parts} else f"part{i}"
        parts.append(Part(name, start, count, material))
        start += count
    return uvs, colors, tuple(parts)


def _material(gltf, blob, index, where: str) -> Material:
    """The glTF material ``index`` as this library's :class:`Material` (a texture embedded in the GLB decoded)."""
    if not isinstance(index, int) or not 0 <= index < len(gltf.materials):
        raise GltfError(f"{where}: material: expected a material index, found {index!r}")
    m = gltf.materials[index]
    pbr = m.pbrMetallicRoughness
    base = pbr.baseColorFactor if pbr is not None and pbr.baseColorFactor is not None else [1.0, 1.0, 1.0, 1.0]
    texture, sources = None, {}
    info = pbr.baseColorTexture if pbr is not None else None
    if info is not None:
        try:
            view = gltf.bufferViews[gltf.images[gltf.textures[info.index].source].bufferView]
            data = blob[(view.byteOffset or 0):(view.byteOffset or 0) + view.byteLength]
            with Image.open(io.BytesIO(data)) as img:
                texture = np.asarray(img.convert("RGBA"), dtype=np.uint8)
            sources["texture"] = (bytes(data), gltf.images[gltf.textures[info.index].source].mimeType or "image/png")
        except (IndexError, TypeError, AttributeError, OSError, ValueError):
            raise GltfError(f"{where}: material {index} baseColorTexture: expected an image embedded in the GLB") from None
    try:
        return Material(name=m.name or f"material{index}", base_color=base, texture=texture,
                        texture_name="embedded" if texture is not None else None, alpha_mode=m.alphaMode or "OPAQUE",
                        alpha_cutoff=0.5 if m.alphaCutoff is None else float(m.alphaCutoff),
                        double_sided=bool(m.doubleSided), sources=sources)
    except AxialDeformError as exc:
        raise GltfError(f"{where}: material {index}: {exc}") from None


def instance_columns(gltf, blob, attrs: dict, where: str) -> tuple[dict, int]:
    """Every instance attribute of an ``EXT_mesh_gpu_instancing`` node read (``attrs``: its accessors by name),
    each known one's type checked (:data:`~axialdeform.core.record.GLTF_INSTANCE_TYPES`), one count for all:
    ``(columns by name, count)``."""
    children = [name for name in attrs if str(name).startswith("_AXIAL_A") and str(name)[8:9].isdigit()]
    if len(attrs) > 16 + 3 * MAX_RECORD_AXES or len(children) > 3 * (MAX_RECORD_AXES - 1):  # before reading any
        raise GltfError(f"{where}: {INSTANCING} attributes: {len(attrs)} of them ({len(children)} of child axes); "
                        f"expected at most {MAX_RECORD_AXES} axes' worth")
    cols = {name: read_accessor(gltf, blob, attrs[name], name, where) for name in attrs}
    for name, col in cols.items():  # each attribute's type, as docs/gltf/AXIALDEFORM_bend says (the npm plugin too)
        kind = _attribute_type(str(name))
        if kind is not None and col.shape[1] != COMPONENTS[kind]:
            raise GltfError(f"{where}: {name}: expected {kind}, found {col.shape[1]} components")
    counts = {len(v) for v in cols.values()}
    if len(counts) != 1:
        raise GltfError(f"{where}: {INSTANCING} attributes have different counts {sorted(counts)}; expected one count")
    return cols, counts.pop()


def instance_records(cols: dict, n: int, where: str) -> np.ndarray:
    """Axis 0's records ``(n, 16|19|22)`` float32 of instance attributes ``cols`` (:func:`instance_columns`'s,
    each known one's type checked there):
    the offsets, ``TRANSLATION``, the angles (``_AXIAL_ANGLES``, else from ``ROTATION``), and ``SCALE``,
    ``_AXIAL_TWIST_TAPER``, ``_COLOR_0`` where written."""
    tint_name, tint_kind, tint_cols = GLTF_TINT_ATTRIBUTE
    tinted = tint_name in cols
    extended = tinted or "SCALE" in cols or "_AXIAL_TWIST_TAPER" in cols
    params = np.zeros((n, WIDTHS[2 if tinted else 1 if extended else 0]), dtype=np.float32)
    if extended:
        params[:, SCALE] = 1.0
        for name, (_, idx) in {**EXTENDED_ATTRIBUTES, **({tint_name: (tint_kind, tint_cols)} if tinted else {})}.items():
            if name in cols:
                params[:, list(idx)] = cols[name]
        if "SCALE" in cols:
            sc = cols["SCALE"]
            if sc.shape[1] != 3 or not (sc == sc[:, :1]).all():
                raise GltfError(f"{where}: SCALE: expected a uniform scale (VEC3 with three equal components) per instance")
            params[:, SCALE] = sc[:, 0]
    for name, (_, idx) in ATTRIBUTES.items():
        if name in cols:
            params[:, list(idx)] = cols[name]
    if "TRANSLATION" in cols:  # EXT_mesh_gpu_instancing: absent, the instances sit at the origin
        params[:, POSITION] = cols["TRANSLATION"]
    if "_AXIAL_ANGLES" not in cols and "ROTATION" in cols:
        params[:, ANGLES] = angles_from_matrices(matrices_from_quaternions(cols["ROTATION"]))
    return params


def child_offsets(cols: dict, n: int, k: int, where: str) -> np.ndarray:
    """The child axes' offsets ``(n, k - 1, 10)`` float32 of a mesh of ``k`` axes from instance attributes ``cols``
    (``_AXIAL_A{j}_D12``, ``_D34``, ``_D5``)."""
    children = np.zeros((n, k - 1, 10), dtype=np.float32)
    for j in range(1, k):
        for name, (kind, first) in child_columns(j).items():
            if name not in cols or cols[name].shape[1] != COMPONENTS[kind]:
                raise GltfError(f"{where}: {INSTANCING} attributes: expected {name} ({kind}) for axis {j}")
            children[:, j - 1, first:first + COMPONENTS[kind]] = cols[name]
    return children


def _attribute_type(name: str) -> str | None:
    """An instance attribute's accessor type (:data:`~axialdeform.core.record.GLTF_INSTANCE_TYPES`)."""
    child = re.fullmatch(r"_AXIAL_A[1-9][0-9]*(_D12|_D34|_D5)", name)
    return GLTF_INSTANCE_TYPES.get("_AXIAL" + child.group(1) if child else name)


def _numbers(value, count: int, where: str, positive: bool = False) -> np.ndarray:
    """``count`` finite numbers (> 0 with ``positive``) as float64, else a GltfError naming ``where``."""
    ok = isinstance(value, (list, tuple)) and len(value) == count and all(
        isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and (x > 0 or not positive)
        for x in value)
    if not ok:
        raise GltfError(f"{where}: expected {count} finite{' positive' if positive else ''} number(s), found "
                        f"{value!r:.120}")
    return np.asarray(value, dtype=np.float64)


def _frame(value, where: str) -> np.ndarray:
    rows = value if isinstance(value, (list, tuple)) and len(value) == 3 else None
    if rows is None:
        raise GltfError(f"{where}: expected 3 rows of 3 numbers (e_a, e_u, e_v), found {value!r:.120}")
    f = np.stack([_numbers(r, 3, where) for r in rows])
    try:
        return axis_frame_matrix(f, where)
    except AxialDeformError as exc:
        raise GltfError(str(exc)) from None


def _read_bend(gltf, blob, prim, ext, extras, cols, mesh, params, where):
    """The bend an ``AXIALDEFORM_bend`` object records (docs/gltf/AXIALDEFORM_bend), checked before
    anything is sized by it: the numbers per instance, the control axis (frame, lo, length, the
    axis line), a tree's axes, the fingerprint; the mesh and its instances as the extension says."""
    if not isinstance(ext, dict):
        raise GltfError(f"{where}: expected an object, found {type(ext).__name__}")
    numbers = ext.get("numbersPerInstance")
    if not isinstance(numbers, int) or isinstance(numbers, bool) or not is_record_width(numbers):
        raise GltfError(f"{where}: numbersPerInstance: expected 16, 19 or 22 plus 10 per axis after the first, "
                        f"found {numbers!r:.40}")
    axis = ext.get("axis")
    if not isinstance(axis, dict):
        raise GltfError(f"{where}: axis: expected an object with frame, lo, length and center, found {axis!r:.80}")
    frame = _frame(axis.get("frame"), f"{where}: axis frame")
    lo = float(_numbers([axis.get("lo")], 1, f"{where}: axis lo")[0])
    length = float(_numbers([axis.get("length")], 1, f"{where}: axis length", positive=True)[0])
    center = _numbers(axis.get("center"), 2, f"{where}: axis center")
    fingerprint = ext.get("fingerprint")  # optional; if there, a string (JSON null is not one)
    if "fingerprint" in ext and not (isinstance(fingerprint, str) and re.fullmatch(r"[0-9a-f]{64}", fingerprint)):
        raise GltfError(f"{where}: fingerprint: expected 64 lower-case hex digits (SHA-256), found {fingerprint!r:.80}")
    if fingerprint is not None and fingerprint != mesh.fingerprint.hex():
        raise MeshMismatchError(f"{where}: fingerprint {fingerprint[:16]} does not match the base mesh in the file "
                                f"({mesh.fingerprint.hex()[:16]}); the file was altered")
    k = tree_shape(numbers)[0]
    axes = ext.get("axes")
    if "axes" in ext and not isinstance(axes, dict):
        raise GltfError(f"{where}: axes: expected an object (count, parents, frames, lo, length), found {axes!r:.80}")
    if (k > 1) != (axes is not None):
        raise GltfError(f"{where}: numbersPerInstance {numbers} is {k} axes an instance, but the extension "
                        f"{'has no' if axes is None else 'has'} axes")
    aligned = next((i for i in range(3) if np.array_equal(frame, np.eye(3)[[i, *PERPENDICULAR[i]]])), -1)
    mid = frame.T @ np.array([lo + length / 2, *center])  # the axis line's middle, model space
    exact = ControlAxis(index=aligned, lo=lo, length=length, center=tuple(float(c) for c in mid),
                        frame=None if aligned >= 0 else tuple(map(tuple, frame)), kind="matrix")
    if params.shape[1] + 10 * (k - 1) != numbers:  # the child axes' 10 numbers each come from their attributes
        raise GltfError(f"{where}: numbersPerInstance: {numbers}, but the instance attributes hold "
                        f"{params.shape[1] + 10 * (k - 1)} numbers an instance")
    if k == 1:
        return mesh.with_control_axis(exact), as_params(params, name=where)
    if not isinstance(axes, dict) or axes.get("count") != k:
        raise GltfError(f"{where}: axes: expected an object of count {k} (numbersPerInstance {numbers}), found "
                        f"{axes!r:.80}")
    from ..axes import check_parents

    try:
        parents = check_parents(axes.get("parents"), k)
    except AxialDeformError as exc:
        raise GltfError(f"{where}: {exc}") from None
    frames = axes.get("frames")
    if not isinstance(frames, list) or len(frames) != k:
        raise GltfError(f"{where}: axes frames: expected {k} frames, found {frames!r:.80}")
    frames = [_frame(f, f"{where}: axes frames[{j}]") for j, f in enumerate(frames)]
    los = _numbers(axes.get("lo"), k, f"{where}: axes lo")
    lengths = _numbers(axes.get("length"), k, f"{where}: axes length", positive=True)
    cached = extras.get("axes") if isinstance(extras.get("axes"), dict) else {}
    names = cached.get("names") if isinstance(cached.get("names"), list) and len(cached.get("names")) == k else \
        [f"axis{j}" for j in range(k)]
    record = {"count": k, "parents": list(parents), "frames": [f.tolist() for f in frames], "names": names}
    mesh, params = _read_tree(gltf, blob, prim, record, cols, mesh, params, where)
    tree = mesh.tree
    lengths_lo = [dataclasses.replace(a, lo=float(los[j]), length=float(lengths[j])) for j, a in enumerate(tree.axes)]
    lengths_lo[0] = exact
    return dataclasses.replace(mesh, tree=dataclasses.replace(tree, axes=tuple(lengths_lo))), params


def _read_tree(gltf, blob, prim, record, cols, mesh, params, where):
    """The mesh of several axes an instanced node records (extras ``axes``,
    the vertex attribute ``_AXIAL_AXIS``, the instanced ``_AXIAL_A{k}_*``)."""
    from ..axes import tree_from_vertices
    from ..blend import split_vertex_code

    try:
        k = int(record["count"])
        parents, frames, names = list(record["parents"]), list(record["frames"]), list(record["names"])
    except (KeyError, TypeError, ValueError):
        raise GltfError(f"{where}: extras axes: expected count, names, parents and frames, found {record!r}"[:300]) from None
    if not 2 <= k <= MAX_RECORD_AXES:  # before anything is sized by it
        raise GltfError(f"{where}: axes count: expected 2 to {MAX_RECORD_AXES} axes, found {k}")
    index = getattr(prim.attributes, AXIS_ATTRIBUTE, None)
    if index is None:
        raise GltfError(f"{where}: a mesh of {k} axes needs the vertex attribute {AXIS_ATTRIBUTE}; found none")
    va = read_accessor(gltf, blob, index, AXIS_ATTRIBUTE, where).reshape(-1)
    if len(va) != mesh.vertex_count or not np.array_equal(va, np.round(va)) or (len(va) and not 0 <= va.min() <= va.max() < 2 ** 23):
        raise GltfError(f"{where}: {AXIS_ATTRIBUTE}: expected one whole axis index (or a blend's code, b + 64 b1 + 4096 q, "
                        f"below 2^23) per vertex ({mesh.vertex_count})")
    va, blend = split_vertex_code(va)
    children = child_offsets(cols, len(params), k, where)
    anchors = record.get("anchors")  # each child's joint (optional: measured from the geometry if absent)
    if anchors is not None and not (isinstance(anchors, list) and len(anchors) == k and all(
            isinstance(t, (int, float)) and not isinstance(t, bool) and 0 <= t <= 1 for t in anchors)):
        raise GltfError(f"{where}: axes anchors: expected {k} numbers in 0..1 (t on each axis's own length), "
                        f"found {anchors!r:.80}")
    try:
        tree = tree_from_vertices(mesh, va.astype(np.int64), parents, frames=[np.asarray(f) for f in frames],
                                  names=names, root_children=False, anchors=anchors, blend=blend)
        mesh = mesh.with_axes(tree)
    except AxialDeformError as exc:
        raise GltfError(f"{where}: extras axes: {exc}") from None
    return mesh, as_params(join_record(params, children), name=where, axes=k)


def read_extras(path: str | os.PathLike) -> dict:
    """The ``extras["axialdeform"]`` dictionaries of a GLB's scenes and nodes (for tools and tests)."""
    gltf = load_glb(Path(path))
    out = {}
    for kind, items in (("scene", gltf.scenes), ("node", gltf.nodes)):
        for k, item in enumerate(items):
            if item.extras and EXTRAS_KEY in item.extras:
                out[f"{kind}/{k}"] = json.loads(json.dumps(item.extras[EXTRAS_KEY]))
    return out

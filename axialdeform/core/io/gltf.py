"""glTF 2.0 export of deformed instances, in two layouts (``docs/interop.md``).

* **baked** (:func:`export_baked`): one mesh per instance holding its
  deformed world positions and normals (:func:`axialdeform.core.bake.bake`), each
  referenced by its own node.  Any glTF viewer shows the exact shapes.
* **instanced** (:func:`export_instanced`): the base mesh once, drawn by one
  node with ``EXT_mesh_gpu_instancing``.  Per instance the extension carries
  ``TRANSLATION`` (VEC3 float, the position ``p``), ``ROTATION`` (VEC4 float,
  the unit quaternion ``x, y, z, w`` of ``R = Rz·Ry·Rx``) and the
  application-specific attributes

  ===============  ======  ===============================================
  name             type    contents (float32, per instance)
  ===============  ======  ===============================================
  ``_AXIAL_D12``   VEC4    ``d1u d1v d2u d2v`` (model units)
  ``_AXIAL_D34``   VEC4    ``d3u d3v d4u d4v`` (model units)
  ``_AXIAL_D5``    VEC2    ``d5u d5v`` (model units)
  ``_AXIAL_ANGLES`` VEC3   ``rx ry rz`` (radians), the original angles
  ===============  ======  ===============================================

  Extended instances (19 numbers) add ``SCALE`` (VEC3 float, ``(s, s, s)``:
  the scale is uniform, applied in model space as glTF's T·R·S does) and
  ``_AXIAL_TWIST_TAPER`` (VEC2 float, ``tw tp``); 16-number files are written
  exactly as before.  Tinted instances (22 numbers) add ``_COLOR_0`` (VEC3
  float, ``tr tg tb``), the per-instance colour three.js's GLTFLoader reads
  as ``instanceColor``; the baked layout gives each tinted instance its own
  materials, the parts' base colour factors times its tint.

  and the node's ``extras["axialdeform"]`` records the control axis
  (``index``, ``lo``, ``length``) and the SHA-256 fingerprint of the base
  mesh.  A viewer that knows the extension but not the deformation draws the
  undeformed base mesh at each instance's position and orientation; a viewer
  without the extension draws the base mesh once.  :func:`read_instanced_glb`
  reads the 16 (19, 22) numbers back bit for bit.

Coordinates are written as they are: glTF says +Y is up and units are
metres, and nothing here re-orients or rescales the model.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..bake import bake_cpu, instance_name
from ..deform import deform, deform_tangents
from ..errors import GltfError
from ..params import as_params
from ..record import (
    ANGLES,
    EXTENDED_WIDTH,
    GLTF_TINT_ATTRIBUTE,
    LEVEL_FIELDS,
    POSITION,
    SCALE,
    TINTED_WIDTH,
    split_record,
    tint_columns,
)
from ..transforms import (
    matrices_from_quaternions,
    quaternions_from_angles,
)
from .atomic import atomic_path, atomic_write_bytes
from .glb import (
    ARRAY_BUFFER,
    ATTRIBUTES,
    AXIS_ATTRIBUTE,
    BEND_EXTENSION,
    COMPONENTS,
    ELEMENT_ARRAY_BUFFER,
    EXTENDED_ATTRIBUTES,
    EXTRAS_KEY,
    FLOAT,
    FORMAT_VERSION,
    INSTANCING,
    LAYOUTS,
    TRIANGLES,
    UINT8,
    UINT32,
    GlbBuilder,
    child_columns,
    quiet_pygltflib,
    read_accessor,
)
from .gltf_read import read_extras, read_instanced_glb
from .safeio import require_finite

__all__ = [
    "GltfError",
    "LAYOUTS",
    "INSTANCING",
    "EXTRAS_KEY",
    "BEND_EXTENSION",
    "bend_extension",
    "ATTRIBUTES",
    "export_glb",
    "export_baked",
    "export_instanced",
    "encode_base_mesh",
    "read_instanced_glb",
    "read_extras",
    "quaternions_from_angles",
    "matrices_from_quaternions",
    "check_glb_path",
    "encode_scene",
    "export_scene",
]


def _mesh_extras(mesh, count: int, layout: str) -> dict:
    a = mesh.axis
    tree = getattr(mesh, "tree", None)
    # several axes: enough to rebuild the tree (each vertex's axis: _AXIAL_AXIS) and to bend it
    axes = {} if tree is None else {"axes": tree.to_json()}
    return {**axes,
        "version": FORMAT_VERSION,
        "layout": layout,
        "count": int(count),
        # a chosen frame (docs/method.md): index -1 and its rows e_a, e_u, e_v
        "axis": {"index": a.index, "name": a.name, "lo": float(a.lo), "length": float(a.length),
                 **({"frame": [list(row) for row in a.frame]} if a.framed else {})},
        "mesh_fingerprint": mesh.fingerprint.hex(),
        "mesh_vertices": mesh.vertex_count,
    }


def bend_extension(mesh, numbers: int) -> dict:
    """The ``AXIALDEFORM_bend`` object of an instancing node (``docs/gltf/AXIALDEFORM_bend``):
    the base mesh's control axis (frame rows ``e_a, e_u, e_v``, ``lo``, ``length``, the axis line
    ``center``), a tree's axes, the numbers per instance and the mesh fingerprint."""
    a = mesh.axis
    out = {"numbersPerInstance": int(numbers),
           "axis": {"frame": a.matrix.tolist(), "lo": float(a.lo), "length": float(a.length),
                    "center": [float(c) for c in a.line]},
           "fingerprint": mesh.fingerprint.hex()}
    tree = getattr(mesh, "tree", None)
    if tree is not None:
        out["axes"] = {k: v for k, v in tree.to_json().items() if k != "names"}
    return out


def check_glb_path(path) -> Path:
    """``path`` as a Path when it names a .glb file that is not a folder; else :class:`GltfError`."""
    path = Path(path)
    if path.suffix.lower() != ".glb":
        raise GltfError(f"{path}: expected a .glb file name (binary glTF), found {path.suffix or 'no extension'!r}")
    if path.is_dir():
        raise GltfError(f"{path}: is a folder; expected a .glb file name")
    return path


def encode_baked(mesh, params, *, positions=None, normals=None, source: str | None = None,
                 tangents: bool = True) -> bytes:
    """The GLB bytes of the baked layout (see :func:`export_baked`); ``source``
    names the parameter file in errors; ``tangents=False`` leaves ``TANGENT``
    out (when ``params`` are not the ones ``positions`` were baked from)."""
    return _build_baked(mesh, params, positions=positions, normals=normals, source=source,
                        tangents=tangents).finish()


def _build_baked(mesh, params, *, positions=None, normals=None, source: str | None = None,
                 tangents: bool = True) -> GlbBuilder:
    params = as_params(params, axes=getattr(mesh, "axis_count", 1))
    tangents = tangents and getattr(mesh, "axis_count", 1) == 1  # several axes: viewers compute their own (MikkTSpace)
    if positions is None or normals is None:

        positions, normals = bake_cpu(mesh, params, source=source)
    if len(params) == 0:
        raise GltfError("baked export: expected at least one instance, found 0")
    positions = np.ascontiguousarray(positions, dtype="<f4")
    normals = np.ascontiguousarray(normals, dtype="<f4")
    n, v = positions.shape[:2]
    if positions.shape != (n, mesh.vertex_count, 3) or normals.shape != positions.shape:
        raise GltfError(
            f"baked arrays: expected positions and normals of shape ({len(params)}, {mesh.vertex_count}, 3), "
            f"found {positions.shape} and {normals.shape}"
        )

    # an overflowing deformation (huge but finite parameters) is refused before any JSON is made
    require_finite(positions, "positions", "xyz", error=GltfError, source=source)
    require_finite(normals, "normals", "xyz", error=GltfError, source=source)
    b = GlbBuilder()
    g = b.g
    look = b.appearance(mesh)
    # all instances share one bufferView per attribute; each accessor starts at its instance
    pos_view = b.view(positions, target=ARRAY_BUFFER, stride=12)
    nrm_view = b.view(normals, target=ARRAY_BUFFER, stride=12)
    tan_view = None
    if tangents and "TEXCOORD_0" in look.attributes and mesh.tangents is not None:

        tangents = np.concatenate([deform_tangents(mesh.axis, mesh.positions, mesh.tangents, params),
                                   np.broadcast_to(mesh.tangents[None, :, 3:], (n, v, 1))], axis=2).astype("<f4")
        tan_view = b.view(np.ascontiguousarray(tangents), target=ARRAY_BUFFER, stride=16)
    lo, hi = positions.min(axis=1), positions.max(axis=1)  # (n, 3): bounds per instance, vectorized
    tints = tint_columns(params)
    for k in range(n):  # glTF objects per instance (JSON), not per vertex
        name = instance_name(k, n)
        pa = b.accessor(pos_view, FLOAT, v, "VEC3", offset=k * v * 12, bounds=np.stack([lo[k], hi[k]]), name=name + "_POSITION")
        na = b.accessor(nrm_view, FLOAT, v, "VEC3", offset=k * v * 12, name=name + "_NORMAL")
        attributes = {"POSITION": pa, "NORMAL": na}
        if tan_view is not None:
            attributes["TANGENT"] = b.accessor(tan_view, FLOAT, v, "VEC4", offset=k * v * 16, name=name + "_TANGENT")
        b.gltf.meshes.append(g.Mesh(name=name, primitives=look.primitives(
            attributes, b, None if tints is None else tints[k])))
        b.gltf.nodes.append(g.Node(name=name, mesh=k, extras={EXTRAS_KEY: {"instance": k}}))
    b.gltf.scenes.append(g.Scene(name="axialdeform baked", nodes=list(range(n)),
                                 extras={EXTRAS_KEY: _mesh_extras(mesh, n, "baked")}))
    b.gltf.scene = 0
    return b


def export_baked(path: str | os.PathLike, mesh, params, *, positions=None, normals=None,
                 source: str | None = None) -> Path:
    """Write one glTF mesh per instance with its deformed world geometry.

    Parameters
    ----------
    path : str or PathLike
        The ``.glb`` to write (atomically).
    mesh : BaseMesh
    params : (n, 16) float32
    positions, normals : (n, v, 3) float32, optional
        Already baked geometry (e.g. from the GPU); baked on the CPU if omitted.

    Every instance is a node ``instance_NNNNNN`` with its own mesh (POSITION,
    NORMAL, world units) and the base mesh's triangles; the scene's
    ``extras["axialdeform"]`` records the axis and the mesh fingerprint.
    """
    path = check_glb_path(path)
    built = _build_baked(mesh, params, positions=positions, normals=normals, source=source)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:  # streamed: the file is never whole in memory
        built.write_to(fh)
    return path


def _base_attributes(b: GlbBuilder, mesh) -> tuple[int, int]:
    """Accessors of the base mesh's POSITION and NORMAL (float32, file order)."""
    pos = b.accessor(b.view(mesh.positions.astype("<f4"), target=ARRAY_BUFFER), FLOAT, mesh.vertex_count, "VEC3",
                     bounds=mesh.positions, name="base_POSITION")
    nrm = b.accessor(b.view(mesh.normals.astype("<f4"), target=ARRAY_BUFFER), FLOAT, mesh.vertex_count, "VEC3",
                     name="base_NORMAL")
    return pos, nrm


def _vertex_attributes(b: GlbBuilder, mesh) -> dict:
    """POSITION, NORMAL (and ``_AXIAL_AXIS``, each vertex's axis -- its code when it blends two --, for a mesh
    of several axes)."""
    pos, nrm = _base_attributes(b, mesh)
    out = {"POSITION": pos, "NORMAL": nrm}
    tree = getattr(mesh, "tree", None)
    if tree is not None:
        out[AXIS_ATTRIBUTE] = b.accessor(b.view(tree.vertex_code.astype("<f4"), target=ARRAY_BUFFER), FLOAT,
                                         mesh.vertex_count, "SCALAR", name=AXIS_ATTRIBUTE)
    return out


def encode_base_mesh(mesh) -> bytes:
    """The GLB bytes of the base mesh alone (one mesh, one node): POSITION and
    NORMAL float32 in the file's vertex order and its triangles, so the
    positions and faces hash to :attr:`BaseMesh.fingerprint` again (what the
    web page checks a parameter file against).  A mesh with appearance keeps
    it: one primitive per part (its triangles in order, so the parts' indices
    concatenated are the mesh's triangles) with its material (base colour
    factor and texture, alpha mode and cutoff, double-sidedness, normal map),
    TEXCOORD_0, COLOR_0 and TANGENT."""
    b = GlbBuilder()
    g = b.g
    attributes = _vertex_attributes(b, mesh)  # before the appearance: the order earlier files have
    look = b.appearance(mesh, plain=True)  # the page colours a plain mesh itself (a layer's colour)
    if "TEXCOORD_0" in look.attributes and mesh.tangents is not None:
        attributes["TANGENT"] = b.accessor(b.view(mesh.tangents.astype("<f4"), target=ARRAY_BUFFER), FLOAT,
                                           mesh.vertex_count, "VEC4", name="base_TANGENT")
    b.gltf.meshes.append(g.Mesh(name=str(mesh.name), primitives=look.primitives(attributes)))
    b.gltf.nodes.append(g.Node(name=str(mesh.name), mesh=0, extras={EXTRAS_KEY: _mesh_extras(mesh, 0, "base")}))
    b.gltf.scenes.append(g.Scene(name="axialdeform base mesh", nodes=[0]))
    b.gltf.scene = 0
    return b.finish()


def encode_instanced(mesh, params) -> bytes:
    """The GLB bytes of the instanced layout (see :func:`export_instanced`)."""
    b = GlbBuilder()
    _add_instanced(b, mesh, params, "axialdeform instances")
    b.gltf.scenes.append(b.g.Scene(name="axialdeform instanced", nodes=[0]))
    b.gltf.scene = 0
    b.gltf.extensionsUsed = [INSTANCING, BEND_EXTENSION]
    return b.finish()


def _add_instanced(b: GlbBuilder, mesh, params, node_name: str, *, color=None, extras=None, bend=None) -> int:
    """Add ``mesh`` once (POSITION, NORMAL, appearance, TANGENT) and one node
    drawing it ``len(params)`` times with ``EXT_mesh_gpu_instancing`` (the
    instanced layout of the module docs); returns the node's index.
    ``color``: linear RGB for a mesh with the default material (a scene layer's)."""
    k = getattr(mesh, "axis_count", 1)
    params = as_params(params, axes=k)
    children = None
    if k > 1:  # several axes: axis 0's record as always, each child axis's offsets as _AXIAL_A{k}_*
        params, children = split_record(params, k)
    n = len(params)
    if n == 0:
        raise GltfError("instanced export: expected at least one instance (EXT_mesh_gpu_instancing needs count >= 1)")
    g = b.g
    attributes = _vertex_attributes(b, mesh)  # before the appearance: the order earlier files have
    look = b.appearance(mesh, color)
    if "TEXCOORD_0" in look.attributes and mesh.tangents is not None:
        attributes["TANGENT"] = b.accessor(b.view(mesh.tangents.astype("<f4"), target=ARRAY_BUFFER), FLOAT,
                                           mesh.vertex_count, "VEC4", name="base_TANGENT")
    b.gltf.meshes.append(g.Mesh(name=node_name if color is not None else "base",
                                primitives=look.primitives(attributes)))
    # per-instance data: no bufferView target (they are not vertex attributes)
    columns = {
        "TRANSLATION": ("VEC3", params[:, POSITION]),
        "ROTATION": ("VEC4", quaternions_from_angles(params[:, ANGLES]).astype(np.float32)),
    }
    extra_attributes = dict(EXTENDED_ATTRIBUTES) if params.shape[1] >= EXTENDED_WIDTH else {}
    if extra_attributes:
        columns["SCALE"] = ("VEC3", np.repeat(params[:, SCALE, None], 3, axis=1))
    if params.shape[1] >= TINTED_WIDTH:
        name, kind, cols = GLTF_TINT_ATTRIBUTE
        extra_attributes[name] = (kind, cols)
    columns.update({name: (kind, params[:, list(cols)])
                    for name, (kind, cols) in {**ATTRIBUTES, **extra_attributes}.items()})
    for j in range(1, k):
        flat = children[:, j - 1].reshape(n, 10)
        columns.update({name: (kind, flat[:, first:first + COMPONENTS[kind]])
                        for name, (kind, first) in child_columns(j).items()})
    attributes = {}
    for name, (kind, data) in columns.items():
        data = np.ascontiguousarray(data, dtype="<f4")
        attributes[name] = b.accessor(b.view(data), FLOAT, n, kind, name=name)
    node_extras = _mesh_extras(mesh, n, "instanced")
    node_extras["attributes"] = {name: _field_names(cols) for name, (_k, cols) in {**ATTRIBUTES, **extra_attributes}.items()}
    if extra_attributes:
        node_extras["attributes"]["SCALE"] = ["s", "s", "s"]
    node_extras.update(extras or {})
    b.gltf.nodes.append(g.Node(name=node_name, mesh=len(b.gltf.meshes) - 1,
                               extensions={INSTANCING: {"attributes": attributes},
                                           BEND_EXTENSION: {**bend_extension(mesh, params.shape[1] + 10 * (k - 1)),
                                                            **(bend or {})}},
                               extras={EXTRAS_KEY: node_extras}))
    return len(b.gltf.nodes) - 1


def encode_scene(scene, layout: str = "baked") -> bytes:
    """GLB bytes of a whole scene (:mod:`axialdeform.core.scene`).

    ``layout="baked"``: the terrain and one mesh per layer holding all its
    instances' deformed world geometry (CPU reference), each with its layer's
    colour as a PBR material.  ``layout="instanced"``: the terrain once, and
    per layer its base mesh once (with its own appearance, or the layer's
    colour) drawn by one node named after the layer with
    ``EXT_mesh_gpu_instancing`` and the ``_AXIAL_*`` attributes, exactly as
    :func:`export_instanced` writes one mesh (:func:`read_instanced_glb` with
    ``node=LAYER`` reads a layer back).  ``layout="generated"``: as instanced, a generated layer's node
    carrying its recipe and a small fallback (:mod:`~axialdeform.core.io.gltf_generate`).  No layout holds
    the scene's wind.
    """
    layers = _scene_layers(scene, layout)
    if layout in ("instanced", "generated"):
        return _encode_scene_instanced(scene, layers, generated=layout == "generated")
    return _build_scene_baked(scene, layers).finish()


def _scene_layers(scene, layout: str) -> list:
    if layout not in LAYOUTS:
        raise GltfError(f"layout: expected one of {', '.join(LAYOUTS)}, found {layout!r}")
    layers = [layer for layer in scene.layers if len(layer.params)]
    if scene.terrain is None and not layers:
        raise GltfError(f"{scene.path}: the scene has nothing to export; expected a terrain or a layer with instances")
    return layers


def _build_scene_baked(scene, layers) -> GlbBuilder:
    """The baked layout of :func:`encode_scene`: per layer (and the terrain)
    one node and one mesh named after it holding every instance's deformed
    world geometry (POSITION, NORMAL, uint32 indices), a PBR material of the
    layer's colour (metallic 0, roughness 0.9); tinted instances: the colour
    times each one's tint as COLOR_0 (normalized uint8) under a white
    material.  The arrays are handed to the builder as they are (no copies):
    :func:`export_scene` streams them to the file."""
    b = GlbBuilder()
    g = b.g
    parts = [("terrain", scene.terrain, None, scene.terrain_color)] if scene.terrain is not None else []
    parts += [(layer.name, layer.mesh, layer.params, layer.color) for layer in layers]
    for name, mesh, params, color in parts:
        if params is None:
            pos, nrm = mesh.positions[None].astype(np.float32), mesh.normals[None].astype(np.float32)
        else:
            with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused just below
                pos, nrm = deform(mesh.axis, mesh.positions, mesh.normals, params)
            require_finite(pos, "positions", "xyz", error=GltfError, source=name)
            require_finite(nrm, "normals", "xyz", error=GltfError, source=name)
        n, v = pos.shape[:2]
        if n * v >= 2**32:
            raise GltfError(f"{name}: {n} instances of {v} vertices are {n * v} vertices in one glTF mesh; expected "
                            "fewer than 2^32 (uint32 indices): export fewer instances, or --instanced")
        faces = np.asarray(mesh.faces).astype(np.uint32)
        index = np.empty((n, len(faces), 3), dtype="<u4")
        np.add(faces[None], (np.uint32(v) * np.arange(n, dtype=np.uint32))[:, None, None], out=index)
        rgb = [float(c) for c in color] if color is not None else [0.6, 0.6, 0.6]
        tints = None if params is None else tint_columns(params)
        flat = pos.reshape(-1, 3)
        attributes = {"POSITION": b.accessor(b.view(flat, target=ARRAY_BUFFER), FLOAT, n * v, "VEC3",
                                             bounds=np.stack([flat.min(axis=0), flat.max(axis=0)]),
                                             name=f"{name}_POSITION"),
                      "NORMAL": b.accessor(b.view(nrm.reshape(-1, 3), target=ARRAY_BUFFER), FLOAT, n * v, "VEC3",
                                           name=f"{name}_NORMAL")}
        if tints is not None:  # the layer's colour times each instance's tint, per vertex
            rgba = np.empty((n, v, 4), dtype=np.uint8)
            rgba[..., :3] = np.rint(255 * np.clip(np.asarray(rgb) * tints, 0, 1))[:, None, :]
            rgba[..., 3] = 255
            acc = b.accessor(b.view(rgba.reshape(-1, 4), target=ARRAY_BUFFER), UINT8, n * v, "VEC4",
                             name=f"{name}_COLOR_0")
            b.gltf.accessors[acc].normalized = True
            attributes["COLOR_0"] = acc
            rgb = [1.0, 1.0, 1.0]
        ind = b.accessor(b.view(index.reshape(-1), target=ELEMENT_ARRAY_BUFFER), UINT32, index.size, "SCALAR",
                         name=f"{name}_indices")
        b.gltf.materials.append(g.Material(name=name, pbrMetallicRoughness=g.PbrMetallicRoughness(
            baseColorFactor=[*rgb, 1.0], metallicFactor=0.0, roughnessFactor=0.9)))
        b.gltf.meshes.append(g.Mesh(name=name, primitives=[g.Primitive(
            attributes=g.Attributes(**attributes), indices=ind, material=len(b.gltf.materials) - 1, mode=TRIANGLES)]))
        b.gltf.nodes.append(g.Node(name=name, mesh=len(b.gltf.meshes) - 1))
    b.gltf.scenes.append(g.Scene(nodes=list(range(len(b.gltf.nodes)))))
    b.gltf.scene = 0
    return b


def _encode_scene_instanced(scene, layers, generated: bool = False) -> bytes:
    """The instanced layout of :func:`encode_scene`; ``generated``: a generated layer as its recipe
    (:func:`~axialdeform.core.io.gltf_generate.generated_form`) with a small fallback of instances."""
    from .gltf_generate import check_generated, generated_form

    if generated:
        check_generated(scene, layers)
    b = GlbBuilder()
    g = b.g
    nodes = []
    if scene.terrain is not None:
        terrain = scene.terrain
        pos, nrm = _base_attributes(b, terrain)
        look = b.appearance(terrain, scene.terrain_color)
        b.gltf.meshes.append(g.Mesh(name="terrain", primitives=look.primitives({"POSITION": pos, "NORMAL": nrm})))
        b.gltf.nodes.append(g.Node(name="terrain", mesh=len(b.gltf.meshes) - 1))
        nodes.append(len(b.gltf.nodes) - 1)
    for layer in layers:
        params, bend = layer.params, None
        if generated and getattr(layer, "generate", None) is not None:
            params, bend = generated_form(b, layer)
        nodes.append(_add_instanced(b, layer.mesh, params, layer.name,
                                    color=layer.color if layer.color is not None else (0.6, 0.6, 0.6),
                                    extras={"layer": layer.name}, bend=bend))
    b.gltf.scenes.append(g.Scene(name="axialdeform scene, instanced", nodes=nodes, extras={EXTRAS_KEY: {
        "version": FORMAT_VERSION, "layout": "instanced", "layers": [layer.name for layer in layers],
        "up": scene.up}}))
    b.gltf.scene = 0
    if layers:
        b.gltf.extensionsUsed = [INSTANCING, BEND_EXTENSION]
    return b.finish()


def export_scene(path: str | os.PathLike, scene, layout: str = "baked") -> Path:
    """Write :func:`encode_scene` (``layout`` ``"baked"``, ``"instanced"`` or ``"generated"``) to ``path``
    (a ``.glb``), atomically."""
    path = check_glb_path(path)
    layers = _scene_layers(scene, layout)
    if layout in ("instanced", "generated"):
        atomic_write_bytes(path, _encode_scene_instanced(scene, layers, generated=layout == "generated"))
        return path
    built = _build_scene_baked(scene, layers)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:  # streamed: the file is never whole in memory
        built.write_to(fh)
    return path


def _field_names(cols) -> list[str]:
    return [LEVEL_FIELDS[-1][c] for c in cols]


def export_instanced(path: str | os.PathLike, mesh, params) -> Path:
    """Write the base mesh once plus ``EXT_mesh_gpu_instancing`` (see the module docs).

    Parameters
    ----------
    path : str or PathLike
        The ``.glb`` to write (atomically).
    mesh : BaseMesh
    params : (n, 16) float32, n >= 1
    """
    path = check_glb_path(path)
    atomic_write_bytes(path, encode_instanced(mesh, params))
    return path


def export_glb(path: str | os.PathLike, mesh, params, layout: str = "baked", *, source: str | None = None) -> Path:
    """Write ``params`` for ``mesh`` as a GLB.

    Parameters
    ----------
    path : str or PathLike
        The ``.glb`` to write (atomically).
    mesh : BaseMesh
    params : (n, 16|19|22) float32
    layout : {"baked", "instanced"}
        Every instance as its own bent mesh, or the base mesh once with ``EXT_mesh_gpu_instancing``
        and the bend in ``AXIALDEFORM_bend``.
    source : str, optional
        The parameter file, named in errors.

    Returns
    -------
    Path
        The file written.
    """
    if layout == "baked":
        return export_baked(path, mesh, params, source=source)
    if layout == "instanced":
        return export_instanced(path, mesh, params)
    raise GltfError(f"layout: expected one of {', '.join(LAYOUTS)}, found {layout!r}")


# ------------------------------------------------------------------------- CLI


def gltf_attributes(data: bytes, kind: str, resolver=None) -> list:
    """What trimesh drops of a glTF file's triangle primitives: ``TANGENT``
    always, ``TEXCOORD_0`` of a primitive without a material.  A list of
    ``(positions (k, 3) float32, {"TANGENT": (k, 4) float32, "TEXCOORD_0":
    (k, 2) float32})`` (the keys the primitive has), one per primitive with
    either, in the file's vertex order, read by pygltflib and
    :func:`axialdeform.core.io.gltf.read_accessor`.  ``kind``: ``"glb"`` or
    ``"gltf"``; ``resolver``: reads a ``.gltf``'s external buffer (a
    :class:`~axialdeform.core.material.SafeResolver`).  Only buffer 0 is read
    (the GLB chunk, a data URI or one ``.bin``); what cannot be read is left
    out (tangents are then computed where a normal map needs them)."""
    import pygltflib

    try:
        if kind == "glb":
            with quiet_pygltflib():
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

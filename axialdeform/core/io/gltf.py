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

import contextlib
import copy
import io
import json
import os
import warnings
from pathlib import Path

import numpy as np
from PIL import Image

from ..bake import bake_cpu, instance_name
from ..deform import deform, deform_tangents
from ..errors import AxialDeformError, GltfError, MeshMismatchError
from ..material import Material
from ..mesh import BaseMesh, area_weighted_normals
from ..params import as_params
from ..record import (
    ANGLES,
    EXTENDED_WIDTH,
    GLTF_ATTRIBUTES,
    GLTF_EXTENDED_ATTRIBUTES,
    GLTF_TINT_ATTRIBUTE,
    LEVEL_FIELDS,
    POSITION,
    SCALE,
    TINTED_WIDTH,
    WIDTHS,
    join_record,
    split_record,
    tint_columns,
)
from ..transforms import (
    angles_from_matrices,
    matrices_from_quaternions,
    quaternions_from_angles,
)
from . import safeio
from .atomic import atomic_path, atomic_write_bytes
from .resolver import error_in_words
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
    "quaternions_from_angles",
    "matrices_from_quaternions",
    "check_glb_path",
    "encode_scene",
    "export_scene",
]

LAYOUTS = ("baked", "instanced")
#: the glTF extension that draws one mesh many times
INSTANCING = "EXT_mesh_gpu_instancing"
#: key of the dictionary this library writes into ``extras``
EXTRAS_KEY = "axialdeform"
#: the vendor extension carrying the bend on an instancing node (docs/gltf/AXIALDEFORM_bend)
BEND_EXTENSION = "AXIALDEFORM_bend"
#: the application-specific per-instance attributes (from the record table)
ATTRIBUTES = GLTF_ATTRIBUTES
EXTENDED_ATTRIBUTES = GLTF_EXTENDED_ATTRIBUTES
_FORMAT_VERSION = 1

# glTF enums
_FLOAT, _UINT8, _UINT16, _UINT32 = 5126, 5121, 5123, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_TRIANGLES = 4
_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}


# --------------------------------------------------------------------- writing


class _Builder:
    """Collects binary data and glTF objects for one GLB (pygltflib underneath)."""

    def __init__(self) -> None:
        import pygltflib as g

        self.g = g
        self.gltf = g.GLTF2(asset=g.Asset(version="2.0", generator="axialdeform"))
        self.chunks: list[bytes] = []
        self.offset = 0

    def view(self, data: np.ndarray, target: int | None = None, stride: int | None = None) -> int:
        # the array's own bytes, not a copy: a baked GLB of a big mesh holds its arrays once
        raw = memoryview(np.ascontiguousarray(data)).cast("B")
        pad = (-len(raw)) % 4  # every bufferView starts 4-byte aligned
        self.gltf.bufferViews.append(
            self.g.BufferView(buffer=0, byteOffset=self.offset, byteLength=len(raw), target=target, byteStride=stride)
        )
        self.chunks.append(raw)
        if pad:
            self.chunks.append(bytes(pad))
        self.offset += len(raw) + pad
        return len(self.gltf.bufferViews) - 1

    def accessor(self, view: int, component: int, count: int, kind: str, *, offset: int = 0,
                 bounds: np.ndarray | None = None, name: str | None = None) -> int:
        acc = self.g.Accessor(bufferView=view, byteOffset=offset, componentType=component, count=int(count),
                              type=kind, name=name)
        if bounds is not None:
            acc.min = [float(x) for x in bounds.min(axis=0)]
            acc.max = [float(x) for x in bounds.max(axis=0)]
        self.gltf.accessors.append(acc)
        return len(self.gltf.accessors) - 1

    def indices(self, mesh, faces=None, name: str = "indices") -> int:
        faces = mesh.faces if faces is None else faces
        small = mesh.vertex_count <= 65535
        data = faces.astype("<u2" if small else "<u4").ravel()
        view = self.view(data, target=_ELEMENT_ARRAY_BUFFER)
        return self.accessor(view, _UINT16 if small else _UINT32, data.size, "SCALAR", name=name)

    def appearance(self, mesh, default_color=None) -> _Appearance:
        """The mesh's parts (indices + material each) and its UV/colour accessors,
        written once; ``default_color`` (linear RGB) replaces a default material."""
        return _Appearance(self, mesh, default_color)

    def write_to(self, fh) -> None:
        """The GLB into the binary file ``fh``, chunk after chunk: the binary
        buffer is never joined in memory (what pygltflib's ``save_to_bytes``
        writes, byte for byte)."""
        import struct

        self.gltf.buffers = [self.g.Buffer(byteLength=self.offset)]
        text = self.gltf.gltf_to_json(separators=(",", ":"), indent=None).encode("utf-8")
        text += b" " * ((-len(text)) % 4)  # the binary chunk starts 4-byte aligned
        fh.write(struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + 8 + self.offset))
        fh.write(struct.pack("<I4s", len(text), b"JSON"))
        fh.write(text)
        fh.write(struct.pack("<I4s", self.offset, b"BIN\x00"))
        for chunk in self.chunks:
            fh.write(chunk)

    def finish(self) -> bytes:
        out = io.BytesIO()
        self.write_to(out)
        return out.getvalue()


#: id(pixels) -> (the pixels, their PNG): each image is encoded at most once a process
#: (a bake writes the same texture into every instance's GLB); the pixels are kept
#: alive by the entry, so an id is never reused while it is cached
_PNG_CACHE: dict[int, tuple[np.ndarray, bytes]] = {}
_PNG_CACHE_MAX = 16


def _png(pixels: np.ndarray) -> bytes:
    hit = _PNG_CACHE.get(id(pixels))
    if hit is not None and hit[0] is pixels:
        return hit[1]
    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(pixels, dtype=np.uint8), "RGBA").save(out, format="PNG")
    if len(_PNG_CACHE) >= _PNG_CACHE_MAX:
        _PNG_CACHE.pop(next(iter(_PNG_CACHE)))
    _PNG_CACHE[id(pixels)] = (pixels, out.getvalue())
    return out.getvalue()


def _image_bytes(m, key: str) -> tuple[bytes, str]:
    """The image of material ``m``'s ``key`` texture as a glTF carries it: the
    model's own PNG or JPEG bytes when it has them (a JPEG stays that JPEG),
    else the pixels encoded as PNG (once)."""
    source = m.sources.get(key)
    if source is not None:
        return source
    return _png(getattr(m, key)), "image/png"


class _Appearance:
    """glTF objects for a base mesh's appearance: per part an index accessor
    and a material (base colour factor + embedded PNG texture, alpha mode and
    cutoff, double-sidedness, normal map), shared TEXCOORD_0 (glTF's ``v``
    points down the image: ``1 - v``) and COLOR_0 (linear RGBA float)."""

    def __init__(self, b: _Builder, mesh, default_color=None) -> None:
        g = b.g
        self.mesh = mesh
        self.attributes: dict[str, int] = {}
        if mesh.uvs is not None:
            uv = np.column_stack([mesh.uvs[:, 0], 1.0 - mesh.uvs[:, 1]]).astype("<f4")
            self.attributes["TEXCOORD_0"] = b.accessor(b.view(uv, target=_ARRAY_BUFFER), _FLOAT, len(uv), "VEC2",
                                                       name="TEXCOORD_0")
        if mesh.colors is not None:
            col = np.clip(mesh.colors, 0.0, 1.0).astype("<f4")
            self.attributes["COLOR_0"] = b.accessor(b.view(col, target=_ARRAY_BUFFER), _FLOAT, len(col), "VEC4",
                                                    name="COLOR_0")
        self.parts = []  # (name, indices accessor, material index or None)
        self._tinted: dict = {}  # (material index or None, tint) -> material index
        materials: dict[int, int] = {}
        single = len(mesh.parts) == 1
        for part in mesh.parts:
            if part.count == 0:
                continue
            m = part.material
            if default_color is not None and m.is_default:  # a scene layer's colour

                m = Material(name=part.name if not single else str(getattr(mesh, "name", "mesh")),
                             base_color=[*default_color[:3], 1.0])
                part_key = ("color", part.name)
            else:
                part_key = id(m)
            if part_key not in materials and not (single and m.is_default):
                materials[part_key] = self._material(b, m)
            faces = mesh.faces[part.start:part.start + part.count]
            idx = b.indices(mesh, faces, name="indices" if single else f"{part.name}_indices")
            self.parts.append((part.name, idx, materials.get(part_key)))
        if b.gltf.textures:
            b.gltf.samplers = [g.Sampler(magFilter=9729, minFilter=9987, wrapS=10497, wrapT=10497)]

    def _texture(self, b: _Builder, m, key: str, name: str) -> int:
        g = b.g
        data, mime = _image_bytes(m, key)
        view = b.view(np.frombuffer(data, dtype=np.uint8))
        b.gltf.images.append(g.Image(bufferView=view, mimeType=mime, name=name))
        b.gltf.textures.append(g.Texture(sampler=0, source=len(b.gltf.images) - 1, name=name))
        return len(b.gltf.textures) - 1

    def _material(self, b: _Builder, m) -> int:
        g = b.g
        pbr = g.PbrMetallicRoughness(baseColorFactor=[float(c) for c in m.base_color], metallicFactor=0.0,
                                     roughnessFactor=0.9)
        if m.texture is not None and self.mesh.uvs is not None:
            pbr.baseColorTexture = g.TextureInfo(index=self._texture(b, m, "texture", f"{m.name}_baseColor"))
        mat = g.Material(name=m.name, pbrMetallicRoughness=pbr, alphaMode=m.alpha_mode,
                         doubleSided=bool(m.double_sided))
        if m.alpha_mode == "MASK":
            mat.alphaCutoff = float(m.alpha_cutoff)
        else:
            mat.alphaCutoff = None
        if m.normal_texture is not None and self.mesh.uvs is not None and self.mesh.tangents is not None:
            mat.normalTexture = g.NormalMaterialTexture(index=self._texture(b, m, "normal_texture", f"{m.name}_normal"))
        b.gltf.materials.append(mat)
        return len(b.gltf.materials) - 1

    def primitives(self, attributes: dict, b: _Builder | None = None, tint=None) -> list:
        """The primitives of the parts over ``attributes``; with ``tint``
        ((3,) linear RGB) each part's material is a copy whose base colour
        factor is multiplied by it (its textures shared)."""
        import pygltflib as g

        out = []
        everything = {**attributes, **self.attributes}
        known = {k: v for k, v in everything.items() if not k.startswith("_")}
        for _name, idx, material in self.parts:
            if tint is not None:
                material = self._tinted_material(b, material, tint)
            attrs = g.Attributes(**known)
            for key, value in everything.items():  # application-specific attributes: "_" and upper case
                if key.startswith("_"):
                    setattr(attrs, key, value)
            out.append(g.Primitive(attributes=attrs, indices=idx, material=material, mode=_TRIANGLES))
        return out

    def _tinted_material(self, b: _Builder, material: int | None, tint) -> int:
        import pygltflib as g

        key = (material, tuple(float(c) for c in tint))
        if key not in self._tinted:
            if material is None:  # glTF's default material: white, metallic 1 -- ours: dielectric
                mat = g.Material(name="tinted", pbrMetallicRoughness=g.PbrMetallicRoughness(
                    baseColorFactor=[1.0, 1.0, 1.0, 1.0], metallicFactor=0.0, roughnessFactor=0.9))
            else:
                mat = copy.deepcopy(b.gltf.materials[material])
            base = mat.pbrMetallicRoughness.baseColorFactor or [1.0, 1.0, 1.0, 1.0]
            mat.pbrMetallicRoughness.baseColorFactor = [float(base[c]) * key[1][c] for c in range(3)] + [float(base[3])]
            b.gltf.materials.append(mat)
            self._tinted[key] = len(b.gltf.materials) - 1
        return self._tinted[key]



def _mesh_extras(mesh, count: int, layout: str) -> dict:
    a = mesh.axis
    tree = getattr(mesh, "tree", None)
    # several axes: enough to rebuild the tree (each vertex's axis: _AXIAL_AXIS) and to bend it
    axes = {} if tree is None else {"axes": tree.to_json()}
    return {**axes,
        "version": _FORMAT_VERSION,
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
                 tangents: bool = True) -> _Builder:
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
    b = _Builder()
    g = b.g
    look = b.appearance(mesh)
    # all instances share one bufferView per attribute; each accessor starts at its instance
    pos_view = b.view(positions, target=_ARRAY_BUFFER, stride=12)
    nrm_view = b.view(normals, target=_ARRAY_BUFFER, stride=12)
    tan_view = None
    if tangents and "TEXCOORD_0" in look.attributes and mesh.tangents is not None:

        tangents = np.concatenate([deform_tangents(mesh.axis, mesh.positions, mesh.tangents, params),
                                   np.broadcast_to(mesh.tangents[None, :, 3:], (n, v, 1))], axis=2).astype("<f4")
        tan_view = b.view(np.ascontiguousarray(tangents), target=_ARRAY_BUFFER, stride=16)
    lo, hi = positions.min(axis=1), positions.max(axis=1)  # (n, 3): bounds per instance, vectorized
    tints = tint_columns(params)
    for k in range(n):  # glTF objects per instance (JSON), not per vertex
        name = instance_name(k, n)
        pa = b.accessor(pos_view, _FLOAT, v, "VEC3", offset=k * v * 12, bounds=np.stack([lo[k], hi[k]]), name=name + "_POSITION")
        na = b.accessor(nrm_view, _FLOAT, v, "VEC3", offset=k * v * 12, name=name + "_NORMAL")
        attributes = {"POSITION": pa, "NORMAL": na}
        if tan_view is not None:
            attributes["TANGENT"] = b.accessor(tan_view, _FLOAT, v, "VEC4", offset=k * v * 16, name=name + "_TANGENT")
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


def _base_attributes(b: _Builder, mesh) -> tuple[int, int]:
    """Accessors of the base mesh's POSITION and NORMAL (float32, file order)."""
    pos = b.accessor(b.view(mesh.positions.astype("<f4"), target=_ARRAY_BUFFER), _FLOAT, mesh.vertex_count, "VEC3",
                     bounds=mesh.positions, name="base_POSITION")
    nrm = b.accessor(b.view(mesh.normals.astype("<f4"), target=_ARRAY_BUFFER), _FLOAT, mesh.vertex_count, "VEC3",
                     name="base_NORMAL")
    return pos, nrm


def _vertex_attributes(b: _Builder, mesh) -> dict:
    """POSITION, NORMAL (and ``_AXIAL_AXIS``, each vertex's axis, for a mesh of several axes)."""
    pos, nrm = _base_attributes(b, mesh)
    out = {"POSITION": pos, "NORMAL": nrm}
    tree = getattr(mesh, "tree", None)
    if tree is not None:
        out[AXIS_ATTRIBUTE] = b.accessor(b.view(tree.vertex_axis.astype("<f4"), target=_ARRAY_BUFFER), _FLOAT,
                                         mesh.vertex_count, "SCALAR", name=AXIS_ATTRIBUTE)
    return out


#: the vertex attribute of a mesh of several axes: each vertex's axis (float, 0 .. K − 1)
AXIS_ATTRIBUTE = "_AXIAL_AXIS"


def _child_columns(k: int) -> dict:
    """The instanced attributes of child axis ``k`` (1 ..): its ten offsets as VEC4, VEC4, VEC2."""
    return {f"_AXIAL_A{k}_D12": ("VEC4", 0), f"_AXIAL_A{k}_D34": ("VEC4", 4), f"_AXIAL_A{k}_D5": ("VEC2", 8)}


def encode_base_mesh(mesh) -> bytes:
    """The GLB bytes of the base mesh alone (one mesh, one node): POSITION and
    NORMAL float32 in the file's vertex order and its triangles, so the
    positions and faces hash to :attr:`BaseMesh.fingerprint` again (what the
    web page checks a parameter file against).  A mesh with appearance keeps
    it: one primitive per part (its triangles in order, so the parts' indices
    concatenated are the mesh's triangles) with its material (base colour
    factor and texture, alpha mode and cutoff, double-sidedness, normal map),
    TEXCOORD_0, COLOR_0 and TANGENT."""
    b = _Builder()
    g = b.g
    attributes = _vertex_attributes(b, mesh)  # before the appearance: the order earlier files have
    look = b.appearance(mesh)
    if "TEXCOORD_0" in look.attributes and mesh.tangents is not None:
        attributes["TANGENT"] = b.accessor(b.view(mesh.tangents.astype("<f4"), target=_ARRAY_BUFFER), _FLOAT,
                                           mesh.vertex_count, "VEC4", name="base_TANGENT")
    b.gltf.meshes.append(g.Mesh(name=str(mesh.name), primitives=look.primitives(attributes)))
    b.gltf.nodes.append(g.Node(name=str(mesh.name), mesh=0, extras={EXTRAS_KEY: _mesh_extras(mesh, 0, "base")}))
    b.gltf.scenes.append(g.Scene(name="axialdeform base mesh", nodes=[0]))
    b.gltf.scene = 0
    return b.finish()


def encode_instanced(mesh, params) -> bytes:
    """The GLB bytes of the instanced layout (see :func:`export_instanced`)."""
    b = _Builder()
    _add_instanced(b, mesh, params, "axialdeform instances")
    b.gltf.scenes.append(b.g.Scene(name="axialdeform instanced", nodes=[0]))
    b.gltf.scene = 0
    b.gltf.extensionsUsed = [INSTANCING, BEND_EXTENSION]
    return b.finish()


def _add_instanced(b: _Builder, mesh, params, node_name: str, *, color=None, extras=None) -> int:
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
        attributes["TANGENT"] = b.accessor(b.view(mesh.tangents.astype("<f4"), target=_ARRAY_BUFFER), _FLOAT,
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
        columns.update({name: (kind, flat[:, first:first + _COMPONENTS[kind]])
                        for name, (kind, first) in _child_columns(j).items()})
    attributes = {}
    for name, (kind, data) in columns.items():
        data = np.ascontiguousarray(data, dtype="<f4")
        attributes[name] = b.accessor(b.view(data), _FLOAT, n, kind, name=name)
    node_extras = _mesh_extras(mesh, n, "instanced")
    node_extras["attributes"] = {name: _field_names(cols) for name, (_k, cols) in {**ATTRIBUTES, **extra_attributes}.items()}
    if extra_attributes:
        node_extras["attributes"]["SCALE"] = ["s", "s", "s"]
    node_extras.update(extras or {})
    b.gltf.nodes.append(g.Node(name=node_name, mesh=len(b.gltf.meshes) - 1,
                               extensions={INSTANCING: {"attributes": attributes},
                                           BEND_EXTENSION: bend_extension(mesh, params.shape[1] + 10 * (k - 1))},
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
    ``node=LAYER`` reads a layer back).  Neither layout holds the scene's wind.
    """
    layers = _scene_layers(scene, layout)
    if layout == "instanced":
        return _encode_scene_instanced(scene, layers)
    return _build_scene_baked(scene, layers).finish()


def _scene_layers(scene, layout: str) -> list:
    if layout not in LAYOUTS:
        raise GltfError(f"layout: expected one of {', '.join(LAYOUTS)}, found {layout!r}")
    layers = [layer for layer in scene.layers if len(layer.params)]
    if scene.terrain is None and not layers:
        raise GltfError(f"{scene.path}: the scene has nothing to export; expected a terrain or a layer with instances")
    return layers


def _build_scene_baked(scene, layers) -> _Builder:
    """The baked layout of :func:`encode_scene`: per layer (and the terrain)
    one node and one mesh named after it holding every instance's deformed
    world geometry (POSITION, NORMAL, uint32 indices), a PBR material of the
    layer's colour (metallic 0, roughness 0.9); tinted instances: the colour
    times each one's tint as COLOR_0 (normalized uint8) under a white
    material.  The arrays are handed to the builder as they are (no copies):
    :func:`export_scene` streams them to the file."""
    b = _Builder()
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
        attributes = {"POSITION": b.accessor(b.view(flat, target=_ARRAY_BUFFER), _FLOAT, n * v, "VEC3",
                                             bounds=np.stack([flat.min(axis=0), flat.max(axis=0)]),
                                             name=f"{name}_POSITION"),
                      "NORMAL": b.accessor(b.view(nrm.reshape(-1, 3), target=_ARRAY_BUFFER), _FLOAT, n * v, "VEC3",
                                           name=f"{name}_NORMAL")}
        if tints is not None:  # the layer's colour times each instance's tint, per vertex
            rgba = np.empty((n, v, 4), dtype=np.uint8)
            rgba[..., :3] = np.rint(255 * np.clip(np.asarray(rgb) * tints, 0, 1))[:, None, :]
            rgba[..., 3] = 255
            acc = b.accessor(b.view(rgba.reshape(-1, 4), target=_ARRAY_BUFFER), _UINT8, n * v, "VEC4",
                             name=f"{name}_COLOR_0")
            b.gltf.accessors[acc].normalized = True
            attributes["COLOR_0"] = acc
            rgb = [1.0, 1.0, 1.0]
        ind = b.accessor(b.view(index.reshape(-1), target=_ELEMENT_ARRAY_BUFFER), _UINT32, index.size, "SCALAR",
                         name=f"{name}_indices")
        b.gltf.materials.append(g.Material(name=name, pbrMetallicRoughness=g.PbrMetallicRoughness(
            baseColorFactor=[*rgb, 1.0], metallicFactor=0.0, roughnessFactor=0.9)))
        b.gltf.meshes.append(g.Mesh(name=name, primitives=[g.Primitive(
            attributes=g.Attributes(**attributes), indices=ind, material=len(b.gltf.materials) - 1, mode=_TRIANGLES)]))
        b.gltf.nodes.append(g.Node(name=name, mesh=len(b.gltf.meshes) - 1))
    b.gltf.scenes.append(g.Scene(nodes=list(range(len(b.gltf.nodes)))))
    b.gltf.scene = 0
    return b


def _encode_scene_instanced(scene, layers) -> bytes:
    """The instanced layout of :func:`encode_scene`."""
    b = _Builder()
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
        nodes.append(_add_instanced(b, layer.mesh, layer.params, layer.name,
                                    color=layer.color if layer.color is not None else (0.6, 0.6, 0.6),
                                    extras={"layer": layer.name}))
    b.gltf.scenes.append(g.Scene(name="axialdeform scene, instanced", nodes=nodes, extras={EXTRAS_KEY: {
        "version": _FORMAT_VERSION, "layout": "instanced", "layers": [layer.name for layer in layers],
        "up": scene.up}}))
    b.gltf.scene = 0
    if layers:
        b.gltf.extensionsUsed = [INSTANCING, BEND_EXTENSION]
    return b.finish()


def export_scene(path: str | os.PathLike, scene, layout: str = "baked") -> Path:
    """Write :func:`encode_scene` (``layout`` ``"baked"`` or ``"instanced"``) to ``path`` (a ``.glb``), atomically."""
    path = check_glb_path(path)
    layers = _scene_layers(scene, layout)
    if layout == "instanced":
        atomic_write_bytes(path, _encode_scene_instanced(scene, layers))
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
    """Write ``params`` for ``mesh`` as a GLB in ``layout`` ``"baked"`` or ``"instanced"``
    (``source``: the parameter file, named in errors)."""
    if layout == "baked":
        return export_baked(path, mesh, params, source=source)
    if layout == "instanced":
        return export_instanced(path, mesh, params)
    raise GltfError(f"layout: expected one of {', '.join(LAYOUTS)}, found {layout!r}")


# --------------------------------------------------------------------- reading


def read_accessor(gltf, blob: bytes, index, name: str, where: str) -> np.ndarray:
    """One accessor of a loaded pygltflib ``GLTF2`` over ``blob`` (buffer 0) as
    a ``(count, components)`` array (normalized integers as floats);
    :class:`GltfError` naming ``where`` and ``name`` if it cannot be read."""
    if not isinstance(index, int) or not 0 <= index < len(gltf.accessors):
        raise GltfError(f"{where}: {name}: expected an accessor index, found {index!r}")
    acc = gltf.accessors[index]
    if acc.componentType not in _DTYPES or acc.type not in _COMPONENTS or acc.bufferView is None:
        raise GltfError(f"{where}: {name}: unsupported accessor ({acc.type} of component type {acc.componentType}, "
                        f"bufferView {acc.bufferView})")
    view = gltf.bufferViews[acc.bufferView]
    dtype = np.dtype(_DTYPES[acc.componentType]).newbyteorder("<")
    comps = _COMPONENTS[acc.type]
    item = dtype.itemsize * comps
    stride = view.byteStride or item
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    need = start + (acc.count - 1) * stride + item if acc.count else start
    if need > (view.byteOffset or 0) + view.byteLength or need > len(blob):
        raise GltfError(f"{where}: {name}: accessor {index} runs past its bufferView (truncated file?)")
    arr = np.ndarray((acc.count, comps), dtype=dtype, buffer=blob, offset=start, strides=(stride, dtype.itemsize))
    out = np.array(arr)
    if acc.normalized and dtype.kind in "iu":
        info = np.iinfo(dtype)
        out = np.maximum(out.astype(np.float64) / info.max, -1.0) if dtype.kind == "i" else out / info.max
    return out


def read_instanced_glb(path: str | os.PathLike, node: str | None = None):
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

    Raises :class:`GltfError` for a file without an instanced node, and
    :class:`MeshMismatchError` if the recorded fingerprint does not match
    the base mesh in the file.
    """
    path = Path(path)
    where = str(path)
    gltf = _load_glb(path)
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
    attrs = node.extensions[INSTANCING].get("attributes", {})
    missing = [k for k in ("TRANSLATION", "_AXIAL_D12", "_AXIAL_D34", "_AXIAL_D5") if k not in attrs]
    if missing or ("_AXIAL_ANGLES" not in attrs and "ROTATION" not in attrs):
        raise GltfError(f"{where}: {INSTANCING} attributes: expected TRANSLATION, ROTATION and "
                        f"{', '.join(ATTRIBUTES)}; missing {', '.join(missing) or 'ROTATION'}")
    cols = {name: read_accessor(gltf, blob, attrs[name], name, where) for name in attrs}
    counts = {len(v) for v in cols.values()}
    if len(counts) != 1:
        raise GltfError(f"{where}: {INSTANCING} attributes have different counts {sorted(counts)}; expected one count")
    n = counts.pop()
    tint_name, tint_kind, tint_cols = GLTF_TINT_ATTRIBUTE
    tinted = tint_name in cols
    extended = tinted or "SCALE" in cols or "_AXIAL_TWIST_TAPER" in cols
    params = np.zeros((n, WIDTHS[2 if tinted else 1 if extended else 0]), dtype=np.float32)
    if extended:
        params[:, SCALE] = 1.0
        for name, (kind, idx) in {**EXTENDED_ATTRIBUTES, **({tint_name: (tint_kind, tint_cols)} if tinted else {})}.items():
            if name in cols:
                if cols[name].shape[1] != _COMPONENTS[kind]:
                    raise GltfError(f"{where}: {name}: expected {kind}, found {cols[name].shape[1]} components")
                params[:, list(idx)] = cols[name]
        if "SCALE" in cols:
            sc = cols["SCALE"]
            if sc.shape[1] != 3 or not (sc == sc[:, :1]).all():
                raise GltfError(f"{where}: SCALE: expected a uniform scale (VEC3 with three equal components) per instance")
            params[:, SCALE] = sc[:, 0]
    for name, (kind, idx) in ATTRIBUTES.items():
        if name in cols:
            if cols[name].shape[1] != _COMPONENTS[kind]:
                raise GltfError(f"{where}: {name}: expected {kind}, found {cols[name].shape[1]} components")
            params[:, list(idx)] = cols[name]
    params[:, POSITION] = cols["TRANSLATION"]
    if "_AXIAL_ANGLES" not in cols:

        params[:, ANGLES] = angles_from_matrices(matrices_from_quaternions(cols["ROTATION"]))

    mesh_def = gltf.meshes[node.mesh]
    if not mesh_def.primitives:
        raise GltfError(f"{where}: mesh {node.mesh}: expected at least one primitive, found none")
    prim = mesh_def.primitives[0]
    for other in mesh_def.primitives:  # one primitive per part, all over the same vertices
        if other.mode not in (None, _TRIANGLES) or other.indices is None:
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
    mesh = BaseMesh(positions, normals, faces, name=where, normals_from_file=from_file)
    extras = (node.extras or {}).get(EXTRAS_KEY, {})
    recorded = extras.get("mesh_fingerprint")
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


def _read_tree(gltf, blob, prim, record, cols, mesh, params, where):
    """The mesh of several axes an instanced node records (extras ``axes``,
    the vertex attribute ``_AXIAL_AXIS``, the instanced ``_AXIAL_A{k}_*``)."""
    from ..axes import tree_from_vertices

    try:
        k = int(record["count"])
        parents, frames, names = list(record["parents"]), list(record["frames"]), list(record["names"])
    except (KeyError, TypeError, ValueError):
        raise GltfError(f"{where}: extras axes: expected count, names, parents and frames, found {record!r}"[:300]) from None
    index = getattr(prim.attributes, AXIS_ATTRIBUTE, None)
    if index is None:
        raise GltfError(f"{where}: a mesh of {k} axes needs the vertex attribute {AXIS_ATTRIBUTE}; found none")
    va = read_accessor(gltf, blob, index, AXIS_ATTRIBUTE, where).reshape(-1)
    if len(va) != mesh.vertex_count or not np.array_equal(va, np.round(va)):
        raise GltfError(f"{where}: {AXIS_ATTRIBUTE}: expected one whole axis index per vertex ({mesh.vertex_count})")
    n = len(params)
    children = np.zeros((n, k - 1, 10), dtype=np.float32)
    for j in range(1, k):
        for name, (kind, first) in _child_columns(j).items():
            if name not in cols or cols[name].shape[1] != _COMPONENTS[kind]:
                raise GltfError(f"{where}: {INSTANCING} attributes: expected {name} ({kind}) for axis {j}")
            children[:, j - 1, first:first + _COMPONENTS[kind]] = cols[name]
    try:
        tree = tree_from_vertices(mesh, va.astype(np.int64), parents, frames=[np.asarray(f) for f in frames],
                                  names=names, root_children=False)
        mesh = mesh.with_axes(tree)
    except AxialDeformError as exc:
        raise GltfError(f"{where}: extras axes: {exc}") from None
    return mesh, as_params(join_record(params, children), name=where, axes=k)


def _load_glb(path: Path):
    """A GLB parsed by pygltflib from bytes read through the bounded reader
    (a regular file, at most half the memory available); :class:`GltfError`
    naming the file otherwise."""
    import pygltflib

    where = str(path)
    try:
        data = safeio.read_regular(path, max(safeio.memory_available() // 2, 1 << 20), "a binary glTF file (.glb)",
                                   GltfError)
    except OSError as exc:
        raise GltfError(f"{where}: cannot read: {exc.strerror}") from None
    try:
        with _quiet_pygltflib():
            gltf = pygltflib.GLTF2.load_from_bytes(bytes(data))
    except Exception as exc:  # pygltflib raises IOError, struct.error, JSON errors
        raise GltfError(f"{where}: not a binary glTF file: {error_in_words(exc, 'glb')}") from None
    if gltf is None:  # what pygltflib returns for bytes it does not recognise
        raise GltfError(f"{where}: not a binary glTF file (no glTF content)")
    return gltf


@contextlib.contextmanager
def _quiet_pygltflib():
    """pygltflib's warnings (and prints) while it parses: what matters is
    checked and said by this module, in its own words, once."""
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        yield


def read_extras(path: str | os.PathLike) -> dict:
    """The ``extras["axialdeform"]`` dictionaries of a GLB's scenes and nodes (for tools and tests)."""
    gltf = _load_glb(Path(path))
    out = {}
    for kind, items in (("scene", gltf.scenes), ("node", gltf.nodes)):
        for k, item in enumerate(items):
            if item.extras and EXTRAS_KEY in item.extras:
                out[f"{kind}/{k}"] = json.loads(json.dumps(item.extras[EXTRAS_KEY]))
    return out


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
            with _quiet_pygltflib():
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

"""The GLB container as this library writes and reads it: glTF's enums, a builder of binary
buffers, accessors and appearance (materials, textures, images), and reading an accessor back
with its bounds checked.  :mod:`.gltf` exports meshes and instances with it; :mod:`.gltf_read`
reads them back."""

from __future__ import annotations

import contextlib
import copy
import io
import struct
import warnings
from pathlib import Path

import numpy as np
from PIL import Image

from ..errors import GltfError
from ..material import Material
from ..material import default_color as default_color_of
from ..record import (
    GLTF_ATTRIBUTES,
    GLTF_EXTENDED_ATTRIBUTES,
)
from . import safeio
from .resolver import error_in_words

__all__ = [
    "LAYOUTS", "INSTANCING", "EXTRAS_KEY", "BEND_EXTENSION", "ATTRIBUTES", "EXTENDED_ATTRIBUTES", "FORMAT_VERSION",
    "FLOAT", "UINT8", "UINT16", "UINT32", "ARRAY_BUFFER", "ELEMENT_ARRAY_BUFFER", "TRIANGLES", "COMPONENTS", "DTYPES",
    "GlbBuilder", "png_bytes", "image_bytes", "Appearance", "AXIS_ATTRIBUTE", "child_columns", "read_accessor",
    "load_glb", "quiet_pygltflib",
]


LAYOUTS = ("baked", "instanced", "generated")  # generated: a scene's generated layers as their recipe
#: the glTF extension that draws one mesh many times
INSTANCING = "EXT_mesh_gpu_instancing"
#: key of the dictionary this library writes into ``extras``
EXTRAS_KEY = "axialdeform"
#: the vendor extension carrying the bend on an instancing node (docs/gltf/AXIALDEFORM_bend)
BEND_EXTENSION = "AXIALDEFORM_bend"
#: the application-specific per-instance attributes (from the record table)
ATTRIBUTES = GLTF_ATTRIBUTES
EXTENDED_ATTRIBUTES = GLTF_EXTENDED_ATTRIBUTES
FORMAT_VERSION = 1

# glTF enums
FLOAT, UINT8, UINT16, UINT32 = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
TRIANGLES = 4
COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}


class GlbBuilder:
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
        view = self.view(data, target=ELEMENT_ARRAY_BUFFER)
        return self.accessor(view, UINT16 if small else UINT32, data.size, "SCALAR", name=name)

    def appearance(self, mesh, default_color=None, plain: bool = False) -> Appearance:
        """The mesh's parts (indices + material each) and its UV/colour accessors,
        written once; ``default_color`` (linear RGB) replaces a default material (else the colour
        ``render`` draws it with); ``plain``: a mesh of one default part gets no material (the
        page's base mesh: the page colours it)."""
        return Appearance(self, mesh, default_color, plain)

    def write_to(self, fh) -> None:
        """The GLB into the binary file ``fh``, chunk after chunk: the binary
        buffer is never joined in memory (what pygltflib's ``save_to_bytes``
        writes, byte for byte)."""

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


def png_bytes(pixels: np.ndarray) -> bytes:
    hit = _PNG_CACHE.get(id(pixels))
    if hit is not None and hit[0] is pixels:
        return hit[1]
    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(pixels, dtype=np.uint8), "RGBA").save(out, format="PNG")
    if len(_PNG_CACHE) >= _PNG_CACHE_MAX:
        _PNG_CACHE.pop(next(iter(_PNG_CACHE)))
    _PNG_CACHE[id(pixels)] = (pixels, out.getvalue())
    return out.getvalue()


def image_bytes(m, key: str) -> tuple[bytes, str]:
    """The image of material ``m``'s ``key`` texture as a glTF carries it: the
    model's own PNG or JPEG bytes when it has them (a JPEG stays that JPEG),
    else the pixels encoded as PNG (once)."""
    source = m.sources.get(key)
    if source is not None:
        return source
    return png_bytes(getattr(m, key)), "image/png"


class Appearance:
    """glTF objects for a base mesh's appearance: per part an index accessor
    and a material (base colour factor + embedded PNG texture, alpha mode and
    cutoff, double-sidedness, normal map), shared TEXCOORD_0 (glTF's ``v``
    points down the image: ``1 - v``) and COLOR_0 (linear RGBA float)."""

    def __init__(self, b: GlbBuilder, mesh, default_color=None, plain: bool = False) -> None:
        g = b.g
        self.mesh = mesh
        self.attributes: dict[str, int] = {}
        if mesh.uvs is not None:
            uv = np.column_stack([mesh.uvs[:, 0], 1.0 - mesh.uvs[:, 1]]).astype("<f4")
            self.attributes["TEXCOORD_0"] = b.accessor(b.view(uv, target=ARRAY_BUFFER), FLOAT, len(uv), "VEC2",
                                                       name="TEXCOORD_0")
        if mesh.colors is not None:
            col = np.clip(mesh.colors, 0.0, 1.0).astype("<f4")
            self.attributes["COLOR_0"] = b.accessor(b.view(col, target=ARRAY_BUFFER), FLOAT, len(col), "VEC4",
                                                    name="COLOR_0")
        self.parts = []  # (name, indices accessor, material index or None)
        self._tinted: dict = {}  # (material index or None, tint) -> material index
        materials: dict[int, int] = {}
        single = len(mesh.parts) == 1
        if default_color is None and not plain:  # what render draws a part without a material with,
            default_color = default_color_of(mesh)  # dielectric (glTF's own is white, metallic 1: black in three.js)
        for part in mesh.parts:
            if part.count == 0:
                continue
            m = part.material
            if m.is_default and default_color is not None:  # a layer's colour, or render's; both sides lit, as render
                m = Material(name=part.name if not single else str(getattr(mesh, "name", "mesh")),
                             base_color=[*default_color[:3], 1.0], double_sided=True)
                part_key = ("color", part.name)
            else:
                part_key = id(m)
            if part_key not in materials and not (plain and single and m.is_default):
                materials[part_key] = self._material(b, m)
            faces = mesh.faces[part.start:part.start + part.count]
            idx = b.indices(mesh, faces, name="indices" if single else f"{part.name}_indices")
            self.parts.append((part.name, idx, materials.get(part_key)))
        if b.gltf.textures:
            b.gltf.samplers = [g.Sampler(magFilter=9729, minFilter=9987, wrapS=10497, wrapT=10497)]

    def _texture(self, b: GlbBuilder, m, key: str, name: str) -> int:
        g = b.g
        data, mime = image_bytes(m, key)
        view = b.view(np.frombuffer(data, dtype=np.uint8))
        b.gltf.images.append(g.Image(bufferView=view, mimeType=mime, name=name))
        b.gltf.textures.append(g.Texture(sampler=0, source=len(b.gltf.images) - 1, name=name))
        return len(b.gltf.textures) - 1

    def _material(self, b: GlbBuilder, m) -> int:
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

    def primitives(self, attributes: dict, b: GlbBuilder | None = None, tint=None) -> list:
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
            out.append(g.Primitive(attributes=attrs, indices=idx, material=material, mode=TRIANGLES))
        return out

    def _tinted_material(self, b: GlbBuilder, material: int | None, tint) -> int:
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


#: the vertex attribute of a mesh of several axes: each vertex's axis (float, 0 .. K − 1)
AXIS_ATTRIBUTE = "_AXIAL_AXIS"


def child_columns(k: int) -> dict:
    """The instanced attributes of child axis ``k`` (1 ..): its ten offsets as VEC4, VEC4, VEC2."""
    return {f"_AXIAL_A{k}_D12": ("VEC4", 0), f"_AXIAL_A{k}_D34": ("VEC4", 4), f"_AXIAL_A{k}_D5": ("VEC2", 8)}


def read_accessor(gltf, blob: bytes, index, name: str, where: str) -> np.ndarray:
    """One accessor of a loaded pygltflib ``GLTF2`` over ``blob`` (buffer 0) as
    a ``(count, components)`` array (normalized integers as floats);
    :class:`GltfError` naming ``where`` and ``name`` if it cannot be read."""
    if not isinstance(index, int) or not 0 <= index < len(gltf.accessors):
        raise GltfError(f"{where}: {name}: expected an accessor index, found {index!r}")
    acc = gltf.accessors[index]
    raw = getattr(gltf, "raw_accessors", [])
    raw = raw[index] if index < len(raw) and isinstance(raw[index], dict) else {}
    for key in ("bufferView", "byteOffset", "componentType", "count"):
        value = raw.get(key)
        if value is not None and (not isinstance(value, int) or isinstance(value, bool)):
            raise GltfError(f"{where}: {name}: accessor {index} {key}: expected a whole number, found {value!r:.40}")
    if acc.componentType not in DTYPES or acc.type not in COMPONENTS or acc.bufferView is None:
        raise GltfError(f"{where}: {name}: unsupported accessor ({acc.type} of component type {acc.componentType}, "
                        f"bufferView {acc.bufferView})")
    if not (isinstance(acc.count, int) and 0 <= acc.count <= len(blob)):
        raise GltfError(f"{where}: {name}: accessor {index} count: expected a whole number 0..{len(blob)} (what the "
                        f"binary chunk can hold), found {acc.count!r:.40}")
    if not (isinstance(acc.bufferView, int) and 0 <= acc.bufferView < len(gltf.bufferViews)):
        raise GltfError(f"{where}: {name}: accessor {index} bufferView: expected 0..{len(gltf.bufferViews) - 1}, "
                        f"found {acc.bufferView!r:.40}")
    view = gltf.bufferViews[acc.bufferView]
    offsets = (acc.byteOffset or 0, view.byteOffset or 0)
    if not all(isinstance(x, int) and x >= 0 for x in offsets):
        raise GltfError(f"{where}: {name}: accessor {index} byteOffset: expected whole numbers >= 0 (the accessor's "
                        f"and its bufferView's), found {offsets!r:.60}")
    dtype = np.dtype(DTYPES[acc.componentType]).newbyteorder("<")
    comps = COMPONENTS[acc.type]
    item = dtype.itemsize * comps
    stride = view.byteStride or item
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    if start % dtype.itemsize or stride % dtype.itemsize:  # the glTF rule; a typed array in JavaScript needs it
        raise GltfError(f"{where}: {name}: accessor {index} byteOffset: expected a multiple of {dtype.itemsize} (the "
                        f"component's size), found {start}")
    need = start + (acc.count - 1) * stride + item if acc.count else start
    if need > (view.byteOffset or 0) + view.byteLength or need > len(blob):
        raise GltfError(f"{where}: {name}: accessor {index} runs past its bufferView (truncated file?)")
    arr = np.ndarray((acc.count, comps), dtype=dtype, buffer=blob, offset=start, strides=(stride, dtype.itemsize))
    out = np.array(arr)
    if acc.normalized and dtype.kind in "iu":
        info = np.iinfo(dtype)
        out = np.maximum(out.astype(np.float64) / info.max, -1.0) if dtype.kind == "i" else out / info.max
    return out


def load_glb(path: Path):
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
        with quiet_pygltflib():
            gltf = pygltflib.GLTF2.load_from_bytes(bytes(data))
    except Exception as exc:  # pygltflib raises IOError, struct.error, JSON errors
        raise GltfError(f"{where}: not a binary glTF file: {error_in_words(exc, 'glb')}") from None
    if gltf is None:  # what pygltflib returns for bytes it does not recognise
        raise GltfError(f"{where}: not a binary glTF file (no glTF content)")
    gltf.raw_accessors = _raw_accessors(data)
    return gltf


def _raw_accessors(data) -> list:
    """The accessors as the file's JSON has them (pygltflib turns ``"0"`` into 0; a JavaScript
    loader does not): what :func:`read_accessor` checks an accessor's whole numbers against."""
    import json

    try:
        (length,) = struct.unpack_from("<I", data, 12)
        doc = json.loads(bytes(data[20:20 + length]))
    except (struct.error, ValueError):
        return []  # pygltflib read it: nothing more to say here
    accessors = doc.get("accessors") if isinstance(doc, dict) else None
    return accessors if isinstance(accessors, list) else []


@contextlib.contextmanager
def quiet_pygltflib():
    """pygltflib's warnings (and prints) while it parses: what matters is
    checked and said by this module, in its own words, once."""
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        yield

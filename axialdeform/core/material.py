"""Appearance of a base mesh: UVs, vertex colours, materials and parts.

Everything here is read through trimesh's visuals and materials (no
hand-written file parser):

* :class:`Material` — base colour factor (linear RGBA) and texture (sRGB
  RGBA pixels), alpha mode (``OPAQUE``, ``MASK`` with ``alpha_cutoff``,
  ``BLEND``), double-sidedness and a normal map (linear RGB pixels);
* :class:`Part` — a contiguous range of the base mesh's triangles drawn with
  one material (a glTF primitive, an OBJ ``usemtl`` group);
* :func:`gather_parts` — every triangle mesh of a loaded trimesh scene, node
  transforms applied, concatenated into ONE vertex/face set with its parts,
  UVs, colours and (where a normal map asks) tangents;
* :func:`compute_tangents` — per-vertex tangents ``(n, 4)`` (xyz + handedness
  w) from positions, normals, UVs and triangles, vectorized.

A texture file that is missing, unreadable or not a regular file (a FIFO, a
device) is never opened: :class:`SafeResolver` checks first, the loader warns
(:class:`AssetWarning`, naming the file and the material) and the part is
drawn with its base colour.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

from .errors import MeshError

__all__ = [
    "Material", "Part", "AssetWarning", "ALPHA_MODES", "DEFAULT_MATERIAL", "gather_parts", "compute_tangents",
    "srgb_to_linear", "linear_to_srgb",
]

ALPHA_MODES = ("OPAQUE", "MASK", "BLEND")


class AssetWarning(UserWarning):
    """Something of a mesh's appearance could not be used (a texture file);
    the mesh still loads and the part is drawn with its base colour."""


def srgb_to_linear(c):
    """sRGB-encoded values in 0..1 to linear (the exact piecewise curve)."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c):
    """Linear values in 0..1 to sRGB encoding (the exact piecewise curve)."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


@dataclass(frozen=True, eq=False)
class Material:
    """How one part looks (the glTF metallic-roughness subset we draw).

    Attributes
    ----------
    name : str
    base_color : (4,) float32
        Linear RGBA factor (glTF ``baseColorFactor``), multiplied with the
        texture and the vertex colour.
    texture : (h, w, 4) uint8 or None
        sRGB-encoded RGBA pixels of the base colour texture, first row at the
        top of the image (glTF/OBJ UV ``v = 0`` is the image's top after the
        loader's flip; see :func:`gather_parts`).
    texture_name : str or None
        Where the texture came from (a file name, or ``"embedded"``).
    alpha_mode : str
        ``"OPAQUE"``, ``"MASK"`` (fragments with alpha < ``alpha_cutoff`` are
        discarded) or ``"BLEND"`` (drawn after opaque parts, unsorted).
    alpha_cutoff : float
    double_sided : bool
        Light the back of a face as its front and never cull it.
    normal_texture : (h, w, 4) uint8 or None
        Tangent-space normal map (linear).
    sources : dict
        ``{"texture" | "normal_texture": (bytes, mime type)}``: the image
        files those pixels were decoded from, exactly (a PNG or JPEG of the
        model), so exports carry them as they came instead of encoding
        again.  Not part of equality.
    """

    name: str = "default"
    base_color: np.ndarray = field(default_factory=lambda: np.ones(4, dtype=np.float32))
    texture: np.ndarray | None = None
    texture_name: str | None = None
    alpha_mode: str = "OPAQUE"
    alpha_cutoff: float = 0.5
    double_sided: bool = False
    normal_texture: np.ndarray | None = None
    sources: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        color = np.asarray(self.base_color, dtype=np.float32).reshape(-1)
        if color.size == 3:
            color = np.append(color, np.float32(1.0))
        if color.shape != (4,) or not np.isfinite(color).all():
            raise MeshError(f"material {self.name!r}: base colour: expected 3 or 4 finite numbers, found {self.base_color!r}")
        object.__setattr__(self, "base_color", color)
        if self.alpha_mode not in ALPHA_MODES:
            raise MeshError(f"material {self.name!r}: alpha mode: expected one of {', '.join(ALPHA_MODES)}, found {self.alpha_mode!r}")
        for key in ("texture", "normal_texture"):
            img = getattr(self, key)
            if img is not None:
                img = np.ascontiguousarray(img, dtype=np.uint8)
                if img.ndim != 3 or img.shape[2] != 4 or img.shape[0] == 0 or img.shape[1] == 0:
                    raise MeshError(f"material {self.name!r}: {key}: expected (h, w, 4) uint8 pixels, found {img.shape}")
                object.__setattr__(self, key, img)

    @property
    def is_default(self) -> bool:
        """True for a white, opaque, single-sided, untextured material."""
        return (self.texture is None and self.normal_texture is None and self.alpha_mode == "OPAQUE"
                and not self.double_sided and bool(np.all(self.base_color == 1.0)))


DEFAULT_MATERIAL = Material()

#: the colour (linear RGB) a part with the default material is drawn with: the bundled meshes' own,
#: else stone grey.  ``render``, the page and exports (a GLB's material) all take it from here.
DEFAULT_COLORS = {"stone": (0.46, 0.44, 0.41), "leaf": (0.30, 0.52, 0.12)}
FALLBACK_COLOR = (0.46, 0.44, 0.41)


def default_color(mesh) -> tuple:
    """(3,) linear RGB: what a part of ``mesh`` without a material of its own is drawn with."""
    return DEFAULT_COLORS.get(str(getattr(mesh, "name", "")), FALLBACK_COLOR)


@dataclass(frozen=True)
class Part:
    """Triangles ``start .. start + count - 1`` of a base mesh, drawn with ``material``."""

    name: str
    start: int
    count: int
    material: Material = DEFAULT_MATERIAL


# --------------------------------------------------------------------- files


# --------------------------------------------------------------------- visuals


#: the largest texture decoded, in pixels (64 MP, 256 MB as RGBA); the environment
#: variable ``AXIALDEFORM_MAX_TEXTURE_PIXELS`` raises (or lowers) it
MAX_TEXTURE_PIXELS = 8192 * 8192


def max_texture_pixels() -> int:
    """:data:`MAX_TEXTURE_PIXELS`, or ``AXIALDEFORM_MAX_TEXTURE_PIXELS`` when set to a whole number."""
    value = os.environ.get("AXIALDEFORM_MAX_TEXTURE_PIXELS", "")
    return int(value) if value.strip().isdigit() else MAX_TEXTURE_PIXELS


#: the image formats glTF carries as they are (others are encoded as PNG)
_GLTF_MIME = {"PNG": "image/png", "JPEG": "image/jpeg"}


def _source(image) -> tuple[bytes, str] | None:
    """The bytes a PIL image was opened from (a PNG or JPEG that trimesh read
    from the model) with its mime type, or None."""
    import io

    fp, mime = getattr(image, "fp", None), _GLTF_MIME.get(getattr(image, "format", None) or "")
    if mime is None or not isinstance(fp, io.BytesIO):
        return None
    data = fp.getvalue()
    # the image ends at its own end marker (a buffer view may carry padding after it)
    end, size = (data.rfind(b"IEND"), 8) if mime == "image/png" else (data.rfind(b"\xff\xd9"), 2)
    return (data[:end + size] if end >= 0 else data), mime


#: False while a mesh is loaded for a command that neither draws nor writes
#: its textures (``load_mesh(..., textures=False)``): no pixel is decoded
_DECODE_TEXTURES = contextvars.ContextVar("axialdeform_decode_textures", default=True)


@contextlib.contextmanager
def texture_decoding(on: bool):
    """Within it, :func:`_pixels` decodes textures (``on``) or leaves every
    one out (the parts keep their base colours; shapes and vertex order are
    the same either way, so is the fingerprint)."""
    token = _DECODE_TEXTURES.set(bool(on))
    try:
        yield
    finally:
        _DECODE_TEXTURES.reset(token)


def _pixels(image, where: str = "") -> np.ndarray | None:
    """A PIL image (or None) as (h, w, 4) uint8 RGBA.  Its size is read from
    the header first: an image over :func:`max_texture_pixels` is not decoded
    (an :class:`AssetWarning` naming ``where``; the part keeps its base colour)."""
    if image is None or not _DECODE_TEXTURES.get():
        return None
    size = getattr(image, "size", None)
    if size is not None and int(size[0]) * int(size[1]) > max_texture_pixels():
        warnings.warn(AssetWarning(
            f"{where}: a texture of {size[0]}x{size[1]} pixels is over the budget of {max_texture_pixels()} pixels "
            "(AXIALDEFORM_MAX_TEXTURE_PIXELS raises it); not decoded, drawn with its base colour"), stacklevel=2)
        return None
    try:
        return np.asarray(image.convert("RGBA"), dtype=np.uint8)
    except Exception:  # a broken embedded image: treated as missing
        return None


def _material_of(visual, fallback_name: str, file_name: str = "") -> Material:
    import trimesh

    mat = getattr(visual, "material", None)
    if mat is None:
        return Material(name=fallback_name)
    if isinstance(mat, trimesh.visual.material.SimpleMaterial):
        name = mat.name or fallback_name
        diffuse = np.asarray(getattr(mat, "diffuse", (255, 255, 255, 255)), dtype=np.float64).reshape(-1)[:4] / 255.0
        color = np.concatenate([srgb_to_linear(diffuse[:3]), diffuse[3:4] if diffuse.size > 3 else [1.0]])
        source = _source(getattr(mat, "image", None))
        texture = _pixels(getattr(mat, "image", None), f"{file_name}: material {name!r}")
        if texture is not None and (texture == texture[0, 0]).all():
            # one colour (trimesh's stand-in for "no material"): the base colour says the same
            px = texture[0, 0].astype(np.float64) / 255.0
            texture = None
            if np.abs(px * 255 - np.asarray(trimesh.visual.DEFAULT_COLOR, dtype=np.float64)).max() > 3.0:
                color = np.concatenate([srgb_to_linear(px[:3]), px[3:4]])
            else:  # no material at all
                return Material(name=name)
        # a texture replaces the diffuse colour of the .mtl (what viewers show)
        if texture is not None:
            color = np.array([1.0, 1.0, 1.0, color[3]])
        alpha_mode = "OPAQUE"
        if texture is not None and (texture[..., 3] < 255).any():
            alpha_mode = "MASK"  # an OBJ texture with holes: a cut-out
        elif color[3] < 1.0:
            alpha_mode = "BLEND"
        # OBJ has no notion of sides; viewers light both (as the plain path does)
        return Material(name=name, base_color=color, texture=texture,
                        texture_name=None if texture is None else "map_Kd", alpha_mode=alpha_mode,
                        double_sided=True, sources={} if texture is None or source is None else {"texture": source})
    # PBRMaterial
    name = getattr(mat, "name", None) or fallback_name
    factor = getattr(mat, "baseColorFactor", None)
    # trimesh keeps glTF's linear factor as uint8 0..255
    color = np.ones(4) if factor is None else np.asarray(factor, dtype=np.float64).reshape(-1)[:4] / 255.0
    sources = {key: src for key, img in (("texture", getattr(mat, "baseColorTexture", None)),
                                         ("normal_texture", getattr(mat, "normalTexture", None)))
               if (src := _source(img)) is not None}
    texture = _pixels(getattr(mat, "baseColorTexture", None), f"{file_name}: material {name!r}")
    normal = _pixels(getattr(mat, "normalTexture", None), f"{file_name}: material {name!r}, normal map")
    sources = {k: v for k, v in sources.items() if (texture if k == "texture" else normal) is not None}
    cutoff = getattr(mat, "alphaCutoff", None)
    return Material(name=name, base_color=color, texture=texture,
                    texture_name=None if texture is None else "embedded",
                    alpha_mode=(getattr(mat, "alphaMode", None) or "OPAQUE").upper(),
                    alpha_cutoff=0.5 if cutoff is None else float(cutoff),
                    double_sided=bool(getattr(mat, "doubleSided", False)),
                    normal_texture=normal, sources=sources)


def _uvs_of(geom, n: int, file_name: str) -> np.ndarray | None:
    uv = getattr(geom.visual, "uv", None)
    if uv is None:
        return None
    uv = np.asarray(uv, dtype=np.float64)
    if uv.ndim != 2 or uv.shape[1] < 2 or len(uv) != n:
        raise MeshError(f"{file_name}: {len(uv)} texture coordinates for {n} vertices; expected one (u, v) per vertex")
    uv = uv[:, :2]
    if not np.isfinite(uv).all():
        raise MeshError(f"{file_name}: a texture coordinate is not a finite number")
    # trimesh flips glTF's v (top-down) to OBJ's bottom-up convention; we keep
    # OBJ's: v = 0 is the bottom row of the image
    return uv


def _colors_of(geom, n: int, file_name: str) -> np.ndarray | None:
    visual = geom.visual
    colors = None
    if getattr(visual, "kind", None) == "vertex" and hasattr(visual, "vertex_colors"):
        colors = visual.vertex_colors
    else:
        attrs = getattr(visual, "vertex_attributes", None) or {}
        if "color" in attrs:
            colors = attrs["color"]
    if colors is None:
        return None
    colors = np.asarray(colors)
    if colors.ndim != 2 or colors.shape[1] not in (3, 4) or len(colors) != n:
        raise MeshError(f"{file_name}: {len(colors)} vertex colours for {n} vertices; expected one colour per vertex")
    c = colors.astype(np.float64)
    if colors.dtype.kind in "ui":
        c = c / 255.0
    if c.shape[1] == 3:
        c = np.hstack([c, np.ones((n, 1))])
    if not np.isfinite(c).all():
        raise MeshError(f"{file_name}: a vertex colour is not a finite number")
    # vertex colours are sRGB-encoded in files; we keep them linear
    c[:, :3] = srgb_to_linear(np.clip(c[:, :3], 0.0, 1.0))
    return c


def _geometry_nodes(graph, file_name: str) -> list:
    """``[(node, world transform (4, 4), geometry name, parent), ...]`` of every node
    that carries geometry, by ONE walk of the scene graph from its root (what
    ``graph[node]`` gives, without walking from the root again for each node:
    a chain of 5 000 nested nodes took 202 s that way).  A node reached twice
    or never (a cycle) is a :class:`MeshError` naming the file."""
    forest = graph.transforms
    children, edges = forest.children, forest.edge_data
    world = {graph.base_frame: np.eye(4)}
    stack, out = [graph.base_frame], []
    while stack:
        parent = stack.pop()
        for child in children.get(parent, ()):
            if child in world:
                raise MeshError(f"{file_name}: the node graph reaches node {child!r} twice (a cycle); expected a tree")
            data = edges.get((parent, child), {})
            matrix = data.get("matrix")
            world[child] = world[parent] if matrix is None else world[parent] @ np.asarray(matrix, dtype=np.float64)
            if data.get("geometry") is not None:
                out.append((child, world[child], data["geometry"], parent))
            stack.append(child)
    missing = set(graph.nodes_geometry) - {node for node, _, _, _ in out}
    if missing:
        raise MeshError(f"{file_name}: nodes {', '.join(sorted(map(repr, missing))[:3])} are never reached from the "
                        "scene's root (a cycle in the node graph); expected a tree")
    return out


#: trimesh names the frame of a glTF mesh's second, third ... primitive ``NODE_xxxxxx``
#: with 6 random hex digits: a name that changes on every load
_RANDOM_FRAME = re.compile(r"^(?P<parent>.+)_[0-9a-f]{6}$")


def _stable_names(placed) -> list[str]:
    """The node names of ``placed`` (file order), trimesh's random primitive
    frames replaced by ``NODE_k``: the node's name and the primitive's index
    among the node's primitives, so a file loads with the same part names
    (and fingerprint) every time."""
    names = [str(node) for node, _, _, _ in placed]
    count: dict[str, int] = {}
    for i, (node, _, _, parent) in enumerate(placed):
        m = _RANDOM_FRAME.match(str(node))
        if m and m.group("parent") == str(parent):
            k = count.get(str(parent), 0)
            count[str(parent)] = k + 1
            names[i] = f"{parent}_{k}"
    return names


def gather_parts(loaded, file_name: str, failed=()) -> dict:
    """Every triangle mesh of what ``trimesh.load`` returned, as one mesh.

    Returns a dict with ``geometries`` (list of ``(trimesh.Trimesh, transform
    (4, 4) or None)`` in scene order), ``uvs`` ((n, 2) float64 or None;
    ``uv_list``: the same per geometry, None where it has none),
    ``colors`` ((n, 4) float64 linear or None) and ``parts`` (list of
    :class:`Part` whose ``start``/``count`` index the concatenated faces).
    A part without UVs in a multi-part mesh with UVs gets UV (0, 0); one
    without colours gets white.  ``failed``: the resolver's ``(name, reason)``
    list, turned into :class:`AssetWarning`\\ s naming the file and material.
    """
    import trimesh

    if isinstance(loaded, trimesh.Scene):
        items = []
        order = {key: i for i, key in enumerate(loaded.geometry)}  # the file's order
        placed = sorted(_geometry_nodes(loaded.graph, file_name), key=lambda it: (order.get(it[2], 0), str(it[0])))
        names = _stable_names(placed)
        for (node, transform, geom_name, _), node in zip(placed, names):
            geom = loaded.geometry.get(geom_name)
            if isinstance(geom, trimesh.Trimesh):
                t = None if np.allclose(transform, np.eye(4)) else np.asarray(transform, dtype=np.float64)
                items.append((str(node), geom, t))
        if not items:
            raise MeshError(f"{file_name}: the file holds no triangle mesh; expected at least one")
    elif isinstance(loaded, trimesh.Trimesh):
        items = [("", loaded, None)]
    else:
        raise MeshError(f"{file_name}: the file holds a {type(loaded).__name__} without faces; expected a triangle mesh")

    uvs, colors, parts, geometries = [], [], [], []
    start = 0
    for node, geom, transform in items:
        n = len(geom.vertices)
        faces = np.asarray(getattr(geom, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
        uvs.append(_uvs_of(geom, n, file_name))
        colors.append(_colors_of(geom, n, file_name))
        fallback = node or Path(file_name).stem
        material = _material_of(geom.visual, fallback, file_name)
        part_name = node or material.name or fallback
        parts.append(Part(name=part_name, start=start, count=len(faces), material=material))
        geometries.append((geom, transform))
        start += len(faces)
    names = [p.name for p in parts]
    if len(set(names)) != len(names):  # unique part names: suffix repeats
        seen: dict[str, int] = {}
        renamed = []
        for p in parts:
            k = seen.get(p.name, 0)
            seen[p.name] = k + 1
            renamed.append(p if k == 0 else Part(f"{p.name}.{k}", p.start, p.count, p.material))
        parts = renamed
    sizes = [len(g.vertices) for g, _ in geometries]
    any_uv = any(u is not None for u in uvs)
    any_color = any(c is not None for c in colors)
    uv_all = np.concatenate([u if u is not None else np.zeros((k, 2)) for u, k in zip(uvs, sizes)]) if any_uv else None
    col_all = np.concatenate([c if c is not None else np.ones((k, 4)) for c, k in zip(colors, sizes)]) if any_color else None
    for texture, reason in failed:
        untextured = sorted({p.material.name for p in parts if p.material.texture is None})
        warnings.warn(AssetWarning(
            f"{file_name}: {texture!r} (texture or material file) {reason}; material {', '.join(repr(m) for m in untextured) or '?'} "
            "drawn with its base colour"), stacklevel=3)
    return {"geometries": geometries, "uvs": uv_all, "colors": col_all, "parts": parts, "uv_list": uvs}


# --------------------------------------------------------------------- tangents


def compute_tangents(positions, normals, uvs, faces) -> np.ndarray:
    """Per-vertex tangents for normal mapping, the usual per-triangle
    accumulation (Lengyel): ``(n, 4) float32``, xyz unit and orthogonal to the
    normal, w = ±1 the handedness of the UV frame (bitangent = w · n × t).

    positions, normals : (n, 3) float; uvs : (n, 2) float; faces : (m, 3) int.
    A vertex whose UVs are degenerate gets any unit vector orthogonal to its normal.
    """
    p = np.asarray(positions, dtype=np.float64)
    nrm = np.asarray(normals, dtype=np.float64)
    uv = np.asarray(uvs, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    e1, e2 = p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]]
    d1, d2 = uv[f[:, 1]] - uv[f[:, 0]], uv[f[:, 2]] - uv[f[:, 0]]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    r = np.where(np.abs(det) > 1e-20, 1.0 / np.where(det == 0, 1.0, det), 0.0)
    sdir = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * r[:, None]
    tdir = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * r[:, None]
    idx = f.ravel()
    n = len(p)
    tan = np.stack([np.bincount(idx, np.repeat(sdir[:, k], 3), minlength=n) for k in range(3)], axis=1)
    bit = np.stack([np.bincount(idx, np.repeat(tdir[:, k], 3), minlength=n) for k in range(3)], axis=1)
    # Gram-Schmidt against the normal
    t = tan - nrm * np.einsum("ij,ij->i", nrm, tan)[:, None]
    length = np.linalg.norm(t, axis=1)
    bad = length < 1e-12
    if bad.any():  # any vector orthogonal to the normal
        helper = np.where(np.abs(nrm[bad, 0:1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        alt = np.cross(nrm[bad], helper)
        t[bad] = alt
        length[bad] = np.linalg.norm(alt, axis=1)
    t /= np.maximum(length, 1e-30)[:, None]
    w = np.where(np.einsum("ij,ij->i", np.cross(nrm, t), bit) < 0.0, -1.0, 1.0)
    return np.hstack([t, w[:, None]]).astype(np.float32)


# --------------------------------------------------------------------- back to trimesh


def _trimesh_material(m: Material):
    """A trimesh PBRMaterial for ``m`` (texture as a PIL image)."""
    import trimesh

    factor = np.clip(np.round(np.asarray(m.base_color, dtype=np.float64) * 255.0), 0, 255).astype(np.uint8)
    return trimesh.visual.material.PBRMaterial(
        name=m.name,
        baseColorFactor=factor,
        baseColorTexture=None if m.texture is None else Image.fromarray(m.texture, "RGBA"),
        normalTexture=None if m.normal_texture is None else Image.fromarray(m.normal_texture, "RGBA"),
        alphaMode=m.alpha_mode,
        alphaCutoff=float(m.alpha_cutoff) if m.alpha_mode == "MASK" else None,
        doubleSided=bool(m.double_sided),
        metallicFactor=0.0,
        roughnessFactor=0.9,
    )


def to_trimesh_with_appearance(mesh, positions=None, normals=None):
    """The base mesh (or one deformed instance: ``positions``/``normals``
    (v, 3)) as trimesh objects that keep the appearance: a ``Trimesh`` for a
    single part, else a ``Scene`` with one ``Trimesh`` per part (named after
    it).  UVs and the material go into ``TextureVisuals``; a mesh with
    colours but no UVs gets ``ColorVisuals`` (sRGB uint8)."""
    import trimesh

    pos = mesh.positions if positions is None else np.asarray(positions)
    nrm = mesh.normals if normals is None else np.asarray(normals)

    def visual(material: Material):
        if mesh.uvs is not None:
            return trimesh.visual.TextureVisuals(uv=mesh.uvs, material=_trimesh_material(material))
        if mesh.colors is not None:
            c = np.hstack([linear_to_srgb(mesh.colors[:, :3]), np.clip(mesh.colors[:, 3:], 0, 1)])
            return trimesh.visual.ColorVisuals(vertex_colors=np.round(c * 255).astype(np.uint8))
        if not material.is_default:
            return trimesh.visual.TextureVisuals(material=_trimesh_material(material))
        return None

    if len(mesh.parts) == 1:
        return trimesh.Trimesh(vertices=pos, faces=mesh.faces, vertex_normals=nrm, visual=visual(mesh.parts[0].material),
                               process=False)
    scene = trimesh.Scene()
    for part in mesh.parts:
        faces = mesh.faces[part.start:part.start + part.count]
        used = np.unique(faces)
        remap = np.zeros(len(pos), dtype=np.int64)
        remap[used] = np.arange(len(used))
        sub = trimesh.Trimesh(vertices=pos[used], faces=remap[faces], vertex_normals=nrm[used], process=False)
        v = visual(part.material)
        if v is not None:
            if isinstance(v, trimesh.visual.TextureVisuals) and v.uv is not None:
                v = trimesh.visual.TextureVisuals(uv=mesh.uvs[used], material=v.material)
            elif isinstance(v, trimesh.visual.ColorVisuals):
                v = trimesh.visual.ColorVisuals(vertex_colors=v.vertex_colors[used])
            sub.visual = v
        scene.add_geometry(sub, node_name=part.name, geom_name=part.name)
    return scene

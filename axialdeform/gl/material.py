"""The GPU side of a mesh's appearance (:mod:`axialdeform.core.material`).

* :class:`AppearanceBuffer` — per-vertex ``in_uv`` (2f), ``in_color`` (4f,
  linear RGBA) and ``in_tangent`` (4f) in one buffer, read by the programs
  built with ``AXIAL_MATERIAL``; defaults where the mesh has none (UV 0,
  white, tangent +x).
* :class:`GpuMaterials` — one sRGB texture (mipmapped) and one normal map per
  material that has them; :meth:`GpuMaterials.bind` sets a program's material
  uniforms for one part.

Both hold their ``ctx``; ``release()`` is safe twice; nothing is released
from ``__del__``.
"""

from __future__ import annotations

import numpy as np

from ..core.errors import ContextError
from .buffers import buffer_content
from .context import texture_anisotropy
from .uniforms import set_uniforms

__all__ = ["AppearanceBuffer", "GpuMaterials", "ALPHA_MODE_INDEX", "GL_SRGB8_ALPHA8"]

GL_SRGB8_ALPHA8 = 0x8C43
ALPHA_MODE_INDEX = {"OPAQUE": 0, "MASK": 1, "BLEND": 2}
_TEXTURE_UNIT, _NORMAL_UNIT = 1, 2  # unit 0 is left to the caller; the shadow map uses 3


class AppearanceBuffer:
    """UVs, colours and tangents of a base mesh: ``(n, 10) float32``, 40 bytes a vertex."""

    def __init__(self, ctx, mesh):
        self.ctx = ctx
        n = mesh.vertex_count
        uv = mesh.uvs if mesh.uvs is not None else np.zeros((n, 2), np.float32)
        color = mesh.colors if mesh.colors is not None else np.ones((n, 4), np.float32)
        tangent = mesh.tangents if mesh.tangents is not None else np.tile(np.float32([1, 0, 0, 1]), (n, 1))
        self.buffer = ctx.buffer(np.hstack([uv, color, tangent]).astype("f4").tobytes())
        self._released = False

    def content(self, program):
        return buffer_content(self.buffer, ("2f", "4f", "4f"), ("in_uv", "in_color", "in_tangent"), program)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        self.buffer.release()


def _check_size(ctx, image: np.ndarray, mesh_name: str, material: str, what: str) -> None:
    limit = int(ctx.info.get("GL_MAX_TEXTURE_SIZE", 2048))
    h, w = image.shape[:2]
    if w > limit or h > limit:
        raise ContextError(
            f"{mesh_name}: the {what} of material {material!r} is {w}x{h} pixels; this GL context allows at most "
            f"{limit}x{limit} (scale the texture down)")


class GpuMaterials:
    """Textures of every part's material, uploaded once (shared between parts
    that use the same material object)."""

    def __init__(self, ctx, mesh):
        self.ctx = ctx
        self._textures: dict[int, tuple] = {}  # id(material) -> (base texture or None, normal texture or None)
        self._objects = []
        self._released = False
        anisotropy = texture_anisotropy(ctx)  # none on a software rasteriser (gl/context.py)
        try:
            for part in mesh.parts:
                m = part.material
                if id(m) in self._textures:
                    continue
                pair = []
                for image, what, srgb in ((m.texture, "base colour texture", True),
                                          (m.normal_texture, "normal map", False)):
                    if image is None:
                        pair.append(None)
                        continue
                    _check_size(ctx, image, str(mesh.name), m.name, what)
                    # OBJ convention (v = 0 at the image's bottom): GL's first row is t = 0
                    data = np.ascontiguousarray(image[::-1])
                    tex = ctx.texture((image.shape[1], image.shape[0]), 4, data.tobytes(),
                                      internal_format=GL_SRGB8_ALPHA8 if srgb else None)
                    self._objects.append(tex)
                    tex.build_mipmaps()
                    tex.filter = (0x2703, 0x2601)  # LINEAR_MIPMAP_LINEAR, LINEAR
                    if anisotropy > 1.0:
                        tex.anisotropy = anisotropy
                    pair.append(tex)
                self._textures[id(m)] = tuple(pair)
        except BaseException:
            self.release()
            raise

    def bind(self, program, material, default_color) -> None:
        """Set ``program``'s material uniforms and textures for ``material``.

        ``default_color`` (linear RGB) replaces the base colour of a default
        (white, untextured) material, so plain meshes keep the renderer's colour."""
        base, normal = self._textures.get(id(material), (None, None))
        color = np.array(material.base_color, dtype=np.float64)
        if material.is_default:
            color[:3] = default_color
        values = {
            "u_base_color": tuple(float(c) for c in color),
            "u_has_texture": base is not None,
            "u_alpha_mode": ALPHA_MODE_INDEX[material.alpha_mode],
            "u_alpha_cutoff": float(material.alpha_cutoff),
            # no material at all (colours or UVs only): both sides lit, as for a plain mesh
            "u_double_sided": bool(material.double_sided or material.is_default),
            "u_has_normal_map": normal is not None,
            "u_texture": _TEXTURE_UNIT,
            "u_normal_map": _NORMAL_UNIT,
        }
        set_uniforms(program, values)
        if base is not None:
            base.use(_TEXTURE_UNIT)
        if normal is not None:
            normal.use(_NORMAL_UNIT)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        for obj in self._objects:
            obj.release()
        self._objects.clear()
        self._textures.clear()

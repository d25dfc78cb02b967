"""Several axes on the GPU (``AXIAL_AXES``): the child axes' offsets in a
texture fetched by instance id, and the axes' uniforms.

Why a texture and not more instanced attributes: a child axis is ten numbers
(three ``vec4``), and the base record, material, tint and cull index already
use most of the 16 vertex attributes that GL 3.3 and WebGL 2 promise; a
texture holds any number of axes and every instance path (plain, sliced,
culled, captured) reaches it by the instance's index.  Layout
(``glsl/axial.glsl``, ``axial_child_offsets``): instance ``i``'s axis ``k``
(1..K−1) is the three RGBA32F texels from ``(i·(K−1) + k − 1)·3`` on, in
rows of :data:`ROW` texels: ``d1u d1v d2u d2v | d3u d3v d4u d4v | d5u d5v 0 0``.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.bounds import child_reach
from ..core.errors import ParamError
from .context import check_alive
from .uniforms import set_uniforms

__all__ = ["AxesTexture", "ROW", "AXES_UNIT", "set_axes_uniforms"]

#: texels per row of the offsets texture (a multiple of 3: an axis never straddles rows)
ROW = 4095
#: the texture unit the offsets texture is bound to (material 1, 2; shadow map 3)
AXES_UNIT = 4


def _texels(children: np.ndarray) -> np.ndarray:
    """(n, K−1, 5, 2) offsets -> (n·(K−1)·3, 4) float32 texels."""
    c = np.asarray(children, dtype=np.float32).reshape(len(children), -1, 10)
    out = np.zeros(c.shape[:2] + (12,), dtype=np.float32)
    out[..., :10] = c
    return out.reshape(-1, 4)


class AxesTexture:
    """The child axes' offsets of every instance, as a float texture.

    ctx : moderngl.Context; tree : the mesh's :class:`~axialdeform.core.axes.AxisTree`
    (K ≥ 2 axes); children : (n, K−1, 5, 2) float;
    capacity : instances it holds before it grows.
    """

    def __init__(self, ctx, tree, children, capacity: int | None = None):
        check_alive(ctx, "a new AxesTexture")
        self.ctx = ctx
        self.tree = tree
        self.axes = int(tree.count)
        self.texture = None
        self.count = 0
        self.child_reach = 0.0
        self._released = False
        self._allocate(max(int(capacity or 0), len(children), 1))
        self.set(children)

    def _allocate(self, capacity: int) -> None:
        if self.texture is not None:
            self.texture.release()
        self.capacity = capacity
        texels = capacity * (self.axes - 1) * 3
        rows = -(-texels // ROW)
        most = int(self.ctx.info.get("GL_MAX_TEXTURE_SIZE", 16384) or 16384)
        if rows > most:
            raise ParamError(f"instances: {capacity} of {self.axes} axes need a {ROW} x {rows} offsets texture; "
                             f"this GL takes at most {most} rows: expected at most "
                             f"{most * ROW // (3 * (self.axes - 1))} instances in one renderer")
        self.texture = self.ctx.texture((ROW, rows), 4, dtype="f4")
        self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)  # float textures: fetched, never filtered

    def _write(self, children: np.ndarray, start: int) -> None:
        texels = _texels(children)
        first = start * (self.axes - 1) * 3
        pos, end = first, first + len(texels)
        while pos < end:  # a partial first row, whole rows, a partial last row
            y, x = divmod(pos, ROW)
            if x == 0 and end - pos >= ROW:
                h = (end - pos) // ROW
                w, take = ROW, h * ROW
            else:
                h, take = 1, min(ROW - x, end - pos)
                w = take
            self.texture.write(texels[pos - first:pos - first + take].tobytes(), viewport=(x, y, w, h))
            pos += take

    def reach(self, children: np.ndarray) -> float:
        """The most any instance's child axes can move a vertex (model units,
        :func:`~axialdeform.core.bounds.child_reach`)."""
        if not len(children):
            return 0.0
        return float(np.max(child_reach(self.tree, children)))

    def set(self, children) -> None:
        """Replace every instance's child offsets ((n, K−1, 5, 2))."""
        children = np.asarray(children, dtype=np.float32)
        if len(children) > self.capacity:
            self._allocate(max(len(children), 2 * self.capacity))
        if len(children):
            self._write(children, 0)
        self.count = len(children)
        self.child_reach = self.reach(children)

    def reserve(self, capacity: int) -> None:
        """Room for ``capacity`` instances (a new texture past the capacity: what it held is gone); a GPU pass
        then writes the texels (:mod:`~axialdeform.gl.generated`) and sets :attr:`count` and :attr:`child_reach`."""
        if int(capacity) > self.capacity:
            self._allocate(max(int(capacity), 2 * self.capacity))

    def update(self, children, start: int) -> None:
        """Overwrite instances ``start ..`` (the bound only grows: culling stays safe)."""
        children = np.asarray(children, dtype=np.float32)
        if len(children):
            self._write(children, int(start))
        self.child_reach = max(self.child_reach, self.reach(children))

    def read(self) -> np.ndarray:
        """The stored offsets, (count, K−1, 5, 2) float32."""
        data = np.frombuffer(self.texture.read(), dtype=np.float32).reshape(-1, 4)
        n = self.count * (self.axes - 1) * 3
        return data[:n].reshape(self.count, self.axes - 1, 12)[..., :10].reshape(self.count, self.axes - 1, 5, 2).copy()

    def bind(self) -> None:
        self.texture.use(AXES_UNIT)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        if self.texture is not None:
            self.texture.release()


def set_axes_uniforms(program, tree) -> None:
    """Every axis's frame (GLSL ``mat3``: ``u_axes_frame[k] * v = F_k v``), ``lo``,
    ``L``, anchor and parent, and the offsets texture's unit."""
    if "u_axes_lo" not in program and "u_axes_frame" not in program:
        return
    frames = np.stack([a.matrix.T for a in tree.axes])  # column-major mat3s: F's transpose, row-major
    values = {"u_axes_frame": np.ascontiguousarray(frames, dtype=np.float32),
              "u_axes_lo": np.array([a.lo for a in tree.axes], dtype=np.float32),
              "u_axes_len": np.array([a.length for a in tree.axes], dtype=np.float32),
              "u_axes_anchor": np.array(tree.anchors, dtype=np.float32),
              "u_axes_offsets": AXES_UNIT}
    set_uniforms(program, values)
    if "u_axes_parent" in program:
        program["u_axes_parent"].write(np.asarray(tree.parents, dtype="<i4").tobytes())

"""Generated layers on the GPU: ``glsl/generate.glsl`` run by transform feedback, one tile a pass.

The records land in a GPU buffer (the one a draw can read); :func:`generate_tile_gpu` reads them
back for the tests, which hold them to the numpy reference :mod:`axialdeform.core.generate`.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.generate import GENERATED_FLOATS, Generate, GroundMaps, recipe_uniforms, tile_size
from .context import bind_framebuffer, release_framebuffer
from .shaders import build_program

__all__ = ["TileGenerator", "generate_tile_gpu"]

_VARYINGS = ("g_d12", "g_d34", "g_d5_px_py", "g_pz_angles", "g_extra", "g_tint")
_FLOATS = GENERATED_FLOATS  # 4 + 4 + 4 + 4 + 4 + 3 an instance: the 22-number record, then kept


class TileGenerator:
    """The generator program for one recipe and base mesh (and the ground's maps) in ``ctx``;
    ``run(tile, buffer)`` writes tile ``(tx, tz)``'s ``m^2`` records into ``buffer``: 23 float32 each,
    the 22-number record (the 16, s, tw, tp, the tint) then 1 (kept) or 0 (dropped)."""

    def __init__(self, ctx, recipe: Generate, mesh, maps: GroundMaps | None = None):
        self.ctx = ctx
        self.recipe = recipe
        self.m = tile_size(recipe)[0]
        self.count = self.m * self.m
        self.program = build_program(ctx, "generate.vert", varyings=_VARYINGS)
        maps = maps if maps is not None else GroundMaps()
        for name, value in recipe_uniforms(recipe, mesh, maps).items():  # AxialRecipe's fields, as the page gets them
            if "u_" + name in self.program:
                self.program["u_" + name].value = tuple(value) if isinstance(value, list) else value
        # the height and density maps (1 x 1 stand-ins where there are none): float32 texels, texelFetch
        self._textures = []
        for unit, (name, grid) in enumerate((("u_heights", maps.heights), ("u_density", maps.density))):
            grid = np.zeros((1, 1), np.float32) if grid is None else np.ascontiguousarray(grid, np.float32)
            tex = ctx.texture((grid.shape[1], grid.shape[0]), 1, grid.tobytes(), dtype="f4")
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._textures.append(tex)
            if name in self.program:
                self.program[name].value = unit
        self.vao = ctx.vertex_array(self.program, [])
        # a draw needs a complete framebuffer even with rasterization discarded (a surfaceless EGL
        # context has none of its own): a 1 x 1 one, bound for the pass
        self._color = ctx.renderbuffer((1, 1))
        self._fbo = ctx.framebuffer(self._color)
        self._released = False

    def buffer(self):
        """A buffer that holds one tile's records."""
        return self.ctx.buffer(reserve=self.count * _FLOATS * 4)

    def run(self, tile, buffer, offset: int = 0) -> None:
        """Tile ``tile``'s records into ``buffer`` from byte ``offset`` on."""
        if "u_tile" in self.program:
            self.program["u_tile"].value = (int(tile[0]), int(tile[1]))
        for unit, tex in enumerate(self._textures):
            tex.use(location=unit)
        previous = self.ctx.fbo
        self._fbo.use()
        try:
            self.vao.transform(buffer, mode=moderngl.POINTS, vertices=self.count, buffer_offset=int(offset))
        finally:
            bind_framebuffer(self.ctx, previous)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        self.vao.release()
        self.program.release()
        release_framebuffer(self.ctx, self._fbo)
        self._color.release()
        for tex in self._textures:
            tex.release()


def generate_tile_gpu(ctx, recipe: Generate, mesh, tx: int, tz: int,
                      maps: GroundMaps | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Tile (tx, tz) as the GPU makes it: ``(records, kept)``, ``(m^2, 16, 19 or 22) float32`` in cell
    order and the ``(m^2,)`` bool of those kept (as :func:`~axialdeform.core.generate.generate_tile`)."""
    gen = TileGenerator(ctx, recipe, mesh, maps)
    buf = gen.buffer()
    try:
        gen.run((tx, tz), buf)
        raw = np.frombuffer(buf.read(), np.float32).reshape(gen.count, _FLOATS)
    finally:
        buf.release()
        gen.release()
    return raw[:, :recipe.width].copy(), raw[:, -1] > 0.5

"""Generated layers on the GPU: ``glsl/generate.glsl`` run by transform feedback, one tile a pass.

The records land in a GPU buffer (the one a draw can read); :func:`generate_tile_gpu` reads them
back for the tests, which hold them to the numpy reference :mod:`axialdeform.core.generate`.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.generate import Generate, recipe_uniforms, tile_size
from .context import bind_framebuffer, release_framebuffer
from .shaders import build_program

__all__ = ["TileGenerator", "generate_tile_gpu"]

_VARYINGS = ("g_d12", "g_d34", "g_d5_px_py", "g_pz_angles", "g_extra")
_FLOATS = 19  # 4 + 4 + 4 + 4 + 3 an instance


class TileGenerator:
    """The generator program for one recipe and base mesh in ``ctx``; ``run(tile, buffer)`` writes tile
    ``(tx, tz)``'s ``m^2`` records (19 float32 each: the 16 numbers, then s, tw, tp) into ``buffer``."""

    def __init__(self, ctx, recipe: Generate, mesh):
        self.ctx = ctx
        self.recipe = recipe
        self.m = tile_size(recipe)[0]
        self.count = self.m * self.m
        self.program = build_program(ctx, "generate.vert", varyings=_VARYINGS)
        for name, value in recipe_uniforms(recipe, mesh).items():  # AxialRecipe's fields, as the page gets them
            if "u_" + name in self.program:
                self.program["u_" + name].value = tuple(value) if isinstance(value, list) else value
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


def generate_tile_gpu(ctx, recipe: Generate, mesh, tx: int, tz: int) -> np.ndarray:
    """Tile (tx, tz)'s records as the GPU makes them: ``(m^2, 16 or 19) float32``, cell order."""
    gen = TileGenerator(ctx, recipe, mesh)
    buf = gen.buffer()
    try:
        gen.run((tx, tz), buf)
        raw = np.frombuffer(buf.read(), np.float32).reshape(gen.count, _FLOATS)
    finally:
        buf.release()
        gen.release()
    return raw[:, :recipe.width].copy()

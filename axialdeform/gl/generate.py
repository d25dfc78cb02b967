"""Generated layers on the GPU: ``glsl/generate.glsl`` run by transform feedback, one tile a pass.

The records land in a GPU buffer (the one a draw can read); :func:`generate_tile_gpu` reads them
back for the tests, which hold them to the numpy reference :mod:`axialdeform.core.generate`.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.generate import GENERATED_FLOATS, Generate, GroundMaps, children_table, recipe_uniforms, tile_size
from ..core.record import join_record
from .context import bind_framebuffer, release_framebuffer
from .shaders import build_program

__all__ = ["TileGenerator", "generate_tile_gpu"]

_VARYINGS = ("g_d12", "g_d34", "g_d5_px_py", "g_pz_angles", "g_extra", "g_tint")
_FLOATS = GENERATED_FLOATS  # 4 + 4 + 4 + 4 + 4 + 3 an instance: the 22-number record, then kept
_CHILD_VARYINGS = tuple(f"c_{k}" for k in range(15))
CHILD_AXES_A_PASS = 6  # generate_children.vert: 60 numbers an instance a pass


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
        values = recipe_uniforms(recipe, mesh, maps)
        self._bend = values["bend"]
        for name, value in values.items():  # AxialRecipe's fields, as the page gets them
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
        # a mesh of several axes: the child axes' offsets by a second program, six axes a pass
        self.children = None
        tree = getattr(mesh, "tree", None)
        if tree is not None:
            table = self._table = children_table(recipe, mesh)
            self.child_count = len(table)
            self.child_program = build_program(ctx, "generate_children.vert", varyings=_CHILD_VARYINGS)
            self.children = ctx.texture((table.shape[1], table.shape[0]), 1, np.ascontiguousarray(table).tobytes(),
                                        dtype="f4")
            self.children.filter = (moderngl.NEAREST, moderngl.NEAREST)
            for name, value in (("u_seed", recipe.seed), ("u_children_n", self.child_count), ("u_children", 2)):
                if name in self.child_program:
                    self.child_program[name].value = value
            self.child_vao = ctx.vertex_array(self.child_program, [])
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
        self.transform(self.vao, buffer, offset)

    def transform(self, vao, buffer, offset: int = 0, vertices: int | None = None) -> None:
        """One transform-feedback pass of ``vao`` over ``vertices`` points (default: a tile's instances) into
        ``buffer`` at byte ``offset``, its own 1 x 1 framebuffer bound meanwhile (a surfaceless context has none)."""
        previous = self.ctx.fbo
        self._fbo.use()
        try:
            vao.transform(buffer, mode=moderngl.POINTS, vertices=self.count if vertices is None else int(vertices),
                          buffer_offset=int(offset))
        finally:
            bind_framebuffer(self.ctx, previous)

    def set_bend_scale(self, scale: float) -> None:
        """Every offset times ``scale`` (the viewer's UP/DOWN keys): the root's amplitude and each child
        axis's, as the records' offsets times ``scale`` (the offsets are linear in them)."""
        if "u_bend" in self.program:
            self.program["u_bend"].value = self._bend * float(scale)
        if self.children is not None:
            table = self._table.copy()
            table[:, 0] *= np.float32(scale)
            self.children.write(np.ascontiguousarray(table).tobytes())

    @property
    def passes(self) -> int:
        """The child passes a tile needs (0: one axis)."""
        return 0 if self.children is None else -(-self.child_count // CHILD_AXES_A_PASS)

    def run_children(self, tile, buffer, step: int, offset: int = 0) -> None:
        """Pass ``step`` of tile ``tile``'s child offsets (axes ``6 step + 1`` .. ``6 step + 6``, 60 float32 an
        instance, zeros past the last axis) into ``buffer`` from byte ``offset`` on."""
        p = self.child_program
        for name, value in (("u_tile", (int(tile[0]), int(tile[1]))), ("u_first", CHILD_AXES_A_PASS * step + 1)):
            if name in p:
                p[name].value = value
        self.children.use(location=2)
        self.transform(self.child_vao, buffer, offset)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        if self.children is not None:
            self.child_vao.release()
            self.child_program.release()
            self.children.release()
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
    kids = ctx.buffer(reserve=gen.count * 60 * 4) if gen.passes else None
    try:
        gen.run((tx, tz), buf)
        raw = np.frombuffer(buf.read(), np.float32).reshape(gen.count, _FLOATS)
        records = raw[:, :recipe.width].copy()
        if gen.passes:
            parts = []
            for step in range(gen.passes):
                gen.run_children((tx, tz), kids, step)
                parts.append(np.frombuffer(kids.read(), np.float32).reshape(gen.count, 60))
            records = join_record(records, np.concatenate(parts, axis=1)[:, :10 * gen.child_count])
    finally:
        buf.release()
        if kids is not None:
            kids.release()
        gen.release()
    return records, raw[:, -1] > 0.5

"""Generated layers on the GPU: ``glsl/generate.glsl`` run by a compute shader on GL >= 4.3
(``glsl/generate.comp``) or by transform feedback on GL 3.3 (``glsl/generate.vert``), one tile a pass.

The records land in a GPU buffer (the one a draw can read); :func:`generate_tile_gpu` reads them
back for the tests, which hold them to the numpy reference :mod:`axialdeform.core.generate`.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.errors import ContextError
from ..core.generate import GENERATED_FLOATS, Generate, GroundMaps, children_table, recipe_uniforms, tile_size
from ..core.record import CHILD_AXES_A_PASS, CHILD_SLOT_VECTORS, join_record, slot_varyings
from .context import bind_framebuffer, release_framebuffer
from .shaders import build_compute, build_program

__all__ = ["TileGenerator", "compute_available", "generate_tile_gpu"]

_VARYINGS = slot_varyings("g")  # glsl/slot.glsl's outputs: the 22-number record, then kept
_FLOATS = GENERATED_FLOATS
_CHILD_VARYINGS = tuple(f"c_{k}" for k in range(CHILD_SLOT_VECTORS))  # CHILD_AXES_A_PASS axes' offsets
_LOCAL = 64  # generate.comp's invocations a work group


def compute_available(ctx) -> bool:
    """Whether ``ctx`` runs compute shaders (GL >= 4.3): the generator's slots by ``glsl/generate.comp``."""
    return int(getattr(ctx, "version_code", 0) or 0) >= 430


class TileGenerator:
    """The generator program for one recipe and base mesh (and the ground's maps) in ``ctx``;
    ``run(tile, buffer)`` writes tile ``(tx, tz)``'s ``m^2`` slots into ``buffer``: 23 float32 each,
    the 22-number record (the 16, s, tw, tp, the tint) then 1 (kept) or 0 (dropped).

    compute : by ``glsl/generate.comp`` (True: GL >= 4.3 required), by transform feedback (False), or
        the first where the context has it (None, the default).  The two write the same slots.
    """

    def __init__(self, ctx, recipe: Generate, mesh, maps: GroundMaps | None = None, compute: bool | None = None):
        self.ctx = ctx
        self.recipe = recipe
        self.m = tile_size(recipe)[0]
        self.count = self.m * self.m
        if compute and not compute_available(ctx):
            raise ContextError(f"generate: compute=True needs OpenGL >= 4.3 (compute shaders), this context has "
                               f"{ctx.version_code}; expected compute=None or False")
        self.program = build_program(ctx, "generate.vert", varyings=_VARYINGS)
        #: the compute shader that writes the slots (None: transform feedback does)
        self.compute = build_compute(ctx, "generate.comp") if compute is not False and compute_available(ctx) else None
        self._programs = [p for p in (self.program, self.compute) if p is not None]
        self._tiles = ctx.buffer(reserve=8)  # the compute path's tiles (ivec2 each)
        maps = maps if maps is not None else GroundMaps()
        values = recipe_uniforms(recipe, mesh, maps)
        self._bend = values["bend"]
        for name, value in values.items():  # AxialRecipe's fields, as the page gets them
            self._set("u_" + name, tuple(value) if isinstance(value, list) else value)
        self._set("u_count", self.count)
        # the height and density maps (1 x 1 stand-ins where there are none): float32 texels, texelFetch
        self._textures = []
        for unit, (name, grid) in enumerate((("u_heights", maps.heights), ("u_density", maps.density))):
            grid = np.zeros((1, 1), np.float32) if grid is None else np.ascontiguousarray(grid, np.float32)
            tex = ctx.texture((grid.shape[1], grid.shape[0]), 1, grid.tobytes(), dtype="f4")
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._textures.append(tex)
            self._set(name, unit)
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

    def set_density(self, maps: GroundMaps, mesh) -> None:
        """The density map of ``maps`` from now on (a painted mask, :mod:`~axialdeform.core.brush`): its texture
        and its numbers; the tiles made next read it."""
        values = recipe_uniforms(self.recipe, mesh, maps)
        for name in ("has_density", "d_lo", "d_inv", "d_size", "d_wrap"):
            self._set("u_" + name, tuple(values[name]) if isinstance(values[name], list) else values[name])
        grid = np.zeros((1, 1), np.float32) if maps.density is None else np.ascontiguousarray(maps.density, np.float32)
        self._textures[1].release()
        self._textures[1] = self.ctx.texture((grid.shape[1], grid.shape[0]), 1, grid.tobytes(), dtype="f4")
        self._textures[1].filter = (moderngl.NEAREST, moderngl.NEAREST)

    def _set(self, name: str, value) -> None:
        """A uniform of the slots' program(s) (both, where there is a compute shader)."""
        for prog in self._programs:
            if name in prog:
                prog[name].value = value

    def buffer(self):
        """A buffer that holds one tile's records."""
        return self.ctx.buffer(reserve=self.count * _FLOATS * 4)

    def run(self, tile, buffer, offset: int = 0) -> None:
        """Tile ``tile``'s records into ``buffer`` from byte ``offset`` on (a multiple of 4)."""
        self.run_tiles([tile], buffer, offset)

    def run_tiles(self, tiles, buffer, offset: int = 0) -> None:
        """Every tile of ``tiles`` ((k, 2) ints), ``m^2`` records each, tile after tile, into ``buffer`` from
        byte ``offset`` on (a multiple of 4): one dispatch of them all (compute), or a pass a tile."""
        tiles = np.asarray(tiles, dtype=np.int64).reshape(-1, 2)
        for unit, tex in enumerate(self._textures):
            tex.use(location=unit)
        if self.compute is None:
            for k, tile in enumerate(tiles):
                self._set("u_tile", (int(tile[0]), int(tile[1])))
                self.transform(self.vao, buffer, offset + k * self.count * _FLOATS * 4)
            return
        if not len(tiles):
            return
        data = np.ascontiguousarray(tiles, dtype="<i4").tobytes()
        if self._tiles.size < len(data):
            self._tiles.orphan(len(data))
        self._tiles.write(data)
        self._set("u_first", int(offset) // 4)
        self._set("u_tiles", len(tiles))
        buffer.bind_to_storage_buffer(binding=0)
        self._tiles.bind_to_storage_buffer(binding=1)
        self.compute.run(group_x=-(-len(tiles) * self.count // _LOCAL))
        # the slots are read next as vertex attributes (the compaction) or by a read-back
        self.ctx.memory_barrier()

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

    def set_seed(self, seed: int) -> None:
        """Another seed (uint32) for the slots and the child axes."""
        self._set("u_seed", int(seed))
        if self.children is not None and "u_seed" in self.child_program:
            self.child_program["u_seed"].value = int(seed)

    def set_bend_scale(self, scale: float) -> None:
        """Every offset times ``scale`` (the viewer's UP/DOWN keys): the root's amplitude and each child
        axis's, as the records' offsets times ``scale`` (the offsets are linear in them)."""
        self._set("u_bend", self._bend * float(scale))
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
        self._tiles.release()
        for prog in self._programs:
            prog.release()
        release_framebuffer(self.ctx, self._fbo)
        self._color.release()
        for tex in self._textures:
            tex.release()


def generate_tile_gpu(ctx, recipe: Generate, mesh, tx: int, tz: int, maps: GroundMaps | None = None,
                      compute: bool | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Tile (tx, tz) as the GPU makes it: ``(records, kept)``, ``(m^2, 16, 19 or 22) float32`` in cell
    order and the ``(m^2,)`` bool of those kept (as :func:`~axialdeform.core.generate.generate_tile`);
    ``compute``: :class:`TileGenerator`'s."""
    gen = TileGenerator(ctx, recipe, mesh, maps, compute=compute)
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

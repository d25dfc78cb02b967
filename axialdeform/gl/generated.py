"""A generated layer drawn from the GPU's own records: tiles made straight into a renderer's buffers.

:class:`GeneratedTiles` ``.make(tiles)``, every time the tiles within reach change:

1. ``glsl/generate.comp`` (GL >= 4.3; ``glsl/generate.vert`` by transform feedback on 3.3) writes every
   tile's ``m^2`` slots (23 float32: the 22-number record, then kept) into one scratch buffer, tile after
   tile (:class:`~axialdeform.gl.generate.TileGenerator`);
2. ``glsl/generate_keep.vert`` + ``generate_keep.geom`` compact the kept slots, in slot order, by
   transform feedback into the :class:`~axialdeform.gl.renderer.AxialRenderer`'s instance buffer (the
   record's 16 or 19 numbers, its layout's), its tint buffer (a tinted recipe) and, for a tree, a scratch buffer of each
   instance's (tile, cell);
3. a tree's child-axis offsets: ``glsl/generate_axes.vert`` draws every texel of them (one point each,
   ``axial_generate_child`` once more) into the renderer's offsets texture.

The culling, level-of-detail, shadow and draw passes then read those buffers as they read uploaded ones.
No record reaches the CPU and none is uploaded: the one number read back is how many were kept (a
``GL_PRIMITIVES_GENERATED`` query, as the GL 3.3 culling pass reads its count).  The instances are those of
:func:`~axialdeform.core.generate.generate_tiles` for the same tiles, in the same order (the tests hold
them to it).  Holds its ``ctx``; ``release()`` is safe twice; nothing is released from ``__del__``.
"""

from __future__ import annotations

from dataclasses import replace

import moderngl
import numpy as np

from ..core.generate import GENERATED_FLOATS, Generate, GroundMaps, child_bound
from ..core.record import TINTED_WIDTH, slot_layout, slot_varyings
from .axes import ROW
from .buffers import buffer_content
from .context import bind_framebuffer, release_framebuffer
from .cull import shared_query
from .generate import TileGenerator
from .shaders import build_program

__all__ = ["GeneratedTiles"]

_SLOT = GENERATED_FLOATS * 4  # bytes a slot of the scratch buffer
_RAW = slot_layout()  # glsl/slot.glsl's vectors as vertex inputs
#: what each compaction pass writes: its define and its varyings (the record's vectors: the 16 numbers', then
#: the extended's three)
_KEEP = {"record": ("AXIAL_KEEP_RECORD", slot_varyings("o", (0, 1))),
         "tint": ("AXIAL_KEEP_TINT", slot_varyings("o", (2,))), "cell": ("AXIAL_KEEP_CELL", ("o_cell",))}


class GeneratedTiles:
    """The tiles of one generated layer made on the GPU into ``renderer`` (float32, 16 or 19 numbers; tinted
    when the recipe has a tint; the mesh's axes).

    renderer : AxialRenderer; recipe : Generate; mesh : the layer's BaseMesh (one axis or a tree);
    maps : GroundMaps (the height and density maps), optional; compute : the slots by a compute shader
    (:class:`~axialdeform.gl.generate.TileGenerator`'s: None, the default, where the context has one).
    """

    def __init__(self, renderer, recipe: Generate, mesh, maps: GroundMaps | None = None,
                 compute: bool | None = None):
        self.ctx = ctx = renderer.ctx
        self.renderer = renderer
        self.recipe = recipe
        self.mesh = mesh
        self.generator = TileGenerator(ctx, recipe, mesh, maps, compute=compute)
        self.tinted = recipe.width == TINTED_WIDTH
        self.tree = mesh.tree if mesh.axis_count > 1 else None
        self.count = 0  # instances kept by the last make
        self.tiles = np.zeros((0, 2), np.int64)
        self._reach = child_bound(recipe, mesh)
        self._scale = 1.0
        self._query = shared_query(ctx)
        self._objects = []
        self._released = False
        passes = ["record"] + (["tint"] if self.tinted else []) + (["cell"] if self.tree is not None else [])
        self._raw = ctx.buffer(reserve=_SLOT)
        self._objects.append(self._raw)
        self._keep = {}
        for name in passes:
            define, varyings = _KEEP[name]
            defines = {define: 1}
            if name == "record" and renderer.extended:
                defines["AXIAL_EXTENDED"] = 1
            elif name == "record":
                varyings = slot_varyings("o", (0,))
            prog = build_program(ctx, "generate_keep.vert", geometry="generate_keep.geom", defines=defines,
                                 varyings=varyings)
            if "u_count" in prog:
                prog["u_count"].value = self.generator.count
            self._objects.append(prog)
            vao = ctx.vertex_array(prog, [buffer_content(self._raw, *_RAW, prog)])
            self._objects.append(vao)
            self._keep[name] = (prog, vao)
        if self.tree is not None:
            self._cells = ctx.buffer(reserve=12)
            self._tiles = ctx.texture((1, 1), 2, dtype="i4")
            self._tiles.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._axes = build_program(ctx, "generate_axes.vert", "generate_axes.frag")
            self._axes_vao = ctx.vertex_array(self._axes, [(self._cells, "3i/i", "i_cell")])
            self._objects += [self._cells, self._axes, self._axes_vao]
            for name, value in (("u_seed", recipe.seed), ("u_children_n", self.tree.count - 1), ("u_row", ROW),
                                ("u_children", 2)):
                if name in self._axes:
                    self._axes[name].value = value

    def _grow(self, name: str, size: int):
        """The scratch buffer ``name`` with room for ``size`` bytes (vertex arrays keep it: orphaned, not replaced)."""
        buffer = getattr(self, name)
        if buffer.size < size:
            buffer.orphan(size)
        return buffer

    def make(self, tiles) -> int:
        """Tiles ``tiles`` ((k, 2) ints) into the renderer, replacing what it drew; returns the instances kept."""
        tiles = np.asarray(tiles, dtype=np.int64).reshape(-1, 2)
        gen, n = self.generator, len(tiles) * self.generator.count
        self.tiles = tiles
        if n == 0:
            self.count = 0
            self.renderer.gpu_written(0, tint=self.tinted)
            return 0
        raw = self._grow("_raw", n * _SLOT)
        gen.run_tiles(tiles, raw)
        instances, tint, texture = self.renderer.gpu_targets(n, tint=self.tinted)
        self.count = self._compact("record", instances, n)
        if self.tinted:
            self._compact("tint", tint, n)
        if self.tree is not None:
            self._child_axes(tiles, n, texture)
        self.renderer.gpu_written(self.count, tint=self.tinted, child_reach=self._reach * self._scale)
        return self.count

    def _compact(self, name: str, out, n: int) -> int:
        _, vao = self._keep[name]
        with self._query:
            self.generator.transform(vao, out, vertices=n)
        return int(self._query.primitives)

    def _child_axes(self, tiles, n: int, texture) -> None:
        """The kept instances' (tile, cell), then every child axis's texels drawn into ``texture``."""
        if self._tiles.width < len(tiles):
            self._tiles.release()
            self._tiles = self.ctx.texture((len(tiles), 1), 2, dtype="i4")
            self._tiles.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self._tiles.write(np.ascontiguousarray(tiles, dtype="<i4").tobytes(), viewport=(0, 0, len(tiles), 1))
        self._tiles.use(location=5)
        self._keep["cell"][0]["u_tiles"].value = 5
        self._grow("_cells", n * 12)
        self._compact("cell", self._cells, n)
        if self.count == 0:
            return
        self.generator.children.use(location=2)
        prog = self._axes
        prog["u_size"].value = (texture.width, texture.height)
        fbo = self.ctx.framebuffer(color_attachments=[texture])
        previous = self.ctx.fbo
        try:
            fbo.use()
            fbo.viewport = (0, 0, texture.width, texture.height)
            self._axes_vao.render(moderngl.POINTS, vertices=3 * (self.tree.count - 1), instances=self.count)
        finally:
            bind_framebuffer(self.ctx, previous)
            release_framebuffer(self.ctx, fbo)

    def set_seed(self, seed: int) -> None:
        """Another seed (the viewer's N key): the next :meth:`make` makes other instances in the same tiles."""
        self.recipe = replace(self.recipe, seed=int(seed) % 2 ** 32)
        self.generator.set_seed(self.recipe.seed)
        if self.tree is not None and "u_seed" in self._axes:
            self._axes["u_seed"].value = self.recipe.seed

    def set_bend_scale(self, scale: float) -> None:
        """Every offset times ``scale`` from the next :meth:`make` on (the viewer's UP/DOWN keys)."""
        self._scale = float(scale)
        self.generator.set_bend_scale(scale)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        self.generator.release()
        for obj in reversed(self._objects):
            obj.release()
        if self.tree is not None:
            self._tiles.release()  # grown by _child_axes: not in _objects

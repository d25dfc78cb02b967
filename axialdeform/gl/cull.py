"""Per-instance frustum culling and LOD choice on the GPU.

Two implementations of one pass, chosen by the context's version
(:func:`indirect_supported`), with the same bound, the same choice and the
same output: the kept instance records byte for byte, in their original
order (level after level with LOD), each followed by the instance's original
index (``int``) and its tint (``vec3``) when tinted.  The draw reads them
with divisor 1 and the original index as ``i_index`` (``AXIAL_CULLED`` in
``glsl/scene.vert``), so per-instance shading and tint are those of the
unculled draw.

* **GL >= 4.3: compute + indirect draws** (``glsl/cull.comp``).  Three
  dispatches (classify, rank, offsets, scatter: an order-keeping prefix
  sum, no atomics) compact the records and write the indirect draw commands
  themselves (instance count and base instance of every draw slot); the
  draws are ``glMultiDrawElementsIndirect`` (``vao.render_indirect``), so the
  CPU never waits for a count.  :meth:`CullPass.run` returns an
  :class:`IndirectDraws`; the counts are read back only when asked
  (:meth:`IndirectDraws.counts`, the renderer's ``stats``).
* **GL 3.3: transform feedback + a query** (``glsl/cull.vert`` +
  ``glsl/cull.geom``): every record is drawn as a point, the geometry shader
  emits the kept ones, transform feedback writes them; a
  ``GL_PRIMITIVES_GENERATED`` query gives the count, which the CPU reads
  before the draw.  With LOD a second stage sorts the visible ones into
  levels (one pass per level).  :meth:`CullPass.run` returns the counts.

``AxialRenderer(indirect=False)`` or the environment variable
``AXIALDEFORM_INDIRECT=0`` forces the GL 3.3 path on any context; a frame
whose buffers exceed ``GL_MAX_SHADER_STORAGE_BLOCK_SIZE`` takes it too.

Because a sphere is dropped only when it lies wholly outside one frustum
plane, every vertex of a dropped instance lies outside that plane too: no
triangle of it can reach a pixel, and the picture is the one without culling.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import moderngl
import numpy as np

from ..core.bounds import frustum_planes
from ..core.errors import ContextError
from .buffers import buffer_content, format_bytes
from .shaders import build_compute, build_program

__all__ = ["CullPass", "CullQuery", "IndirectDraws", "shared_query", "ALL_VISIBLE_PLANES", "indirect_supported",
           "INDIRECT_ENV", "choose_indirect"]

#: planes no sphere is outside of (LOD without frustum culling)
ALL_VISIBLE_PLANES = np.tile(np.array([0.0, 0.0, 0.0, 1.0]), (6, 1))
#: environment variable: ``0`` forces the GL 3.3 (transform feedback + query) path
INDIRECT_ENV = "AXIALDEFORM_INDIRECT"
_BLOCK = 256  # instances per block of glsl/cull.comp's rank stage (AXIAL_BLOCK)
_LOCAL = 64  # invocations per work group of its stages 1, 2 and 4
_MAX_GROUPS = 65535  # work groups along x (GL's guaranteed minimum); more go on y


def indirect_supported(ctx) -> bool:
    """Whether ``ctx`` has what the indirect path needs: compute shaders,
    storage buffers, base instance and multi-draw-indirect (GL >= 4.3)."""
    return int(getattr(ctx, "version_code", 0) or 0) >= 430


def choose_indirect(ctx, indirect) -> bool:
    """``indirect``: None picks by version (and :data:`INDIRECT_ENV`); True
    demands the indirect path; False is the GL 3.3 path."""
    if indirect is None:
        return indirect_supported(ctx) and os.environ.get(INDIRECT_ENV, "1").strip() not in ("0", "false", "no", "off")
    if indirect and not indirect_supported(ctx):
        raise ContextError(f"indirect: the indirect culling path needs OpenGL >= 4.3 (compute shaders), this context "
                           f"has {ctx.version_code}; expected indirect=None or False")
    return bool(indirect)


def _field_bytes(fmt: str) -> int:
    """Bytes of one attribute format, padding (``"2x"``) included."""
    return int(fmt[:-1] or 1) if fmt.endswith("x") else format_bytes(fmt)


def shared_query(ctx):
    """ONE ``GL_PRIMITIVES_GENERATED`` query per context, kept on it: moderngl 5
    cannot delete a query, so a query per pass would leak one per renderer."""
    query = getattr(ctx, "_axialdeform_primitives_query", None)
    if query is None:
        query = ctx.query(primitives=True)
        ctx._axialdeform_primitives_query = query
    return query


class IndirectDraws:
    """The draws of one culled frame on the indirect path: every draw slot's
    instance count and first record are on the GPU (written by the pass).

    ``render(vao, mode, key, vertices, first)`` draws slot ``key`` (see
    :class:`CullPass`'s ``draws``) as ``vertices`` indices from index
    ``first``; :meth:`counts` reads the kept instances per level back (the
    one call that waits for the GPU)."""

    def __init__(self, cull: CullPass, levels: int):
        self.cull = cull
        self.levels = levels

    def render(self, vao, mode, key, vertices: int, first: int = 0) -> None:
        vao.render_indirect(self.cull.commands, mode, count=1, first=self.cull.command(key, vertices, first))

    def slot_instances(self, key, vertices: int, first: int = 0) -> tuple[int, int]:
        """``(instance count, base instance)`` of slot ``key`` as the pass wrote them
        (read back: waits for the pass; for drawing it in slices on a software
        rasteriser, where waiting costs nothing)."""
        slot = self.cull.command(key, vertices, first)
        command = np.frombuffer(self.cull.commands.read(size=20, offset=20 * slot), "<u4")
        return int(command[1]), int(command[4])

    def copy_counts(self, buffer) -> None:
        """Copy the counts (4 uint32) into ``buffer`` on the GPU, no wait
        (the next pass may overwrite the pass's own)."""
        self.cull.ctx.copy_buffer(buffer, self.cull.counts_buffer, size=16)

    def counts(self) -> list[int]:
        """Instances kept per level (waits for the pass)."""
        return read_counts(self.cull.counts_buffer, self.levels)


def read_counts(buffer, levels: int) -> list[int]:
    """The first ``levels`` of the four uint32 counts in ``buffer``."""
    return [int(c) for c in np.frombuffer(buffer.read(size=16), dtype="<u4")[:levels]]


@dataclass(frozen=True)
class CullQuery:
    """What one culling pass tests the instances against.

    Attributes
    ----------
    view, projection : (4, 4) float32
        The camera (pyrr layout).
    frustum : bool
        Test against the view frustum (False: every instance is in view).
    center : (3,) float
        Each instance's bounding-sphere centre in model space (the mesh's axis centre).
    radius : float
        The bounding-sphere radius (every LOD level, every bend).
    lod_errors : sequence of float
        Each level's geometric error, model units (up to 4).
    eye : (3,) float
        The camera's position, world.
    px_scale : float
        Pixels per unit of ``error / distance`` (perspective) or per unit (``ortho``).
    ortho : bool
        An orthographic projection.
    lod_px : float
        The largest screen error a level may make, pixels.
    wind_reach : float
        How far the wind and the child axes move a vertex beyond the bound.
    """

    view: object
    projection: object
    frustum: bool = True
    center: tuple = (0.0, 0.0, 0.0)
    radius: float = 1.0
    lod_errors: tuple = (0.0,)
    eye: tuple = (0.0, 0.0, 0.0)
    px_scale: float = 1.0
    ortho: bool = False
    lod_px: float = 1.0
    wind_reach: float = 0.0

    def uniforms(self, levels: int) -> dict:
        """The culling programs' uniforms for ``levels`` LOD levels."""
        planes = frustum_planes(self.view, self.projection) if self.frustum else ALL_VISIBLE_PLANES
        errors = np.zeros(4)
        errors[: len(self.lod_errors)] = self.lod_errors
        return {
            "u_planes": planes, "u_bound_center": tuple(float(c) for c in self.center), "u_radius": float(self.radius),
            "u_wind_reach": float(self.wind_reach),
            "u_levels": int(levels), "u_lod_error": errors, "u_eye": tuple(float(e) for e in self.eye),
            "u_px_scale": float(self.px_scale), "u_ortho": bool(self.ortho), "u_lod_px": float(self.lod_px),
        }


class CullPass:
    """The culling pass of one instance layout (float or quantized, with or
    without tint) and the compacted output buffer.

    ctx : moderngl.Context; instances : InstanceBuffer; defines : dict of the
    renderer's program variant; tint : (buffer, "3f", "i_tint") or None.
    indirect : None (by version, see :func:`indirect_supported`), True or False.
    draws : the draw slots of the indirect path, ``(key, level)`` each: one
    command per slot, whose instance count and base instance the pass fills
    in from the slot's level (``key`` names it for :meth:`IndirectDraws.render`,
    which sets its index count and first index).
    """

    def __init__(self, ctx, instances, defines: dict, tint=None, *, indirect=None, draws=()):
        self.ctx = ctx
        self.instances = instances
        self.tint = tint
        self.tinted = tint is not None
        self._released = False
        self._objects = []
        self.quantized = instances.quantized
        names = ["o_q0", "o_q1", "o_q2", "o_q3"] if self.quantized else ["o_d12", "o_d34", "o_d5", "o_position", "o_angles"]
        if getattr(instances, "extended", False):
            names.append("o_q4" if self.quantized else "o_extra")
        names.append("o_index")
        if self.tinted:
            names.append("o_tint")
        defs = dict(defines)
        if self.tinted:
            defs["AXIAL_TINT"] = 1
        self._defines, self._varyings = defs, names
        self.program = None  # the GL 3.3 pass (transform feedback), built on first use
        self._lod_stage = None  # (program, vao, output buffer): its second, per-level stage, built on first use
        self.query = shared_query(ctx)
        #: bytes of one compacted record: the instance record, the index, the tint
        self.out_bytes = instances.record_bytes + 4 + (12 if self.tinted else 0)
        self.buffer = None
        self.output = None  # the buffer the draw reads: ``buffer``, or the LOD stage's
        #: whether :meth:`run` takes the indirect (compute) path
        self.indirect = choose_indirect(ctx, indirect)
        self.slots = {}
        self.commands = self.counts_buffer = None
        self._scratch = {}  # name -> buffer of the compute path (info, block sums, block offsets)
        try:
            if self.indirect:
                self._build_compute(defs, draws)
            else:
                self._build_feedback()
        except BaseException:  # a shader the driver cannot build: free what was made
            self.release()
            raise

    # ------------------------------------------------------------ building
    def _build_feedback(self) -> None:
        if self.program is not None:
            return
        self.program = build_program(self.ctx, "cull.vert", geometry="cull.geom", defines=self._defines,
                                     varyings=self._varyings)
        self._objects.append(self.program)
        fmts, attrs = self.instances.formats
        content = [buffer_content(self.instances.buffer, fmts, attrs, self.program)]
        if self.tint is not None:
            content.append(buffer_content(self.tint[0], ("3f",), ("i_tint",), self.program))
        self.vao = self.ctx.vertex_array(self.program, content)
        self._objects.append(self.vao)

    def _build_compute(self, defs: dict, draws) -> None:
        words = {"AXIAL_REC_WORDS": self.instances.record_bytes // 4, "AXIAL_TINT_WORDS": 3 if self.tinted else 0}
        self.stages = []
        for stage in (1, 2, 3, 4):
            cs = build_compute(self.ctx, "cull.comp", defines={**defs, **words, "AXIAL_CULL_STAGE": stage})
            self._objects.append(cs)
            self.stages.append(cs)
        levels = np.zeros(max(len(draws), 1), dtype="<u4")
        for slot, (key, level) in enumerate(draws):
            self.slots[key] = slot
            levels[slot] = level
        self._static = {}  # slot -> (index count, first index) written into its command
        self.commands = self.ctx.buffer(np.zeros((len(levels), 5), "<u4").tobytes())
        self._slot_levels = self.ctx.buffer(levels.tobytes())
        self.counts_buffer = self.ctx.buffer(reserve=32)
        self._objects += [self.commands, self._slot_levels, self.counts_buffer]
        self._slot_count = len(draws)
        self.storage_limit = int(self.ctx.info.get("GL_MAX_SHADER_STORAGE_BLOCK_SIZE", 1 << 27))

    def command(self, key, vertices: int, first: int) -> int:
        """The slot of ``key``, its index count and first index written (once)."""
        slot = self.slots[key]
        if self._static.get(slot) != (vertices, first):
            self.commands.write(np.array([vertices], "<u4").tobytes(), offset=20 * slot)
            self.commands.write(np.array([first], "<u4").tobytes(), offset=20 * slot + 8)
            self._static[slot] = (vertices, first)
        return slot

    def ensure_capacity(self, count: int) -> None:
        """Room for ``count`` compacted records (grows by orphaning; never shrinks)."""
        need = max(count, 1) * self.out_bytes
        if self.buffer is None:
            self.buffer = self.ctx.buffer(reserve=need)
        elif self.buffer.size < need:
            self.buffer.orphan(need)

    def _scratch_buffer(self, name: str, size: int):
        buf = self._scratch.get(name)
        if buf is None:
            buf = self._scratch[name] = self.ctx.buffer(reserve=max(size, 16))
        elif buf.size < size:
            buf.orphan(size)
        return buf

    def _lod(self, count: int):
        """The second stage: reads :attr:`buffer` (records + index) and writes
        per-level runs into its own buffer of ``count`` records."""
        if self._lod_stage is None:
            prog = build_program(self.ctx, "cull.vert", geometry="cull.geom",
                                 defines={**self._defines, "AXIAL_CULL_INDEXED": 1}, varyings=self._varyings)
            self._objects.append(prog)
            fmts, attrs = self.instances.formats
            fmts, attrs = fmts + ("1i",) + (("3f",) if self.tinted else ()), attrs + ("i_index",) + (("i_tint",) if self.tinted else ())
            vao = self.ctx.vertex_array(prog, [buffer_content(self.buffer, fmts, attrs, prog)])
            self._objects.append(vao)
            self._lod_stage = [prog, vao, self.ctx.buffer(reserve=max(count, 1) * self.out_bytes)]
        out = self._lod_stage[2]
        if out.size < max(count, 1) * self.out_bytes:
            out.orphan(max(count, 1) * self.out_bytes)
        return self._lod_stage

    @staticmethod
    def _set(program, uniforms: dict) -> None:
        for name, value in uniforms.items():
            if name in program:
                if isinstance(value, np.ndarray):
                    program[name].write(value.astype("f4").tobytes())
                else:
                    program[name].value = value

    def set_uniforms(self, uniforms: dict) -> None:
        self._set(self.program, uniforms)

    # ------------------------------------------------------------ running
    def fits_storage(self, count: int) -> bool:
        """Whether ``count`` instances fit the storage blocks of the indirect path."""
        return max(self.instances.record_bytes, self.out_bytes) * max(count, 1) <= self.storage_limit

    def run(self, count: int, levels: int, query: CullQuery, prepare=None):
        """Cull ``count`` instances for ``query`` (the camera and the instances' bounds).
        Level ``k``'s records start at record ``sum(counts[:k])`` of :attr:`output`.
        ``prepare(program)`` is called on each program before it runs (the renderer's
        quantization table).

        Returns the number kept per LOD level (a list; one entry with
        ``levels == 1``) on the GL 3.3 path, which waits for the GPU's
        count; an :class:`IndirectDraws` on the indirect path, which does not."""
        self.ensure_capacity(count)
        uniforms = query.uniforms(levels)
        if self.indirect and self.fits_storage(count):
            return self._run_compute(count, levels, uniforms, prepare)
        return self._run_feedback(count, levels, uniforms, prepare)

    @staticmethod
    def _grid(invocations: int) -> tuple[int, int, int]:
        """Work groups of :data:`_LOCAL` for ``invocations``: along x, and on
        y too past :data:`_MAX_GROUPS` (the shader skips the extra ones)."""
        groups = max((invocations + _LOCAL - 1) // _LOCAL, 1)
        gx = min(groups, _MAX_GROUPS)
        return gx, (groups + gx - 1) // gx, 1

    def _run_compute(self, count: int, levels: int, uniforms: dict, prepare) -> IndirectDraws:
        ctx = self.ctx
        blocks = (count + _BLOCK - 1) // _BLOCK
        rec = self.instances.record_bytes
        uniforms = {**uniforms, "u_count": count, "u_blocks": blocks, "u_slots": self._slot_count}
        info = self._scratch_buffer("info", 4 * count)
        block_counts = self._scratch_buffer("counts", 16 * blocks)
        offsets = self._scratch_buffer("offsets", 16 * blocks)
        self.instances.buffer.bind_to_storage_buffer(0, size=rec * count)
        if self.tint is not None:
            self.tint[0].bind_to_storage_buffer(1, size=12 * count)
        info.bind_to_storage_buffer(2, size=4 * count)
        block_counts.bind_to_storage_buffer(3, size=16 * blocks)
        offsets.bind_to_storage_buffer(4, size=16 * blocks)
        self.buffer.bind_to_storage_buffer(5, size=self.out_bytes * count)
        self.counts_buffer.bind_to_storage_buffer(6)
        self.commands.bind_to_storage_buffer(7)
        self._slot_levels.bind_to_storage_buffer(8)
        grids = (self._grid(count), self._grid(blocks), (1, 1, 1), self._grid(count))
        for cs, grid in zip(self.stages, grids):
            self._set(cs, uniforms)
            if prepare is not None:
                prepare(cs)
            cs.run(*grid)
            ctx.memory_barrier()  # storage writes -> the next stage, the draws' attributes and commands
        self.output = self.buffer
        return IndirectDraws(self, levels)

    def _run_feedback(self, count: int, levels: int, uniforms: dict, prepare) -> list[int]:
        self._build_feedback()
        self.set_uniforms(uniforms)
        if prepare is not None:
            prepare(self.program)
        self.program["u_level"].value = -1
        with self.query:
            self.vao.transform(self.buffer, mode=moderngl.POINTS, vertices=count)
        visible = int(self.query.primitives)
        self.output = self.buffer
        if levels <= 1:
            return [visible]
        # second stage: only the visible ones, once per level, into consecutive runs
        prog, vao, out = self._lod(count)
        if prepare is not None:
            prepare(prog)
        self._set(prog, uniforms)
        self._set(prog, {"u_planes": ALL_VISIBLE_PLANES})
        counts = []
        offset = 0
        for level in range(levels):
            if offset >= visible:  # every visible instance has its level (and a run past the end is GL_INVALID_VALUE)
                counts.append(0)
                continue
            prog["u_level"].value = level
            with self.query:
                vao.transform(out, mode=moderngl.POINTS, vertices=visible, buffer_offset=offset * self.out_bytes)
            kept = int(self.query.primitives)
            counts.append(kept)
            offset += kept
        self.output = out
        return counts

    def bind_records(self, vao, program, first: int) -> None:
        """Point ``vao``'s instanced attributes at the compacted records from
        record ``first`` on (the indirect path: 0, the commands' base instance
        picks the level)."""
        fmts, attrs = self.instances.formats
        fields = list(zip(fmts, attrs)) + [("1i", "i_index")] + ([("3f", "i_tint")] if self.tinted else [])
        offset = first * self.out_bytes
        for fmt, name in fields:
            if name is not None and name in program:
                cls = "i" if ("u" in fmt or fmt.endswith("i")) else "f"
                vao.bind(program[name].location, cls, self.output, fmt, offset=offset, stride=self.out_bytes, divisor=1)
            offset += _field_bytes(fmt)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        for obj in reversed(self._objects):
            obj.release()
        self._objects.clear()
        for buf in self._scratch.values():
            buf.release()
        self._scratch.clear()
        if self.buffer is not None:
            self.buffer.release()
        if self._lod_stage is not None:
            self._lod_stage[2].release()

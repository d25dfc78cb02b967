"""Per-instance frustum culling and LOD choice on the GPU (GL 3.3 core).

One pass per frame (one per LOD level with LOD on) draws every instance
record as a point through ``glsl/cull.vert`` + ``glsl/cull.geom``: the vertex
shader computes the instance's bounding sphere (``glsl/bounds.glsl``, the
same as :func:`axialdeform.core.bounds.instance_bounds`), tests it against
the six frustum planes and picks its LOD level; the geometry shader emits
only the kept ones, and transform feedback writes them, in their original
order, compacted into one buffer: the record byte for byte, then the
instance's original index (``int``), then its tint (``vec3``) when tinted.
A ``GL_PRIMITIVES_GENERATED`` query gives the count (the buffer holds every
instance, so it equals ``TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN``); the CPU
reads it back before the draw (no indirect drawing yet).  The draw then reads
the compacted records with divisor 1 and the original index as
``i_index`` (``AXIAL_CULLED`` in ``glsl/scene.vert``), so per-instance shading
and tint are those of the unculled draw.

Because a sphere is dropped only when it lies wholly outside one frustum
plane, every vertex of a dropped instance lies outside that plane too: no
triangle of it can reach a pixel, and the picture is the one without culling.
"""

from __future__ import annotations

import numpy as np

from ..core.bounds import frustum_planes
from .buffers import _content, _format_bytes
from .shaders import build_program

__all__ = ["CullPass", "ALL_VISIBLE_PLANES"]

#: planes no sphere is outside of (LOD without frustum culling)
ALL_VISIBLE_PLANES = np.tile(np.array([0.0, 0.0, 0.0, 1.0]), (6, 1))


def _field_bytes(fmt: str) -> int:
    """Bytes of one attribute format, padding (``"2x"``) included."""
    return int(fmt[:-1] or 1) if fmt.endswith("x") else _format_bytes(fmt)


def _shared_query(ctx):
    """ONE ``GL_PRIMITIVES_GENERATED`` query per context, kept on it: moderngl 5
    cannot delete a query, so a query per pass would leak one per renderer."""
    query = getattr(ctx, "_axialdeform_primitives_query", None)
    if query is None:
        query = ctx.query(primitives=True)
        setattr(ctx, "_axialdeform_primitives_query", query)
    return query


class CullPass:
    """The culling program of one instance layout (float or quantized, with or
    without tint) and the compacted output buffer.

    ctx : moderngl.Context; instances : InstanceBuffer; defines : dict of the
    renderer's program variant; tint : (buffer, "3f", "i_tint") or None.
    """

    def __init__(self, ctx, instances, defines: dict, tint=None):
        self.ctx = ctx
        self.instances = instances
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
        self.program = build_program(ctx, "cull.vert", geometry="cull.geom", defines=defs, varyings=names)
        self._objects.append(self.program)
        self._defines, self._varyings = defs, names
        self._lod_stage = None  # (program, vao, output buffer): the second, per-level stage, built on first use
        fmts, attrs = instances.formats
        content = [_content(instances.buffer, fmts, attrs, self.program)]
        if tint is not None:
            content.append(_content(tint[0], ("3f",), ("i_tint",), self.program))
        self.vao = ctx.vertex_array(self.program, content)
        self._objects.append(self.vao)
        self.query = _shared_query(ctx)
        #: bytes of one compacted record: the instance record, the index, the tint
        self.out_bytes = instances.record_bytes + 4 + (12 if self.tinted else 0)
        self.buffer = None
        self.output = None  # the buffer the draw reads: ``buffer``, or the LOD stage's

    def ensure_capacity(self, count: int) -> None:
        """Room for ``count`` compacted records (grows by orphaning; never shrinks)."""
        need = max(count, 1) * self.out_bytes
        if self.buffer is None:
            self.buffer = self.ctx.buffer(reserve=need)
        elif self.buffer.size < need:
            self.buffer.orphan(need)

    def _lod(self, count: int):
        """The second stage: reads :attr:`buffer` (records + index) and writes
        per-level runs into its own buffer of ``count`` records."""
        if self._lod_stage is None:
            prog = build_program(self.ctx, "cull.vert", geometry="cull.geom",
                                 defines={**self._defines, "AXIAL_CULL_INDEXED": 1}, varyings=self._varyings)
            self._objects.append(prog)
            fmts, attrs = self.instances.formats
            fmts, attrs = fmts + ("1i",) + (("3f",) if self.tinted else ()), attrs + ("i_index",) + (("i_tint",) if self.tinted else ())
            vao = self.ctx.vertex_array(prog, [_content(self.buffer, fmts, attrs, prog)])
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

    def run(self, count: int, levels: int, view, projection, *, frustum: bool, center, radius: float,
            lod_errors=(0.0,), eye=(0.0, 0.0, 0.0), px_scale: float = 1.0, ortho: bool = False,
            lod_px: float = 1.0, wind_reach: float = 0.0, prepare=None) -> list[int]:
        """Cull ``count`` instances; returns the number kept per LOD level
        (one entry with ``levels == 1``).  Level ``k``'s records start at
        record ``sum(counts[:k])`` of :attr:`output`.  With LOD, the first
        stage keeps the visible instances and a second stage sorts only those
        into levels (one pass per level).  ``prepare(program)`` is called on
        each program before it runs (the renderer's quantization table)."""
        import moderngl

        self.ensure_capacity(count)
        planes = frustum_planes(view, projection) if frustum else ALL_VISIBLE_PLANES
        errors = np.zeros(4)
        errors[: len(lod_errors)] = lod_errors
        uniforms = {
            "u_planes": planes, "u_bound_center": tuple(float(c) for c in center), "u_radius": float(radius),
            "u_wind_reach": float(wind_reach),
            "u_levels": int(levels), "u_lod_error": errors, "u_eye": tuple(float(e) for e in eye),
            "u_px_scale": float(px_scale), "u_ortho": bool(ortho), "u_lod_px": float(lod_px),
        }
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
        """Point ``vao``'s instanced attributes at the compacted records from record ``first`` on."""
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
        if self.buffer is not None:
            self.buffer.release()
        if self._lod_stage is not None:
            self._lod_stage[2].release()

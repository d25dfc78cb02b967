"""The renderer's shader variants: one program (and its vertex arrays) per
mesh kind, tint, shadow and level of detail, built on first use, and the
uniforms of the axis, the wind and the quantization table they share.
A mixin of :class:`~axialdeform.gl.renderer.AxialRenderer`."""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.errors import ParamError, ShaderError
from ..core.wind import Wind
from .axes import set_axes_uniforms
from .cull import CullPass
from .shaders import build_program
from .uniforms import set_uniforms

__all__ = ["ShaderVariants"]


class ShaderVariants:
    """Methods of :class:`~axialdeform.gl.renderer.AxialRenderer` (see the module)."""

    # ------------------------------------------------------------ plumbing
    @property
    def _edge_buffer(self):
        return self.mesh_buffers.edges if self._part_edges is None else self._part_edges[0]

    @property
    def _edge_count(self) -> int:
        return self.mesh_buffers.edge_indices if self._part_edges is None else self._part_edges[1]

    def _vertex_array(self, program, index_buffer, instance_buffer=None, extra=()):
        content = [self.mesh_buffers.content(program), (instance_buffer or self.instances).content(program), *extra]
        if self.appearance is not None:
            content.append(self.appearance.content(program))
        vao = self.ctx.vertex_array(program, content, index_buffer=index_buffer, index_element_size=4)
        self._objects.append(vao)
        return vao

    def _edges_vao(self, tinted: bool, shadowed: bool = False, windy: bool = False):
        """The vertex array of the edges (plain, tinted, shadow-receiving and/or windy), built on first use."""
        if shadowed or windy:
            entry = self._variants[(tinted, shadowed, windy)]
            if entry[2] is None:
                entry[2] = self._vertex_array(entry[0], self._edge_buffer, extra=entry[3])
            return entry[2]
        if tinted:
            if self._tint[2] is None:
                self._tint[2] = self._vertex_array(self._tint[0], self._edge_buffer,
                                                   extra=[(self._tint[3], "3f/i", "i_tint")])
            return self._tint[2]
        if self._vao_edges is None:
            self._vao_edges = self._vertex_array(self.program, self._edge_buffer)
        return self._vao_edges

    # ------------------------------------------------------------ drawing
    def _variant(self, tinted: bool, shadowed: bool, windy: bool = False):
        """(program, triangles vao, a function that returns the edges vao) of the
        plain, tinted, shadow-receiving and/or windy program (edges: built on first use)."""
        def edges():
            return self._edges_vao(tinted, shadowed, windy)

        if not (shadowed or windy):
            if tinted:
                return self._tint[0], self._tint[1], edges
            return self.program, self._vao_triangles, edges
        key = (tinted, shadowed, windy)
        if key not in self._variants:
            defines = self._variant_defines(tinted=tinted, shadowed=shadowed, windy=windy)
            extra = []
            if tinted:
                extra = [(self._tint[3], "3f/i", "i_tint")]
            prog = build_program(self.ctx, "scene.vert", "scene.frag", defines=defines)
            self._objects.append(prog)
            self._set_axis_uniforms(prog)
            self._variants[key] = [prog, self._vertex_array(prog, self.mesh_buffers.triangles, extra=extra), None, extra]
        entry = self._variants[key]
        return entry[0], entry[1], edges

    def _variant_defines(self, *, tinted=False, shadowed=False, windy=False, culled=False) -> dict:
        """The defines of one build of ``scene.vert``/``scene.frag``: the mesh's (:attr:`_defines`) and what this draw
        uses -- a tint, a shadow map, the wind (``AXIAL_WIND``: left out of the still builds, which then do none of its
        vertex work), the culling pass's output."""
        flags = {"AXIAL_TINT": tinted, "AXIAL_SHADOW": shadowed, "AXIAL_WIND": windy, "AXIAL_CULLED": culled}
        return {**self._defines, **{name: 1 for name, on in flags.items() if on}}

    def _culled_state(self, tinted: bool, shadowed: bool = False, windy: bool = False):
        """The cull pass (one per tint state) and the draw program/VAOs reading
        its output (one per tint/shadow/wind variant), built on first use."""
        state = self._culled.get((tinted, shadowed, windy))
        if state is None:
            cull = self._cull_passes.get(tinted)
            if cull is None:
                tint = (self._tint[3], "3f", "i_tint") if tinted else None
                try:
                    cull = CullPass(self.ctx, self.instances, self._defines, tint=tint, indirect=self._indirect,
                                    draws=self._draw_slots())
                except ShaderError as exc:
                    if self._indirect is not None:
                        raise
                    import warnings  # a driver that cannot build the compute pass: the GL 3.3 one, same picture

                    warnings.warn(f"indirect culling unavailable, using transform feedback: {exc}", RuntimeWarning,
                                  stacklevel=3)
                    self._indirect = False
                    cull = CullPass(self.ctx, self.instances, self._defines, tint=tint, indirect=False)
                self._cull_passes[tinted] = cull
                self._objects.append(cull)
            defines = self._variant_defines(tinted=tinted, shadowed=shadowed, windy=windy, culled=True)
            prog = build_program(self.ctx, "scene.vert", "scene.frag", defines=defines)
            self._objects.append(prog)
            self._set_axis_uniforms(prog)
            vaos = []
            for level in range(len(self._level_buffers)):  # edges: built by the first wireframe draw (lazy edges)
                vaos.append([self._culled_vao(prog, level, self._level_buffers[level].triangles), None])
            state = self._culled[(tinted, shadowed, windy)] = (cull, prog, vaos)
        return state

    def _culled_vao(self, prog, level: int, index_buffer):
        """A vertex array of one LOD level for the culled program (instances: bound by the cull pass)."""
        mb = self._level_buffers[level]
        extra = [self._level_appearance[level].content(prog)] if self.appearance is not None else []
        vao = self.ctx.vertex_array(prog, [mb.content(prog), *extra], index_buffer=index_buffer, index_element_size=4)
        self._objects.append(vao)
        return vao

    def _culled_edges(self, vaos, prog, level: int):
        if vaos[level][1] is None:
            edges = self._edge_buffer if level == 0 else self._level_edge_data(level)[0]
            vaos[level][1] = self._culled_vao(prog, level, edges)
        return vaos[level][1]

    def _level_edge_data(self, level: int):
        """(edge index buffer, index count) of LOD level ``level`` > 0: all its
        edges, or those of the chosen parts only (built on first use)."""
        if self._part_edges is None:
            return self._level_buffers[level].edges, self._level_buffers[level].edge_indices
        if level not in self._level_edges:
            e = self.lod_levels[level].part_edges(self._draw_index)
            buffer = self.ctx.buffer(np.ascontiguousarray(e, dtype="u4"))
            self._objects.append(buffer)
            self._level_edges[level] = (buffer, int(e.size))
        return self._level_edges[level]

    def _set_axis_uniforms(self, program) -> None:
        axis = self.mesh.axis
        # u_frame is a GLSL mat3 (columns): F's rows e_a, e_u, e_v so that u_frame * v = F v
        frame = {"u_frame": np.ascontiguousarray(axis.matrix.T)} if axis.framed else {"u_axis": axis.index}
        set_uniforms(program, {**frame, "u_lo": axis.lo, "u_len": axis.length, "u_center": axis.line,
                               "u_instance_base": 0, "u_wind_strength": 0.0})
        if self.mesh.tree is not None:
            set_axes_uniforms(program, self.mesh.tree)
        self._set_quant_uniforms(program)

    @staticmethod
    def _windy(wind) -> bool:
        """Whether ``wind`` blows (a :class:`Wind` of strength != 0): the draw then needs an ``AXIAL_WIND`` build."""
        if wind is not None and not isinstance(wind, Wind):
            raise ParamError(f"wind: expected an axialdeform.Wind or None, found {type(wind).__name__}")
        return wind is not None and wind.strength != 0

    def _set_wind_uniforms(self, program, wind, time) -> None:
        """The wind's uniforms (strength 0: still); no buffer is written."""
        windy = self._windy(wind)
        if "u_wind_strength" not in program:  # a still build (no AXIAL_WIND), or no bend (AXIAL_NO_BEND)
            return
        if not windy:
            program["u_wind_strength"].value = 0.0
            return
        set_uniforms(program, wind.uniforms(time))

    def _set_quant_uniforms(self, program) -> None:
        """The per-column decode table of a quantized instance buffer (no-op otherwise)."""
        if "u_qmin" in program:
            program["u_qmin"].write(self.instances.qmin[:16].astype("f4").tobytes())
            program["u_qstep"].write(self.instances.qstep[:16].astype("f4").tobytes())
        if "u_qmin_extra" in program:
            program["u_qmin_extra"].value = tuple(float(x) for x in self.instances.qmin[16:19])
            program["u_qstep_extra"].value = tuple(float(x) for x in self.instances.qstep[16:19])

    def _refresh_quant_uniforms(self) -> None:
        if not self.quantized:
            return

        programs = [o for o in self._objects if isinstance(o, moderngl.Program)]
        if self._capture is not None:
            programs.append(self._capture[0])
        for prog in programs:
            self._set_quant_uniforms(prog)

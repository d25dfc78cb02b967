"""The renderer's drawing: parts, one instanced draw each (alpha modes,
alpha-to-coverage, the hidden-line depth pre-pass), culled draws (indirect
or counted), and slices of a big draw on a software rasteriser.
A mixin of :class:`~axialdeform.gl.renderer.AxialRenderer`."""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.bounds import wind_reach
from .context import draw_in_batches, flush_budget
from .cull import CullQuery, IndirectDraws
from .uniforms import eye_position, set_uniforms

#: alpha below which a ``BLEND`` part leaves no depth in depth-only passes (shadows)
BLEND_DEPTH_CUTOFF = 0.5
_GL_SAMPLE_ALPHA_TO_COVERAGE = 0x809E


__all__ = ["Drawing", "BLEND_DEPTH_CUTOFF"]


class Drawing:
    """Methods of :class:`~axialdeform.gl.renderer.AxialRenderer` (see the module)."""

    def _draw_parts(self, prog, vao, view, projection, *, depth_only: bool = False, instances: int | None = None,
                    level: int = 0) -> None:
        """One instanced draw per part: opaque and cut-out parts, then blended ones.
        ``instances``: how many to draw (default :attr:`count`; the visible count after culling);
        ``level``: the LOD level whose parts ``vao`` draws (its parts have the base mesh's materials)."""

        instances = self.count if instances is None else instances
        fbo = self.ctx.fbo
        coverage = None  # whether BLEND parts draw with alpha-to-coverage: asked once per draw
        for part in self._level_parts(level):
            if part.count == 0:
                continue
            material = part.material
            if self.materials is not None:
                self.materials.bind(prog, material, self.color)
            is_blend = material.alpha_mode == "BLEND"
            if is_blend and depth_only:  # shadows and hidden-line depth: a cut-out at alpha 0.5
                set_uniforms(prog, {"u_alpha_mode": 1, "u_alpha_cutoff": BLEND_DEPTH_CUTOFF})
            blend = is_blend and not depth_only
            if blend and coverage is None:
                coverage = self._alpha_to_coverage(fbo)
            if blend and coverage:  # order-independent: depth writes on, alpha -> sample mask
                self.ctx.enable_direct(_GL_SAMPLE_ALPHA_TO_COVERAGE)
            elif blend:
                self.ctx.enable(moderngl.BLEND)
                self.ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
                fbo.depth_mask = False
            try:
                with self.culling(view, projection, enabled=not material.double_sided):
                    self._instanced(vao, moderngl.TRIANGLES, part.count * 3, part.start * 3, instances,
                                    ("t", level, part.start * 3), split=not (blend and not coverage))
            finally:
                if blend and coverage:
                    self.ctx.disable_direct(_GL_SAMPLE_ALPHA_TO_COVERAGE)
                elif blend:
                    fbo.depth_mask = True
                    self.ctx.disable(moderngl.BLEND)

    def _alpha_to_coverage(self, fbo) -> bool:
        """:attr:`alpha_to_coverage`, or (None) whether ``fbo`` is multisampled:
        its first colour attachment has 2 or more samples (a window's default
        framebuffer has none to ask: the viewer sets the attribute)."""
        if self.alpha_to_coverage is not None:
            return bool(self.alpha_to_coverage)
        attachments = getattr(fbo, "color_attachments", None) or ()
        return bool(attachments) and int(getattr(attachments[0], "samples", 0) or 0) > 1

    def _run_cull(self, cull, view, projection, levels: int, *, frustum: bool):
        """Run ``cull`` for the camera ``view``, ``projection``: the counts per
        level (GL 3.3 path) or an :class:`IndirectDraws` (indirect path)."""
        height = float(self.ctx.viewport[3]) if self.ctx.viewport else 1.0
        ortho = abs(float(projection[3, 3]) - 1.0) < 1e-9  # pyrr layout: w = 1 for orthographic
        query = CullQuery(view, projection, frustum=frustum, center=self.mesh.axis.center, radius=self.bound_radius,
                          lod_errors=tuple(level.error for level in self.lod_levels[:levels]), eye=eye_position(view),
                          px_scale=abs(float(projection[1, 1])) * height / 2.0, ortho=ortho, lod_px=self.lod_error,
                          # the wind's and the child axes' reach (several axes) widen every bound
                          wind_reach=wind_reach(self.mesh, self.wind if self.bend else None)
                          + (self.child_reach if self.bend else 0.0))
        return cull.run(self.count, levels, query, prepare=self._set_quant_uniforms)

    def _draw_culled(self, cull, prog, vaos, result, draw_level) -> None:
        """Every level's draws from the cull pass's output: ``draw_level(level,
        triangles vao, edges(), instances)``; ``instances`` is the level's
        count (GL 3.3 path: empty levels are skipped) or the
        :class:`IndirectDraws` (every level is drawn, its count on the GPU)."""
        indirect = isinstance(result, IndirectDraws)
        first = 0
        for level, kept in enumerate([result] * result.levels if indirect else result):
            if indirect or kept:
                vao_t = vaos[level][0]
                cull.bind_records(vao_t, prog, first)

                def culled_edges(level=level, first=first):
                    vao_e = self._culled_edges(vaos, prog, level)
                    cull.bind_records(vao_e, prog, first)
                    return vao_e

                draw_level(level, vao_t, culled_edges, kept)
            if not indirect:
                first += kept

    def _draw(self, prog, vao_triangles, edges, level: int, mode: str, hidden_line, view, projection,
              instances) -> None:
        """``instances`` instances of one level: the parts' triangles, or the
        edges in wireframe (``edges()`` returns their vao: built on first use)."""

        if mode == "wireframe":  # lines are never culled
            if hidden_line:
                self._depth_prepass(prog, vao_triangles, level, view, projection, instances,
                                    fill=hidden_line == "fill")
            fill = hidden_line == "fill"
            set_uniforms(prog, {"u_line_alpha": 0.45 if fill else 1.0})
            if fill:  # the shaded fill shows through the lines
                self.ctx.enable(moderngl.BLEND)
                self.ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
            try:
                blocks = self.mesh_buffers.grid_blocks if level == 0 and self._part_edges is None else None
                if blocks is not None:  # a height map: blocks of rows from one small index buffer
                    if isinstance(instances, IndirectDraws):  # culled: the pass's count and first record
                        count, base = instances.slot_instances(("e", level, 0), self._edge_count, 0)
                    else:
                        count, base = int(instances), 0
                    self._draw_grid_edges(edges(), count, base)
                else:
                    count = self._edge_count if level == 0 else self._level_edge_data(level)[1]
                    self._instanced(edges(), moderngl.LINES, count, 0, instances, ("e", level, 0))
            finally:
                self.ctx.depth_func = "<"
                if fill:
                    self.ctx.disable(moderngl.BLEND)
            return
        self._draw_triangles(prog, vao_triangles, level, view, projection, instances)

    def _draw_triangles(self, prog, vao, level: int, view, projection, instances: int, *, depth_only: bool = False):
        """One instanced draw per part of LOD level ``level`` (0: the base mesh)."""
        self._draw_parts(prog, vao, view, projection, depth_only=depth_only, instances=instances, level=level)

    def _depth_prepass(self, prog, vao, level: int, view, projection, instances: int, fill: bool) -> None:
        """The triangles first, pushed back a little so the lines on them pass
        the ``<=`` test: into the depth buffer only (colour kept by a (0, 1)
        blend), or with ``fill`` also drawn washed-out (``u_mode`` 3)."""

        set_uniforms(prog, {"u_mode": 3 if fill else 0})
        if not fill:
            self.ctx.enable(moderngl.BLEND)
            self.ctx.blend_func = moderngl.ZERO, moderngl.ONE
        self.ctx.polygon_offset = 1.0, 1.0
        try:
            self._draw_triangles(prog, vao, level, view, projection, instances, depth_only=True)
        finally:
            self.ctx.polygon_offset = 0.0, 0.0
            if not fill:
                self.ctx.disable(moderngl.BLEND)
                self.ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
            set_uniforms(prog, {"u_mode": 2})
        self.ctx.depth_func = "<="

    def _draw_slots(self) -> list:
        """The indirect draw commands: ``(key, level)`` of every draw a culled
        frame can make: the triangles of each part (level 0) or of a level,
        the edges of each level."""
        levels = range(len(self._level_buffers))
        slots = [(("t", level, part.start * 3), level) for level in levels for part in self._level_parts(level)]
        return slots + [(("e", level, 0), level) for level in levels]

    def _level_parts(self, level: int) -> list:
        """The parts drawn at LOD level ``level``, in draw order (opaque and cut-out, then blended):
        the chosen parts of the base mesh (level 0) or their simplified counterparts."""
        if level == 0:
            return self._draw_order
        return [self.lod_levels[level].parts[i] for i in self._draw_index]

    def _instanced(self, vao, mode, vertices: int, first: int, instances, key, *, split: bool = True) -> None:
        """One instanced draw: ``instances`` a count, or the GPU's (:class:`IndirectDraws`, slot ``key``).
        On a software rasteriser a big multisampled draw is made in slices
        (:func:`~axialdeform.gl.context.flush_budget`): of whole instances, in order,
        for a small mesh (GL 4.2); else of its index range
        (:func:`~axialdeform.gl.context.draw_in_batches`), but not when ``split`` is
        False (blended parts, whose order matters)."""

        if isinstance(instances, IndirectDraws):
            def draw(n, start):
                instances.render(vao, mode, key, n, start)
        else:
            def draw(n, start):
                vao.render(mode, vertices=n, first=start, instances=instances)
        per = 2 if mode == moderngl.LINES else 3
        budget = flush_budget(self.ctx, per)
        primitives = vertices // per
        if budget is None or primitives * max(self.count, 1) <= budget:
            draw(vertices, first)
            return
        if 4 * primitives <= budget and self.ctx.version_code >= 420:
            # a small mesh, many instances: slices of whole instances, in order (indirect
            # commands with a base instance, GL 4.2), so the very same picture, blended or not
            if isinstance(instances, IndirectDraws):
                count, base = instances.slot_instances(key, vertices, first)  # waits for the culling pass
            else:
                count, base = int(instances), 0
            self._draw_instance_slices(vao, mode, vertices, first, count, base, max(1, budget // primitives))
            return
        if not split:
            draw(vertices, first)
            return
        # a big mesh (or GL 3.3): slices of its triangles, every instance in each, sized for
        # EVERY instance whatever this draw's count (culled, a level's): the same slices
        # with and without culling, so the same order and the same picture
        draw_in_batches(self.ctx, draw, vertices, first, per, max(self.count, 1))

    def _draw_grid_edges(self, vao, instances: int, base: int = 0) -> None:
        """A height map's wireframe: every block of grid rows drawn from the one
        block-sized index buffer with its base vertex (an indirect command each,
        in the order of the whole edge list: the same picture), the GL queue
        finished after each block on a software rasteriser (bounded memory)."""
        if self._slice_commands is None:
            self._slice_commands = self.ctx.buffer(reserve=20)
            self._objects.append(self._slice_commands)
        finish = flush_budget(self.ctx, 2) is not None
        if instances <= 0:
            return
        for command in self.mesh_buffers.grid_edge_draws(int(instances), int(base)):
            self._slice_commands.write(np.array(command, "<u4").tobytes())
            vao.render_indirect(self._slice_commands, moderngl.LINES, count=1, first=0)
            if finish:
                self.ctx.finish()

    def _draw_instance_slices(self, vao, mode, vertices: int, first: int, count: int, base: int, step: int) -> None:
        """Draw instances ``base .. base + count`` in slices of ``step``, the GL queue
        finished after each (one indirect command a slice, base instance set)."""
        if self._slice_commands is None:
            self._slice_commands = self.ctx.buffer(reserve=20)
            self._objects.append(self._slice_commands)
        # gl_InstanceID restarts at 0 in every draw (GLSL 3.30 has no gl_BaseInstance): the
        # unculled program adds u_slice_base (the culled one reads each record's own index)
        slice_base = vao.program.get("u_slice_base", None)
        try:
            for start in range(0, count, step):
                n = min(step, count - start)
                self._slice_commands.write(np.array([vertices, n, first, 0, base + start], "<u4").tobytes())
                if slice_base is not None:
                    slice_base.value = base + start
                vao.render_indirect(self._slice_commands, mode, count=1, first=0)
                self.ctx.finish()
        finally:
            if slice_base is not None:
                slice_base.value = 0

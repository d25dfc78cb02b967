"""The renderer's capture: what the GPU draws, read back by transform
feedback in chunks (what the CPU reference is tested against).
A mixin of :class:`~axialdeform.gl.renderer.AxialRenderer`."""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.errors import ParamError
from ..core.io.safeio import require_finite
from .buffers import InstanceBuffer, as_index
from .context import bind_framebuffer, release_framebuffer
from .shaders import build_program

_CAPTURE_BYTES = 128 * 1024 * 1024  # transform feedback output per pass
_KEEP = object()  # capture(wind=...) not given: keep the renderer's wind


__all__ = ["Capture"]


class Capture:
    """Methods of :class:`~axialdeform.gl.renderer.AxialRenderer` (see the module)."""

    # ------------------------------------------------------------ capture
    def capture(self, start: int = 0, count: int | None = None, progress=None, *, time: float | None = None,
                wind=_KEEP, check_finite: bool = True, level: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """World positions and normals as the GPU computes them, by transform
        feedback of the drawing vertex shader.

        A non-finite result (parameters too large for float32) raises
        :class:`AxialDeformError` naming the instance and coordinate.
        Returns two ``(count, vertices, 3) float32`` arrays in the base mesh's
        vertex order, for instances ``start .. start + count - 1``.
        ``progress``: optional object with ``update(instances_done)`` (a tqdm bar).
        ``time``, ``wind``: as :meth:`render` (default: the renderer's own).
        ``level``: the LOD level whose vertices are captured (0: the base
        mesh; ``len(lod_levels) - 1`` at most), in that level's vertex order,
        bent with the base mesh's axis like every level.
        """

        self._check()
        self._bind_axes()
        start = as_index(start, "capture: start")
        level = as_index(level, "capture: level")
        if not 0 <= level < len(self.lod_levels):
            raise ParamError(f"capture: level: expected 0..{len(self.lod_levels) - 1}, found {level}")
        count = self.count - start if count is None else as_index(count, "capture: count")
        if start < 0 or count < 0 or start + count > self.count:
            raise ParamError(f"capture: instances {start}..{start + count - 1} are outside 0..{self.count - 1}")
        v = self.lod_levels[level].vertex_count
        per_instance = max(lv.vertex_count for lv in self.lod_levels) * 24  # room for any level
        chunk = max(1, min(count, _CAPTURE_BYTES // per_instance))
        wind = self.wind if wind is _KEEP else wind
        windy = self._windy(wind)  # the still build leaves the wind out (glsl/scene.vert, AXIAL_WIND)
        if self._capture is None or self._capture[2].capacity < chunk or self._capture_windy != windy:
            self._release_capture()
            prog = build_program(self.ctx, "scene.vert", defines=self._variant_defines(windy=windy),
                                 varyings=("v_world", "v_normal"))
            self._capture_windy = windy
            self._set_axis_uniforms(prog)
            scratch = InstanceBuffer(self.ctx, capacity=chunk, quantized=self.quantized, extended=self.extended)
            vao = self.ctx.vertex_array(prog, [self.mesh_buffers.content(prog), scratch.content(prog)])
            output = self.ctx.buffer(reserve=chunk * per_instance)
            # a draw needs a complete framebuffer even with rasterization
            # discarded; a surfaceless EGL context has none of its own
            color = self.ctx.renderbuffer((1, 1))
            fbo = self.ctx.framebuffer(color)
            self._capture = (prog, vao, scratch, output, fbo, color)
            self._capture_levels = {0: vao}
        prog, _, scratch, output, fbo, _ = self._capture
        if level not in self._capture_levels:  # a coarser level's vertices, same program and instances
            self._capture_levels[level] = self.ctx.vertex_array(
                prog, [self._level_buffers[level].content(prog), scratch.content(prog)])
        vao = self._capture_levels[level]
        self._set_wind_uniforms(prog, wind, self.time if time is None else float(time))
        out = np.empty((count, v, 6), dtype=np.float32)
        previous = self.ctx.fbo
        fbo.use()
        try:
            for a in range(0, count, chunk):  # chunks bound GPU memory; each is one transform-feedback draw
                k = min(chunk, count - a)
                rec = self.instances.record_bytes
                self.ctx.copy_buffer(scratch.buffer, self.instances.buffer, size=k * rec, read_offset=(start + a) * rec)
                scratch.count = k
                if "u_instance_base" in prog:  # the wind's per-instance phase follows the instance's index
                    prog["u_instance_base"].value = start + a
                vao.transform(output, mode=moderngl.POINTS, vertices=v, instances=k)
                out[a : a + k] = np.frombuffer(output.read(size=k * v * 24), dtype="f4").reshape(k, v, 6)
                if progress is not None:
                    progress.update(k)
        finally:
            bind_framebuffer(self.ctx, previous)  # give the caller back their framebuffer
        positions, normals = out[..., :3].copy(), out[..., 3:].copy()
        # parameters too large for float32 overflow on the GPU: an error naming the instance
        if check_finite:  # bake() checks itself, naming the parameter file
            require_finite(positions, "positions", "xyz", first=start)
            require_finite(normals, "normals", "xyz", first=start)
        return positions, normals

    def _release_capture(self) -> None:
        if self._capture is not None:
            prog, vao, scratch, output, fbo, color = self._capture
            release_framebuffer(self.ctx, fbo)
            for obj in (*[a for lv, a in self._capture_levels.items() if lv], vao, prog, scratch, output, color):
                obj.release()
            self._capture = None

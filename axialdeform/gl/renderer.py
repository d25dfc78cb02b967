"""The renderer: one base mesh, every instance bent by its own control axis
in the vertex shader, all instances in ONE instanced draw call.

Use it inside your own moderngl program::

    import axialdeform as ad
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 1000, seed=1)
    with ad.AxialRenderer(ctx, mesh, params) as r:
        r.render(view, proj, mode="solid")      # pyrr matrices, as built by pyrr

``view`` and ``proj`` are (4, 4) matrices in pyrr's layout (what
``pyrr.matrix44.create_look_at`` / ``create_perspective_projection``
return); the shader computes ``clip = proj * view * world``.
"""

from __future__ import annotations

from contextlib import contextmanager

import moderngl
import numpy as np

from ..core.arrays import as_array
from ..core.bounds import base_radius
from ..core.errors import ArgumentError, AxialDeformError, ParamError, ShaderError
from ..core.lod import LodLevel, build_lod_levels, check_lod_error
from ..core.look import DEFAULT_LOOK, Look
from ..core.material import DEFAULT_COLORS, default_color  # noqa: F401  the default colour's one home
from ..core.options import RENDERER_FIELDS, RenderOptions
from ..core.params import check_tree_params, is_extended
from ..core.record import split_record, tint_columns
from .axes import AxesTexture
from .buffers import InstanceBuffer, MeshBuffers
from .capture import Capture
from .context import check_alive, require_framebuffer
from .cull import IndirectDraws, choose_indirect, read_counts
from .draw import BLEND_DEPTH_CUTOFF, Drawing
from .material import AppearanceBuffer, GpuMaterials
from .shaders import build_program
from .uniforms import camera_matrices, set_camera_uniforms, set_uniforms
from .variants import ShaderVariants

__all__ = ["AxialRenderer", "MODES", "DEFAULT_COLORS", "BLEND_DEPTH_CUTOFF", "MODE_INDEX", "unit_vector"]

MODES = ("solid", "flat", "wireframe")
MODE_INDEX = {"solid": 0, "flat": 1, "wireframe": 2}
#: render(look=None): the default light and lines, every edge drawn (no depth pre-pass)
_PLAIN_LOOK = DEFAULT_LOOK.replace(hidden_line=False)


class AxialRenderer(ShaderVariants, Drawing, Capture):
    """Draws ``count`` deformed instances of one base mesh.

    Parameters
    ----------
    ctx : moderngl.Context
        The caller's context (GL 3.3 core or newer).
    mesh : BaseMesh
        The base mesh.
    params : (n, 16) float32, optional
        The 16 numbers per instance, or (n, 19): extended instances (scale,
        twist, taper after the 16), or (n, 22): tinted instances (their
        tint colours them, as :meth:`set_tint` does).
    options : RenderOptions, optional
        How to draw (:class:`~axialdeform.core.options.RenderOptions`:
        ``AxialRenderer(ctx, mesh, params, RenderOptions(culling=False))``).
    capacity : int, optional
        Instances to reserve room for (``set_params`` up to it never reallocates).
    **fields
        Deprecated (they still work for one release, with a DeprecationWarning): fields of
        :class:`RenderOptions` that replace ``options``': ``bend``,
        ``quantized``, ``cull_back_faces``, ``parts``, ``extended``, ``wind``, ``culling``,
        ``lod``, ``lod_error``, ``indirect``, ``position_ids`` (what each does: its docstring).

    Notes
    -----
    A mesh with UVs, vertex colours, several parts or a material
    (:attr:`BaseMesh.has_appearance`) is drawn with ``AXIAL_MATERIAL``:
    textures (sRGB), vertex colours, ``MASK`` cut-outs, ``BLEND`` parts after
    the opaque ones -- with alpha-to-coverage into a multisampled target
    (order-independent, with depth writes; :attr:`alpha_to_coverage`), else
    blended unsorted without depth writes -- normal maps and two-sided
    lighting where the material is double-sided.  In depth-only passes
    (shadows, hidden-line depth) a ``BLEND`` part is a cut-out at alpha
    :data:`BLEND_DEPTH_CUTOFF`: it casts shadows where it is mostly opaque.
    :attr:`stats` describes the last :meth:`render`: instances submitted,
    visible (drawn), per LOD level, and vertices processed.
    """

    def __init__(self, ctx, mesh, params=None, options: RenderOptions | None = None, *, capacity: int | None = None,
                 **fields):
        check_alive(ctx, "a new AxialRenderer")
        opts = RenderOptions.of(options, fields, "AxialRenderer", RENDERER_FIELDS)
        bend, quantized, cull_back_faces, parts = opts.bend, opts.quantized, opts.cull_back_faces, opts.parts
        extended, wind, culling, lod, lod_error, indirect = (opts.extended, opts.wind, opts.culling, opts.lod,
                                                             opts.lod_error, opts.indirect)

        self.ctx = ctx
        self.mesh = mesh
        self.parts = tuple(mesh.parts) if parts is None else tuple(
            mesh.part(n) for n in ([parts] if isinstance(parts, str) else parts))
        if not self.parts:
            raise AxialDeformError(f"{mesh.name}: parts: expected at least one part name, found none")
        # opaque and cut-out parts first, blended ones last (unsorted)
        self._draw_order = sorted(self.parts, key=lambda p: p.material.alpha_mode == "BLEND")
        # where each drawn part sits in mesh.parts (and so in every LOD level's parts)
        self._draw_index = [next(i for i, q in enumerate(mesh.parts) if q is p) for p in self._draw_order]
        self.bend = bend
        self.culling_enabled = bool(culling)
        self.lod = bool(lod)
        self.lod_error = check_lod_error(lod_error)
        self._stats: dict = {}
        self._stats_gpu = None  # (buffer, levels): counts of the last indirect frame, read when stats is asked
        self._stats_buffer = None
        self._indirect = indirect
        self.shadow_result = None
        if indirect:

            choose_indirect(ctx, True)  # a context below GL 4.3: the error now, not at the first draw
        self.cull_back_faces = bool(mesh.is_volume) if cull_back_faces is None else bool(cull_back_faces)
        self.quantized = bool(quantized)
        self._released = False
        self._objects = []
        self._slice_commands = None  # the one indirect command of instance slices (software rasterisers)
        #: K, the mesh's axes: K > 1 draws with AXIAL_AXES (child offsets in a texture, gl/axes.py)
        self.axis_count = mesh.axis_count
        self._axes = None
        params, children = self._split_axes(params)
        defines = {} if bend else {"AXIAL_NO_BEND": 1}
        if self.axis_count > 1:
            defines["AXIAL_AXES"] = self.axis_count
        if self.quantized:
            defines["AXIAL_QUANTIZED"] = 1
        if mesh.has_appearance:
            defines["AXIAL_MATERIAL"] = 1
        if mesh.axis.framed:  # a chosen axis frame: u_frame instead of u_axis (glsl/scene.vert)
            defines["AXIAL_FRAME"] = 1
        if extended is None:
            extended = params is not None and is_extended(params)
        self.extended = bool(extended)
        if self.extended:
            defines["AXIAL_EXTENDED"] = 1
        #: the instances' wind phases and shades hash where they stand, not their index (a generated layer's)
        self.position_ids = bool(opts.position_ids)
        if self.position_ids:
            defines["AXIAL_POSITION_IDS"] = 1
        self._defines = defines
        self.appearance = None
        self.materials = None
        self._variants = {}
        #: ``BLEND`` parts: True draws them with alpha-to-coverage (order-independent,
        #: depth-tested against each other; needs a multisampled target), False
        #: blends them unsorted without depth writes, None (default) picks
        #: alpha-to-coverage when the bound framebuffer is multisampled
        self.alpha_to_coverage = None
        #: the wind (:class:`axialdeform.Wind`) or None (still); set it any time
        self.wind = wind
        #: seconds: the time the wind is drawn at (``render(time=...)`` sets it)
        self.time = 0.0
        try:
            self.program = build_program(ctx, "scene.vert", "scene.frag", defines=defines)
            self._objects.append(self.program)
            self.mesh_buffers = MeshBuffers(ctx, mesh)
            if mesh.has_appearance:
                self.appearance = AppearanceBuffer(ctx, mesh)
                self.materials = GpuMaterials(ctx, mesh)
            self._part_edges = None
            if len(self.parts) != len(mesh.parts):  # wireframe of the chosen parts only
                faces = np.concatenate([mesh.faces[p.start:p.start + p.count] for p in self.parts])
                e = np.unique(np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0).astype("u4")
                self._part_edges = (ctx.buffer(e), int(e.size))
                self._objects.append(self._part_edges[0])
            self.instances = InstanceBuffer(ctx, params, capacity, quantized=self.quantized, extended=self.extended)
            if self.axis_count > 1:
                self._axes = AxesTexture(ctx, mesh.tree, children, capacity)
            self._vao_triangles = self._vertex_array(self.program, self.mesh_buffers.triangles)
            self._vao_edges = None  # built by the first wireframe draw (lazy edges)
            #: the levels of detail (level 0 is the base mesh itself)
            self.lod_levels = build_lod_levels(mesh) if self.lod else [LodLevel.of(mesh)]
            self._level_buffers = [self.mesh_buffers]
            self._level_appearance = [self.appearance]
            self._level_edges = {}  # level -> (edge buffer, indices) of the chosen parts (levels > 0)
            for level in self.lod_levels[1:]:
                self._level_buffers.append(MeshBuffers(ctx, level))
                if self.appearance is not None:
                    self._level_appearance.append(AppearanceBuffer(ctx, level))
        except BaseException:
            self.release()
            raise
        self._capture = None  # (program, vao, scratch instances, output) built on first capture
        self._capture_windy = False  # whether the capture program is the windy build
        self._tint = None  # (program, triangles vao, edges vao, buffer) built by the first set_tint
        self._tint_count = None  # colours in the tint buffer; None: tint off
        self._tint_from_record = False  # the tint came with tinted (n, 22) parameters, not from set_tint
        self._cull_passes = {}  # tinted -> CullPass
        self._culled = {}  # (tinted, shadowed, windy) -> (CullPass, draw program, [(triangles vao, edges vao) per level])
        #: bounding-sphere radius about ``mesh.axis.center`` covering every LOD level
        self.bound_radius = base_radius(mesh, *[level.positions for level in self.lod_levels[1:]])
        self._set_axis_uniforms(self.program)
        if params is not None:
            self._record_tint(params)
        self.color = default_color(mesh)
        #: world up (unit vector), for the sky/ground hemisphere ambient
        self.up = (0.0, 1.0, 0.0)

    def _check(self) -> None:
        if self._released:
            raise AxialDeformError("this AxialRenderer was released; create a new one")
        check_alive(self.ctx, "this AxialRenderer")

    # ------------------------------------------------------------ parameters
    @property
    def count(self) -> int:
        """Number of instances drawn."""
        return self.instances.count

    @property
    def stats(self) -> dict:
        """What the last :meth:`render` drew: ``submitted``, ``visible``,
        ``levels`` (visible per LOD level), ``vertices`` (processed by the
        vertex shader), ``culling``, ``lod``, ``indirect``.  On the indirect
        path the counts stay on the GPU until this is read: reading it waits
        for that frame's culling pass, a frame that never asks never waits."""
        if self._stats_gpu is not None:
            buffer, levels = self._stats_gpu
            self._stats_gpu = None
            counts = read_counts(buffer, levels)
            self._stats.update(visible=int(sum(counts)), levels=counts,
                               vertices=int(sum(k * self.lod_levels[i].vertex_count for i, k in enumerate(counts))))
        return self._stats

    def _split_axes(self, params):
        """``params`` of a K-axis mesh as (axis 0's standard record, the child
        axes' offsets (n, K−1, 5, 2)); ``(params, None)`` for one axis."""
        if self.axis_count == 1 or params is None:
            return params, (np.zeros((0, self.axis_count - 1, 5, 2), np.float32) if self.axis_count > 1 else None)
        return split_record(check_tree_params(params, self.axis_count), self.axis_count)

    @property
    def child_reach(self) -> float:
        """How far the child axes of any instance can move a vertex (model
        units; 0 for one axis): what culling adds to each bound."""
        return 0.0 if self._axes is None else self._axes.child_reach

    def _bind_axes(self) -> None:
        if self._axes is not None:
            self._axes.bind()

    def set_params(self, params) -> None:
        """Replace all parameters with ``params`` (n, 16|19|22) float32; the buffer is reallocated only if the
        count grows past its capacity.  A mesh of K axes takes ``(n, 10·K + 6)`` (``+ 3`` extended, ``+ 6`` tinted)."""
        self._check()
        params, children = self._split_axes(params)
        self.instances.set(params)
        if self._axes is not None:
            self._axes.set(children)
        self._refresh_quant_uniforms()
        self._record_tint(params)

    def _record_tint(self, params) -> None:
        """Tinted parameters ((n, 22)) colour the instances by their own tint
        (the record's ``tr tg tb``: :func:`set_tint` with them); parameters
        without one end a tint that came from a record (not one set by hand)."""
        tint = tint_columns(params)
        if tint is not None:
            self.set_tint(tint)
            self._tint_from_record = True
        elif self._tint_from_record:
            self.set_tint(None)

    def update_params(self, params, start: int = 0) -> None:
        """Overwrite the instances ``start .. start + len(params) - 1`` in place.

        ``start`` must be an integer (int or numpy integer): a float, a
        string, None or NaN raises :class:`ArgumentError`."""
        self._check()
        params, children = self._split_axes(params)
        self.instances.update(params, start, setter="set_params()", name="update_params")
        if self._axes is not None:
            self._axes.update(children, start)
        tint = tint_columns(params)
        if tint is not None and self._tint_count is not None and len(tint):
            self._tint[3].write(np.ascontiguousarray(tint, dtype=np.float32).tobytes(), offset=int(start) * 12)

    # ------------------------------------------------------------ instances written on the GPU
    def gpu_targets(self, capacity: int, *, tint: bool = False) -> tuple:
        """Room for ``capacity`` instances that a GPU pass writes (a generated layer, :mod:`~axialdeform.gl.generated`):
        ``(instance buffer, tint buffer or None, child-axes texture or None)``, grown where needed, nothing
        written.  The pass writes the records in this renderer's layout (float32, 16 numbers or 19 extended),
        the tints (``tint=True``: 3 float32 an instance) and a tree's child-axis texels, then calls
        :meth:`gpu_written`."""
        self._check()
        if self.quantized:
            raise AxialDeformError("gpu_targets: instances written on the GPU need a float32 renderer (quantized=False)")
        self.instances.reserve(capacity)
        if self._axes is not None:
            self._axes.reserve(capacity)
        buffer = None
        if tint:
            if self._tint is None:
                self.set_tint(np.zeros((0, 3), np.float32))
            buffer = self._tint[3]
            if buffer.size < capacity * 12:
                buffer.orphan(capacity * 12)
        return self.instances.buffer, buffer, None if self._axes is None else self._axes.texture

    def gpu_written(self, count: int, *, tint: bool = False, child_reach: float = 0.0) -> None:
        """``count`` instances are in :meth:`gpu_targets`' buffers (``tint``: with their tints; with child axes
        that move a vertex at most ``child_reach`` model units: culling's bound)."""
        self.instances.count = int(count)
        self._tint_count = int(count) if tint else None
        self._tint_from_record = bool(tint)
        if self._axes is not None:
            self._axes.count = int(count)
            self._axes.child_reach = float(child_reach)

    # ------------------------------------------------------------ optional tint
    def set_tint(self, colors) -> None:
        """Give every instance its own base colour; ``None`` goes back to ``color``.

        colors : (count, 3) linear RGB in 0..1, one row per instance in the
            order of the parameters, or None.

        Tinted parameters ((n, 22): the record's ``tint`` field) call this
        with their own colours; calling it by hand replaces those.

        The colours live in a second instanced buffer (12 bytes an instance)
        read by a variant of the program compiled with ``AXIAL_TINT``; the
        draw stays ONE instanced call.  A renderer that never calls this keeps
        the plain program and pays nothing.  Calling it again with the same
        count overwrites the buffer in place.
        """
        self._check()
        self._tint_from_record = False
        if colors is None:
            self._tint_count = None
            return
        values = np.ascontiguousarray(colors, dtype=np.float32)
        if values.ndim != 2 or values.shape[1] != 3 or not np.isfinite(values).all():
            raise ParamError(f"tint: expected (count, 3) finite linear RGB, found shape {values.shape}")
        if self._tint is None:
            prog = build_program(self.ctx, "scene.vert", "scene.frag", defines={**self._defines, "AXIAL_TINT": 1})
            self._objects.append(prog)
            buffer = self.ctx.buffer(reserve=max(len(values), self.instances.capacity, 1) * 12)
            self._objects.append(buffer)
            tint = (buffer, "3f/i", "i_tint")
            self._set_axis_uniforms(prog)
            self._tint = [prog, self._vertex_array(prog, self.mesh_buffers.triangles, extra=[tint]), None, buffer]
        buffer = self._tint[3]
        if values.nbytes > buffer.size:
            buffer.orphan(values.nbytes)
        if len(values):
            buffer.write(values.tobytes())
        self._tint_count = len(values)

    def render(self, view, projection, mode: str = "solid", *, look: Look | None = None, shadow=None,
               time: float | None = None) -> None:
        """Draw every instance into the currently bound framebuffer: one
        instanced draw call per part (one for a single-part mesh), after the
        culling pass (when on) that keeps the visible instances.

        Parameters
        ----------
        view, projection : (4, 4) float32
            pyrr-layout matrices (``clip = projection * view * world``).
        mode : {"solid", "flat", "wireframe"}
            Analytic normals, face normals of the deformed triangles, or the
            mesh's edges as lines.
        look : Look, optional
            Light, ambient, line colour and wireframe style
            (:class:`axialdeform.Look`); None: the default look with every
            edge drawn.  With ``look.hidden_line`` a wireframe first fills
            the depth buffer with the triangles, so only the lines of the
            front-most surface show; ``"fill"`` also paints the triangles,
            washed out towards white, under the lines.
        shadow : ShadowMap, optional
            Already drawn (:meth:`render_shadow`) from the same light: the
            sun is shadowed by the instances (the ambient is not).
        time : float, optional
            Seconds; sets :attr:`time`, the clock of :attr:`wind`.

        Notes
        -----
        The base colour is :attr:`color`, world up (for the hemisphere
        ambient) :attr:`up` and the wind :attr:`wind`: set them on the
        renderer.  Animating the wind sets uniforms only: no buffer is written.
        """
        look = _PLAIN_LOOK if look is None else look
        if not isinstance(look, Look):
            raise ArgumentError(f"look: expected an axialdeform.Look, found {type(look).__name__}")
        light_dir, ambient, hidden_line = look.light_dir, look.ambient, look.wire_style

        self._check()
        self._bind_axes()
        if mode not in MODE_INDEX:
            raise ArgumentError(f"render mode: expected one of {', '.join(MODES)}, found {mode!r}")
        view, projection = camera_matrices(view, projection)
        require_framebuffer(self.ctx, "AxialRenderer.render")
        tinted = self._tint_count is not None
        if tinted and self._tint_count != self.count:
            raise ParamError(f"tint: {self._tint_count} colours for {self.count} instances; "
                             "call set_tint with one colour per instance (or None)")
        if time is not None:
            self.time = float(time)
        shadowed = shadow is not None and (mode != "wireframe" or hidden_line == "fill")
        windy = self._windy(self.wind)
        n = self.count
        state = None
        if (self.culling_enabled or self.lod) and n:
            try:
                state = self._culled_state(tinted, shadowed, windy)
            except ShaderError as exc:  # a driver that cannot build the pass: plain drawing, same picture
                import warnings

                warnings.warn(f"culling/LOD pass unavailable, drawing every instance: {exc}", RuntimeWarning, stacklevel=2)
                self.culling_enabled = self.lod = False
        if state is not None:
            cull, prog, vaos = state
        else:
            prog, vao_triangles, edges = self._variant(tinted, shadowed, windy)
        set_camera_uniforms(prog, view, projection)
        self._set_wind_uniforms(prog, self.wind, self.time)
        set_uniforms(prog, {
            "u_mode": MODE_INDEX[mode],
            "u_color": tuple(self.color),
            "u_line_color": tuple(look.line_color),
            "u_light_dir": tuple(unit_vector(light_dir, "light_dir")),
            "u_light_color": look.light_color, "u_sky_color": look.sky_color, "u_bounce_color": look.ground_color,
            "u_up": tuple(unit_vector(self.up, "up")),
            "u_ambient": float(ambient),
        })
        if shadowed:
            shadow.bind(prog)
        self._stats_gpu = None
        self._stats = {"submitted": n, "visible": n, "levels": [n], "vertices": n * self.mesh.vertex_count,
                       "culling": False, "lod": False, "indirect": False}
        if n == 0:
            return
        self.ctx.enable(moderngl.DEPTH_TEST)
        if state is None:
            self._draw(prog, vao_triangles, edges, 0, mode, hidden_line, view, projection, n)
            return
        if self.quantized:
            self._set_quant_uniforms(prog)
        levels = len(self.lod_levels) if self.lod else 1
        result = self._run_cull(cull, view, projection, levels, frustum=self.culling_enabled)
        self._stats.update(culling=self.culling_enabled, lod=self.lod)
        if isinstance(result, IndirectDraws):  # the counts stay on the GPU: copied, read when stats is asked
            if self._stats_buffer is None:
                self._stats_buffer = self.ctx.buffer(reserve=16)
                self._objects.append(self._stats_buffer)
            result.copy_counts(self._stats_buffer)
            self._stats_gpu = (self._stats_buffer, levels)
            self._stats.update(indirect=True)
        else:
            self._stats.update(visible=int(sum(result)), levels=result,
                               vertices=int(sum(k * self.lod_levels[i].vertex_count for i, k in enumerate(result))))

        def draw_level(level, vao_t, edges, instances):
            self._draw(prog, vao_t, edges, level, mode, hidden_line, view, projection, instances)

        self._draw_culled(cull, prog, vaos, result, draw_level)

    def render_shadow(self, shadow, *, clear: bool = True) -> None:
        """Draw the instances into ``shadow`` (a :class:`~axialdeform.gl.shadow.ShadowMap`,
        fitted with :meth:`ShadowMap.fit`): one instanced depth draw per part;
        ``MASK`` cut-outs cast cut-out shadows, and the wind of the next
        :meth:`render` bends the shadows too.  With culling on, the culling
        pass first keeps the casters whose bound reaches the light's view
        volume (every level of detail is the full mesh here): the same shadow
        map, fewer vertices.  Restores the caller's framebuffer.  ``clear=False``
        adds these casters to a map other renderers drew (a scene's layers)."""
        self._check()
        self._bind_axes()
        state = None
        windy = self._windy(self.wind)
        if self.culling_enabled and self.count:
            try:
                state = self._culled_state(False, False, windy)
            except ShaderError as exc:
                import warnings

                warnings.warn(f"culling pass unavailable, drawing every caster: {exc}", RuntimeWarning, stacklevel=2)
                self.culling_enabled = False
        prog, vao, _ = self._variant(False, False, windy) if state is None else (state[1], None, None)
        with shadow.target(clear):
            if self.count == 0:
                return
            set_camera_uniforms(prog, shadow.view, shadow.projection)
            self._set_wind_uniforms(prog, self.wind, self.time)
            set_uniforms(prog, {"u_mode": 0})

            self.ctx.enable(moderngl.DEPTH_TEST)
            if state is None:
                self._draw_parts(prog, vao, None, None, depth_only=True)
                return
            cull, _, vaos = state
            if self.quantized:
                self._set_quant_uniforms(prog)
            result = self._run_cull(cull, shadow.view, shadow.projection, 1, frustum=True)
            #: casters the last :meth:`render_shadow` kept (a list, or :class:`IndirectDraws` on the GPU)
            self.shadow_result = result

            def draw_level(level, vao_t, edges, instances):
                self._draw_parts(prog, vao_t, None, None, depth_only=True, instances=instances)

            self._draw_culled(cull, prog, vaos[:1], result, draw_level)

    @contextmanager
    def culling(self, view=None, projection=None, enabled: bool = True):
        """The face-culling state of this renderer's triangle draws, for code
        that draws the same mesh with its own vertex arrays (a no-op when
        :attr:`cull_back_faces` is False).

        With ``view`` and ``projection`` a mirroring camera (a reflection
        pass: the two matrices together turn handedness) swaps which winding
        faces the camera, as three.js does for mirrored objects.  ``enabled`` False leaves the state as
        it is (a caller that culls nothing)."""
        if not self.cull_back_faces or not enabled:
            yield
            return

        mirrored = view is not None and projection is not None and _mirrors(view, projection)
        self.ctx.front_face = "cw" if mirrored else "ccw"
        self.ctx.cull_face = "back"
        self.ctx.enable(moderngl.CULL_FACE)
        try:
            yield
        finally:
            self.ctx.disable(moderngl.CULL_FACE)

    # ------------------------------------------------------------ lifetime
    def release(self) -> None:
        """Free every GL object; safe to call twice.  Never called from ``__del__``."""
        if self._released:
            return
        self._released = True
        self._release_capture() if hasattr(self, "_capture") else None
        for obj in reversed(self._objects):
            obj.release()
        self._objects.clear()
        for mb in getattr(self, "_level_buffers", [])[1:]:
            mb.release()
        for ab in getattr(self, "_level_appearance", [])[1:]:
            ab.release()
        for holder in ("mesh_buffers", "instances", "appearance", "materials", "_axes"):
            if getattr(self, holder, None) is not None:
                getattr(self, holder).release()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def _mirrors(view, projection) -> bool:
    """True when ``projection * view`` flips handedness.  A camera that does
    not (``pyrr`` look-at + perspective or orthographic) has a negative
    determinant, because GL's projections turn the right-handed eye space
    into left-handed clip space."""
    det = np.linalg.det(np.asarray(view, dtype=np.float64).reshape(4, 4)) * \
        np.linalg.det(np.asarray(projection, dtype=np.float64).reshape(4, 4))
    return bool(det > 0.0)


def unit_vector(v, name: str = "direction") -> np.ndarray:
    v = as_array(v, (3,), name)
    return v / max(np.linalg.norm(v), 1e-12)

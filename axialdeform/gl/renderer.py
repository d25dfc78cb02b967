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

import contextlib
from contextlib import contextmanager

import numpy as np

from .buffers import InstanceBuffer, MeshBuffers, as_index
from .cull import CullPass, IndirectDraws, read_counts
from .context import (bind_framebuffer, check_alive, draw_in_batches, flush_budget, release_framebuffer,
                      require_framebuffer)
from ..core.bounds import base_radius, wind_reach
from ..core.errors import ArgumentError, AxialDeformError, ParamError, ShaderError
from ..core.look import DEFAULT_LOOK, Look
from ..core.arrays import as_array
from ..core.safeio import require_finite
from ..core.wind import Wind
from .uniforms import camera_matrices, eye_position, set_camera_uniforms, set_uniforms
from .material import AppearanceBuffer, GpuMaterials
from .shaders import build_program

__all__ = ["AxialRenderer", "BakedMeshes", "MODES", "DEFAULT_COLORS", "BLEND_DEPTH_CUTOFF"]

MODES = ("solid", "flat", "wireframe")
_MODE_INDEX = {"solid": 0, "flat": 1, "wireframe": 2}
#: default base colours (linear RGB) by bundled mesh name
DEFAULT_COLORS = {"stone": (0.46, 0.44, 0.41), "leaf": (0.30, 0.52, 0.12)}
_CAPTURE_BYTES = 128 * 1024 * 1024  # transform feedback output per pass
_KEEP = object()  # capture(wind=...) not given: keep the renderer's wind
#: render(look=None): the default light and lines, every edge drawn (no depth pre-pass)
_PLAIN_LOOK = DEFAULT_LOOK.replace(hidden_line=False)
#: alpha below which a ``BLEND`` part leaves no depth in depth-only passes (shadows)
BLEND_DEPTH_CUTOFF = 0.5
_GL_SAMPLE_ALPHA_TO_COVERAGE = 0x809E


class AxialRenderer:
    """Draws ``count`` deformed instances of one base mesh.

    Parameters
    ----------
    ctx : moderngl.Context
        The caller's context (GL 3.3 core or newer).
    mesh : BaseMesh
        The base mesh.
    params : (n, 16) float32, optional
        The 16 numbers per instance, or (n, 19): extended instances (scale,
        twist, taper after the 16).
    capacity : int, optional
        Instances to reserve room for (``set_params`` up to it never reallocates).
    bend : bool
        False draws only rotation + position (the "all the same" method).
    quantized : bool
        Store each instance as 16 uint16 (32 bytes of GPU memory instead of
        64), decoded in the vertex shader (``glsl/quantized.glsl``) with the
        per-column table of :func:`axialdeform.core.params.quantize_params`; what
        is drawn and captured is the deformation of the dequantized numbers.
    cull_back_faces : bool or None
        Skip the triangles that face away from the camera (GL back-face
        culling, three.js's ``side: FrontSide``).  ``None`` (the default)
        culls exactly when the base mesh bounds a volume with outward
        triangles (:attr:`BaseMesh.is_volume`): then no back face can be
        seen and the picture is the same, drawn in about a third less time on a
        software rasterizer.  Open meshes (a leaf) stay two-sided.  Culled
        draws set ``ctx.front_face`` (``"ccw"``; ``"cw"`` for a mirroring
        camera, such as a reflection pass) and ``ctx.cull_face = "back"``,
        and leave ``CULL_FACE`` disabled afterwards.  A double-sided
        material's part is never culled.
    parts : sequence of str, optional
        Names of the base mesh's parts to draw (all by default); see
        :attr:`BaseMesh.parts`.  Every part is one instanced draw call over
        the same instance buffer, and all share the mesh's ONE control axis.

    extended : bool or None
        Store 19 numbers per instance (``AXIAL_EXTENDED``: 76 bytes, 40
        quantized).  ``None`` (the default): exactly when ``params`` has 19
        columns.  An extended renderer takes 16-number parameters too (as
        ``s = 1, tw = 0, tp = 0``); a 16-number one refuses 19.
    wind : Wind or None
        The wind drawn (and captured) from now on; see :attr:`wind` and
        :attr:`time`.  It moves control points in the vertex shader from
        uniforms alone: animating it writes no buffer.
    culling : bool
        Per-instance frustum culling on the GPU (:mod:`axialdeform.gl.cull`):
        a transform-feedback pass keeps only the instances whose bounding
        sphere reaches the view, and the draw reads those.  On by default: it
        cannot change the picture (an instance is dropped only when every one
        of its vertices lies outside one frustum plane).
    lod : bool
        Draw each instance with one of up to four levels of detail of the
        base mesh (:func:`axialdeform.core.lod.build_lod_levels`), the
        coarsest whose geometric error projects to at most ``lod_error``
        pixels; one instanced draw per level and part (plain switches, no
        dithering).  Changes pixels, so off by default.  Every part is
        simplified on its own and keeps its material; UVs, vertex colours,
        normals and tangents are carried to the simplified vertices.
    lod_error : float
        Allowed screen-space error of a level in pixels (> 0; default 1).
    indirect : bool or None
        How the culling pass reaches the draw (:mod:`axialdeform.gl.cull`):
        ``None`` (the default) picks compute shaders + indirect draws on
        GL >= 4.3 (the CPU never waits for the visible count) and transform
        feedback + a query on GL 3.3 (or when the environment variable
        ``AXIALDEFORM_INDIRECT=0``); ``True`` demands the indirect path
        (:class:`ContextError` below GL 4.3); ``False`` forces the GL 3.3 one.
        Both draw the same picture.

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

    def __init__(self, ctx, mesh, params=None, *, capacity: int | None = None, bend: bool = True,
                 quantized: bool = False, cull_back_faces: bool | None = None, parts=None,
                 extended: bool | None = None, wind: Wind | None = None, culling: bool = True, lod: bool = False,
                 lod_error: float = 1.0, indirect: bool | None = None):
        check_alive(ctx, "a new AxialRenderer")
        from ..core.lod import LodLevel, build_lod_levels, check_lod_error

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
            from .cull import _choose_indirect

            _choose_indirect(ctx, True)  # a context below GL 4.3: the error now, not at the first draw
        self.cull_back_faces = bool(mesh.is_volume) if cull_back_faces is None else bool(cull_back_faces)
        self.quantized = bool(quantized)
        self._released = False
        self._objects = []
        self._slice_commands = None  # the one indirect command of instance slices (software rasterisers)
        defines = {} if bend else {"AXIAL_NO_BEND": 1}
        if self.quantized:
            defines["AXIAL_QUANTIZED"] = 1
        if mesh.has_appearance:
            defines["AXIAL_MATERIAL"] = 1
        if extended is None:
            extended = params is not None and np.shape(params)[-1] == 19
        self.extended = bool(extended)
        if self.extended:
            defines["AXIAL_EXTENDED"] = 1
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
                self._part_edges = (ctx.buffer(e.tobytes()), int(e.size))
                self._objects.append(self._part_edges[0])
            self.instances = InstanceBuffer(ctx, params, capacity, quantized=self.quantized, extended=self.extended)
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
        self._tint = None  # (program, triangles vao, edges vao, buffer) built by the first set_tint
        self._tint_count = None  # colours in the tint buffer; None: tint off
        self._cull_passes = {}  # tinted -> CullPass
        self._culled = {}  # (tinted, shadowed) -> (CullPass, draw program, [(triangles vao, edges vao) per level])
        #: bounding-sphere radius about ``mesh.axis.center`` covering every LOD level
        self.bound_radius = base_radius(mesh, *[level.positions for level in self.lod_levels[1:]])
        self._set_axis_uniforms(self.program)
        self.color = DEFAULT_COLORS.get(str(mesh.name), (0.46, 0.44, 0.41))
        #: world up (unit vector), for the sky/ground hemisphere ambient
        self.up = (0.0, 1.0, 0.0)

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

    def _edges_vao(self, tinted: bool, shadowed: bool = False):
        """The vertex array of the edges (plain, tinted and/or shadow-receiving), built on first use."""
        if shadowed:
            entry = self._variants[(tinted, True)]
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

    def _set_axis_uniforms(self, program) -> None:
        axis = self.mesh.axis
        i, j = axis.perpendicular
        center = (axis.center[i], axis.center[j])
        set_uniforms(program, {"u_axis": axis.index, "u_lo": axis.lo, "u_len": axis.length, "u_center": center,
                               "u_instance_base": 0, "u_wind_strength": 0.0})
        self._set_quant_uniforms(program)

    def _set_wind_uniforms(self, program, wind, time) -> None:
        """The wind's uniforms (strength 0: still); no buffer is written."""
        if "u_wind_strength" not in program:  # the linker removed it: no bend (AXIAL_NO_BEND)
            return
        if wind is not None and not isinstance(wind, Wind):
            raise ParamError(f"wind: expected an axialdeform.Wind or None, found {type(wind).__name__}")
        if wind is None or wind.strength == 0:
            program["u_wind_strength"].value = 0.0
            return
        set_uniforms(program, {"u_wind_strength": float(wind.strength), "u_wind_dir": tuple(wind.unit_direction),
                               "u_wind_gust": float(wind.gustiness), "u_wind_cycles": tuple(wind.cycles(time)),
                               "u_wind_wavenumber": float(wind.wavenumber)})

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
        import moderngl

        programs = [o for o in self._objects if isinstance(o, moderngl.Program)]
        if self._capture is not None:
            programs.append(self._capture[0])
        for prog in programs:
            self._set_quant_uniforms(prog)

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

    def set_params(self, params) -> None:
        """Replace all parameters; the buffer is reallocated only if the count grows past its capacity."""
        self._check()
        self.instances.set(params)
        self._refresh_quant_uniforms()

    def update_params(self, params, start: int = 0) -> None:
        """Overwrite the instances ``start .. start + len(params) - 1`` in place.

        ``start`` must be an integer (int or numpy integer): a float, a
        string, None or NaN raises :class:`ArgumentError`."""
        self._check()
        self.instances.update(params, start, setter="set_params()", name="update_params")

    # ------------------------------------------------------------ optional tint
    def set_tint(self, colors) -> None:
        """Give every instance its own base colour; ``None`` goes back to ``color``.

        colors : (count, 3) linear RGB in 0..1, one row per instance in the
            order of the parameters, or None.

        The colours live in a second instanced buffer (12 bytes an instance)
        read by a variant of the program compiled with ``AXIAL_TINT``; the
        draw stays ONE instanced call.  A renderer that never calls this keeps
        the plain program and pays nothing.  Calling it again with the same
        count overwrites the buffer in place.
        """
        self._check()
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

    # ------------------------------------------------------------ drawing
    def _variant(self, tinted: bool, shadowed: bool):
        """(program, triangles vao, a function that returns the edges vao) of the
        plain, tinted and/or shadow-receiving program (edges: built on first use)."""
        def edges():
            return self._edges_vao(tinted, shadowed)

        if not shadowed:
            if tinted:
                return self._tint[0], self._tint[1], edges
            return self.program, self._vao_triangles, edges
        key = (tinted, shadowed)
        if key not in self._variants:
            defines = {**self._defines, "AXIAL_SHADOW": 1}
            extra = []
            if tinted:
                defines["AXIAL_TINT"] = 1
                extra = [(self._tint[3], "3f/i", "i_tint")]
            prog = build_program(self.ctx, "scene.vert", "scene.frag", defines=defines)
            self._objects.append(prog)
            self._set_axis_uniforms(prog)
            self._variants[key] = [prog, self._vertex_array(prog, self.mesh_buffers.triangles, extra=extra), None, extra]
        entry = self._variants[key]
        return entry[0], entry[1], edges

    def _draw_parts(self, prog, vao, view, projection, *, depth_only: bool = False, instances: int | None = None,
                    level: int = 0) -> None:
        """One instanced draw per part: opaque and cut-out parts, then blended ones.
        ``instances``: how many to draw (default :attr:`count`; the visible count after culling);
        ``level``: the LOD level whose parts ``vao`` draws (its parts have the base mesh's materials)."""
        import moderngl

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

        The base colour is :attr:`color`, world up (for the hemisphere
        ambient) :attr:`up` and the wind :attr:`wind`: set them on the
        renderer.  Animating the wind sets uniforms only: no buffer is written.
        """
        look = _PLAIN_LOOK if look is None else look
        if not isinstance(look, Look):
            raise ArgumentError(f"look: expected an axialdeform.Look, found {type(look).__name__}")
        light_dir, ambient, hidden_line = look.light_dir, look.ambient, look.wire_style
        import moderngl

        self._check()
        if mode not in _MODE_INDEX:
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
        n = self.count
        state = None
        if (self.culling_enabled or self.lod) and n:
            try:
                state = self._culled_state(tinted, shadowed)
            except ShaderError as exc:  # a driver that cannot build the pass: plain drawing, same picture
                import warnings

                warnings.warn(f"culling/LOD pass unavailable, drawing every instance: {exc}", RuntimeWarning, stacklevel=2)
                self.culling_enabled = self.lod = False
        if state is not None:
            cull, prog, vaos = state
        else:
            prog, vao_triangles, edges = self._variant(tinted, shadowed)
        set_camera_uniforms(prog, view, projection)
        self._set_wind_uniforms(prog, self.wind, self.time)
        set_uniforms(prog, {
            "u_mode": _MODE_INDEX[mode],
            "u_color": tuple(self.color),
            "u_line_color": tuple(look.line_color),
            "u_light_dir": tuple(_unit(light_dir, "light_dir")),
            "u_up": tuple(_unit(self.up, "up")),
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

    def _run_cull(self, cull, view, projection, levels: int, *, frustum: bool):
        """Run ``cull`` for the camera ``view``, ``projection``: the counts per
        level (GL 3.3 path) or an :class:`IndirectDraws` (indirect path)."""
        height = float(self.ctx.viewport[3]) if self.ctx.viewport else 1.0
        ortho = abs(float(projection[3, 3]) - 1.0) < 1e-9  # pyrr layout: w = 1 for orthographic
        return cull.run(self.count, levels, view, projection, frustum=frustum,
                        center=self.mesh.axis.center, radius=self.bound_radius,
                        lod_errors=[level.error for level in self.lod_levels[:levels]], eye=eye_position(view),
                        px_scale=abs(float(projection[1, 1])) * height / 2.0, ortho=ortho,
                        lod_px=self.lod_error, wind_reach=wind_reach(self.mesh, self.wind if self.bend else None),
                        prepare=self._set_quant_uniforms)

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
        import moderngl

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
        import moderngl

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
        state = None
        if self.culling_enabled and self.count:
            try:
                state = self._culled_state(False, False)
            except ShaderError as exc:
                import warnings

                warnings.warn(f"culling pass unavailable, drawing every caster: {exc}", RuntimeWarning, stacklevel=2)
                self.culling_enabled = False
        prog, vao, _ = self._variant(False, False) if state is None else (state[1], None, None)
        with shadow.target(clear):
            if self.count == 0:
                return
            set_camera_uniforms(prog, shadow.view, shadow.projection)
            self._set_wind_uniforms(prog, self.wind, self.time)
            set_uniforms(prog, {"u_mode": 0})
            import moderngl

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

    def _culled_state(self, tinted: bool, shadowed: bool = False):
        """The cull pass (one per tint state) and the draw program/VAOs reading
        its output (one per tint/shadow variant), built on first use."""
        state = self._culled.get((tinted, shadowed))
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
            defines = {**self._defines, "AXIAL_CULLED": 1, **({"AXIAL_TINT": 1} if tinted else {}),
                       **({"AXIAL_SHADOW": 1} if shadowed else {})}
            prog = build_program(self.ctx, "scene.vert", "scene.frag", defines=defines)
            self._objects.append(prog)
            self._set_axis_uniforms(prog)
            vaos = []
            for level in range(len(self._level_buffers)):  # edges: built by the first wireframe draw (lazy edges)
                vaos.append([self._culled_vao(prog, level, self._level_buffers[level].triangles), None])
            state = self._culled[(tinted, shadowed)] = (cull, prog, vaos)
        return state

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
        import moderngl

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
            buffer = self.ctx.buffer(e.astype("u4").tobytes())
            self._objects.append(buffer)
            self._level_edges[level] = (buffer, int(e.size))
        return self._level_edges[level]

    @contextmanager
    def culling(self, view=None, projection=None, enabled: bool = True):
        """The face-culling state of this renderer's triangle draws, for code
        that draws the same mesh with its own vertex arrays (a no-op when
        :attr:`cull_back_faces` is False).

        With ``view`` and ``projection`` a mirroring camera (a reflection
        pass: the two matrices together turn handedness) swaps which winding
        faces the camera, as three.js does for mirrored objects."""
        if not self.cull_back_faces or not enabled:
            yield
            return
        import moderngl

        mirrored = view is not None and projection is not None and _mirrors(view, projection)
        self.ctx.front_face = "cw" if mirrored else "ccw"
        self.ctx.cull_face = "back"
        self.ctx.enable(moderngl.CULL_FACE)
        try:
            yield
        finally:
            self.ctx.disable(moderngl.CULL_FACE)

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
        import moderngl

        self._check()
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
        if self._capture is None or self._capture[2].capacity < chunk:
            self._release_capture()
            prog = build_program(self.ctx, "scene.vert", defines=dict(self._defines),
                                 varyings=("v_world", "v_normal"))
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
        self._set_wind_uniforms(prog, self.wind if wind is _KEEP else wind, self.time if time is None else float(time))
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
        for holder in ("mesh_buffers", "instances", "appearance", "materials"):
            if getattr(self, holder, None) is not None:
                getattr(self, holder).release()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()


class BakedMeshes:
    """Meshes that are already deformed (``axialdeform bake`` output, or any
    mesh files), each with its own vertex and index buffers and vertex
    array, drawn one draw call each with the shading, uniforms and face
    culling of an un-bent :class:`AxialRenderer` -- the thesis's "load every
    one" method, drawn exactly like the instanced methods.

    Parameters
    ----------
    ctx : moderngl.Context
    like : BaseMesh
        A mesh whose name picks the colour and whose :attr:`BaseMesh.is_volume`
        decides back-face culling (the base mesh the files were baked from).
    mode : str
        One of :data:`MODES`; only the index buffers this mode draws are made.
    """

    def __init__(self, ctx, like, mode: str = "solid", *, cull_back_faces: bool | None = None):
        if mode not in _MODE_INDEX:
            raise AxialDeformError(f"render mode: expected one of {', '.join(MODES)}, found {mode!r}")
        self.ctx = ctx
        self.mode = mode
        self._items = []  # (MeshBuffers, vao, index count)
        self._released = False
        self.renderer = AxialRenderer(ctx, like, np.zeros((0, 16), np.float32), bend=False,
                                      cull_back_faces=cull_back_faces)
        self.cull_back_faces = self.renderer.cull_back_faces

    def __len__(self) -> int:
        return len(self._items)

    def add(self, mesh) -> None:
        """Upload one deformed mesh (world positions and normals as they are)."""
        if self._released:
            raise AxialDeformError("these BakedMeshes were released; create new ones")
        wire = self.mode == "wireframe"
        buffers = MeshBuffers(self.ctx, mesh, indices=("edges",) if wire else ("triangles",))
        try:
            program = self.renderer.program
            vao = self.ctx.vertex_array(program, [buffers.content(program)],
                                        index_buffer=buffers.edges if wire else buffers.triangles,
                                        index_element_size=4)
        except BaseException:
            buffers.release()
            raise
        self._items.append((buffers, vao, buffers.edge_indices if wire else buffers.triangle_indices))

    def render(self, view, projection, **options) -> None:
        """Draw every mesh into the bound framebuffer (one draw call each)."""
        import moderngl

        self.renderer.render(view, projection, self.mode, **options)  # no instances: sets the uniforms only
        self.ctx.enable(moderngl.DEPTH_TEST)
        wire = self.mode == "wireframe"
        primitive = moderngl.LINES if wire else moderngl.TRIANGLES
        with (contextlib.nullcontext() if wire else self.renderer.culling(view, projection)):
            for _, vao, n in self._items:
                draw_in_batches(self.ctx, lambda count, first, vao=vao: vao.render(primitive, vertices=count, first=first),
                                n, 0, 2 if wire else 3, 1)

    def release(self) -> None:
        """Free every GL object; safe to call twice."""
        if self._released:
            return
        self._released = True
        for buffers, vao, _ in self._items:
            vao.release()
            buffers.release()
        self._items.clear()
        self.renderer.release()

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


def _unit(v, name: str = "direction") -> np.ndarray:
    v = as_array(v, (3,), name)
    return v / max(np.linalg.norm(v), 1e-12)

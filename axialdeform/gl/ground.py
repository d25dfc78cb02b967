"""An optional ground plane under the instances: its own small program
(``glsl/ground.vert`` + ``glsl/ground.frag``), drawn in its own call, never
part of the instanced draw.  It shares the instances' light model
(``glsl/lighting.glsl``), so both read as one scene::

    ground = ad.gl.GroundPlane(ctx)
    ground.fit(mesh, params)                  # centre, size and height from the instances
    target.use(background)
    ground.render(view, proj, look=look)
    renderer.render(view, proj, "solid")
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..core.arrays import as_array
from ..core.axis import AXIS_NAMES
from ..core.bounds import ground_square, instance_bounds, stack_spheres
from ..core.errors import ArgumentError, AxialDeformError
from ..core.look import DEFAULT_LOOK, Look
from .context import require_framebuffer
from .shaders import build_program
from .uniforms import camera_matrices, set_camera_uniforms, set_uniforms

__all__ = ["GroundPlane", "GROUND_COLOR"]

#: default ground colour (linear RGB): dry sand
GROUND_COLOR = (0.50, 0.45, 0.37)


class GroundPlane:
    """A square across the world up axis, lit like the instances, fading out
    at its edge.

    Parameters
    ----------
    ctx : moderngl.Context
    up : ``"x"``, ``"y"`` or ``"z"``
        World up axis; the plane is across it.
    color : (3,) linear RGB
    cell : float
        Grid spacing in world units (0: no grid).
    """

    def __init__(self, ctx, *, up: str = "y", color=GROUND_COLOR, cell: float = 0.0):
        if up not in AXIS_NAMES:
            raise ArgumentError(f"ground up axis: expected one of x, y, z, found {up!r}")
        self.ctx = ctx
        self.up = up
        self.color = tuple(as_array(color, (3,), "ground color").tolist())
        self.cell = float(cell)
        self.center = np.zeros(3)
        self.radius = 10.0
        self._released = False
        self.program = build_program(ctx, "ground.vert", "ground.frag")
        self._shadowed = None  # (program, vao) receiving a ShadowMap, built on first use
        try:
            self.vao = ctx.vertex_array(self.program, [])
        except BaseException:
            self.program.release()
            raise

    #: the drawn square reaches this many times the fitted radius: far enough that the view meets the
    #: horizon on the ground, where it fades into the background (no edge, no void under the horizon)
    EXTENT = 8.0

    @property
    def drawn_radius(self) -> float:
        """Half the side of the square actually drawn (world units): :attr:`EXTENT` times :attr:`radius`."""
        return self.EXTENT * self.radius

    @property
    def up_vector(self) -> np.ndarray:
        """(3,) unit world up."""
        return np.eye(3)[AXIS_NAMES.index(self.up)]

    def fit(self, mesh, params, *, margin: float = 1.6, sink: float = 0.35) -> GroundPlane:
        """Place the plane under the instances.

        The square is centred under the instances' bounding spheres and
        ``margin`` times as wide as they spread; it lies ``sink`` times the
        typical sphere radius above their lowest point (so instances rest in
        it rather than float over it).  Returns ``self``.
        """
        return self.fit_layers([(mesh, params)], margin=margin, sink=sink)

    def fit_layers(self, layers, *, margin: float = 1.6, sink: float = 0.35, height: float | None = None) -> GroundPlane:
        """:meth:`fit` under several ``[(mesh, params), ...]`` (a scene's layers); ``height``: the plane's
        height along up where the scene knows it (generated layers stand on 0), else fitted."""
        return self.fit_spheres(*stack_spheres(instance_bounds(mesh, params) for mesh, params in layers),
                                margin=margin, sink=sink, height=height)

    def fit_spheres(self, centers, radii, *, margin: float = 1.6, sink: float = 0.35,
                    height: float | None = None) -> GroundPlane:
        """:meth:`fit` under spheres (``centers`` (n, 3), ``radii`` (n,)): the instances' bounds, or generated
        tiles' (:func:`~axialdeform.core.generate.tile_spheres`) whose instances live on the GPU."""
        if not len(np.asarray(centers).reshape(-1, 3)):
            return self
        self.center, self.radius = ground_square(centers, radii, AXIS_NAMES.index(self.up), margin=margin, sink=sink,
                                                 height=height)
        return self

    def render(self, view, projection, *, look: Look | None = None, shadow=None) -> None:
        """Draw the plane into the bound framebuffer (depth test on).

        Parameters
        ----------
        view, projection : (4, 4) float32
            pyrr-layout matrices.
        look : Look, optional
            Its light, ambient and background (the clear colour, sRGB, that
            the plane fades into); default :data:`~axialdeform.core.look.DEFAULT_LOOK`.
        shadow : ShadowMap, optional
            A drawn :class:`~axialdeform.gl.shadow.ShadowMap` (the instances'
            shadows on the ground).
        """
        look = DEFAULT_LOOK if look is None else look
        background, light_dir, ambient = look.background, look.light_dir, look.ambient

        if self._released:
            raise AxialDeformError("this GroundPlane was released; create a new one")
        view, projection = camera_matrices(view, projection)
        require_framebuffer(self.ctx, "GroundPlane.render")
        a = AXIS_NAMES.index(self.up)
        axis_u, axis_v = (np.eye(3)[i] for i in range(3) if i != a)
        light = as_array(light_dir, (3,), "light_dir")
        background = as_array(background, (None,), "background")
        if len(background) not in (3, 4):
            raise ArgumentError(f"background: expected 3 or 4 numbers (RGB[A]), found {len(background)}")
        prog, vao = self.program, self.vao
        if shadow is not None:
            if self._shadowed is None:
                sp = build_program(self.ctx, "ground.vert", "ground.frag", defines={"AXIAL_SHADOW": 1})
                self._shadowed = (sp, self.ctx.vertex_array(sp, []))
            prog, vao = self._shadowed
            shadow.bind(prog)
        set_camera_uniforms(prog, view, projection)
        set_uniforms(prog, {
            "u_center": tuple(self.center), "u_axis_u": tuple(axis_u), "u_axis_v": tuple(axis_v),
            "u_radius": self.drawn_radius, "u_color": self.color, "u_background": tuple(background[:3]),
            "u_light_dir": tuple(light / max(np.linalg.norm(light), 1e-12)), "u_up": tuple(self.up_vector),
            "u_light_color": look.light_color, "u_sky_color": look.sky_color, "u_bounce_color": look.ground_color,
            "u_ambient": float(ambient), "u_cell": self.cell,
        })
        self.ctx.enable(moderngl.DEPTH_TEST)
        vao.render(moderngl.TRIANGLE_STRIP, vertices=4)

    def release(self) -> None:
        """Free the GL objects; safe to call twice."""
        if self._released:
            return
        self._released = True
        if self._shadowed is not None:
            self._shadowed[1].release()
            self._shadowed[0].release()
        self.vao.release()
        self.program.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

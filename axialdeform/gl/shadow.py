"""A shadow map from the key light (the sun of ``glsl/lighting.glsl``).

::

    shadow = ad.gl.ShadowMap(ctx).fit(mesh, params, light_dir)
    renderer.render_shadow(shadow)               # instances -> depth map, one draw per part
    target.use(background)
    ground.render(view, proj, shadow=shadow)     # instances shadow the ground ...
    renderer.render(view, proj, shadow=shadow)   # ... and each other

An orthographic camera looks along ``-light_dir`` at a box around every
instance's bounding sphere; ``glsl/shadow.glsl`` samples the depth texture
with hardware comparison and a 3x3 filter.  Holds its ``ctx``; ``release()``
is safe twice; nothing is released from ``__del__``.
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from ..core.bounds import instance_bounds, light_box
from ..core.errors import AxialDeformError
from ..core.look import LIGHT_DIR
from .context import bind_framebuffer, release_framebuffer
from .uniforms import set_uniforms

__all__ = ["ShadowMap", "SHADOW_UNIT", "SHADOW_SIZE"]

#: texture unit of the shadow map (the material textures use 1 and 2)
SHADOW_UNIT = 3
#: the side of a shadow map (texels), render's and the page's
SHADOW_SIZE = 2048


class ShadowMap:
    """A ``size`` x ``size`` depth texture and the light's view/projection.

    Attributes
    ----------
    view, projection : (4, 4) float32
        pyrr-layout matrices of the light camera (set by :meth:`fit`).
    """

    def __init__(self, ctx, size: int = SHADOW_SIZE):
        self.ctx = ctx
        limit = int(ctx.info.get("GL_MAX_TEXTURE_SIZE", 2048))
        self.size = int(max(16, min(int(size), limit)))
        self.view = np.eye(4, dtype=np.float32)
        self.projection = np.eye(4, dtype=np.float32)
        self.offset = 0.0
        self._released = False
        self.texture = ctx.depth_texture((self.size, self.size))
        try:
            self.texture.compare_func = "<="
            self.texture.repeat_x = False
            self.texture.repeat_y = False
            self.fbo = ctx.framebuffer(depth_attachment=self.texture)
        except BaseException:
            self.texture.release()
            raise

    def fit(self, mesh, params, light_dir=LIGHT_DIR, *, extra=None) -> ShadowMap:
        """Aim the light camera at every instance (their bounding spheres);
        ``extra``: (k, 4) more spheres ``x, y, z, r`` to keep inside (a ground).  Returns self."""
        return self.fit_layers([(mesh, params)], light_dir, extra=extra)

    def fit_layers(self, layers, light_dir=LIGHT_DIR, *, extra=None) -> ShadowMap:
        """:meth:`fit` over several ``[(mesh, params), ...]`` (a scene's layers)."""

        spheres = [np.zeros((0, 4))]
        for mesh, params in layers:
            centers, radii = instance_bounds(mesh, params)
            if len(centers):
                spheres.append(np.hstack([centers, radii[:, None]]))
        spheres = np.vstack(spheres)
        if extra is not None:
            spheres = np.vstack([spheres, np.asarray(extra, dtype=np.float64).reshape(-1, 4)])
        if len(spheres) == 0:
            return self
        self.view, self.projection, self.offset = light_box(spheres, light_dir, self.size)
        return self

    @property
    def matrix(self) -> np.ndarray:
        """(4, 4) float32 world -> light clip, pyrr layout (``view @ projection``)."""
        return (np.asarray(self.view, np.float64) @ np.asarray(self.projection, np.float64)).astype(np.float32)

    @contextmanager
    def target(self, clear: bool = True):
        """Bind the depth framebuffer (cleared unless ``clear`` is False: a
        further caster of the same map) for the depth pass; the caller's
        framebuffer and viewport come back afterwards."""
        if self._released:
            raise AxialDeformError("this ShadowMap was released; create a new one")
        previous, viewport = self.ctx.fbo, self.ctx.viewport
        self.fbo.use()
        self.ctx.viewport = (0, 0, self.size, self.size)
        if clear:
            self.fbo.clear(depth=1.0)
        try:
            yield
        finally:
            bind_framebuffer(self.ctx, previous)
            self.ctx.viewport = viewport

    def bind(self, program) -> None:
        """The uniforms of ``glsl/shadow.glsl`` and the texture on :data:`SHADOW_UNIT`."""
        if self._released:
            raise AxialDeformError("this ShadowMap was released; create a new one")
        self.texture.use(SHADOW_UNIT)
        set_uniforms(program, {"u_shadow_map": SHADOW_UNIT, "u_shadow_offset": float(self.offset),
                               "u_shadow_texel": 1.0 / self.size, "u_light_matrix": self.matrix})

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        release_framebuffer(self.ctx, self.fbo)
        self.texture.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

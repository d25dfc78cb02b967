"""One frame's composition, written once: the key light's shadow pass over
every caster, then the ground plane, then every renderer -- in that order,
with one :class:`~axialdeform.core.look.Look`.  :func:`render_image` and the
viewer draw every picture through it."""

from __future__ import annotations

import numpy as np

from ..core.look import Look

__all__ = ["Frame"]


class Frame:
    """The pieces of a picture: renderers, an optional ground plane and an
    optional shadow map.  It owns none of them (the caller releases them).

    Parameters
    ----------
    renderers : sequence of AxialRenderer
        Drawn in order (a scene's terrain first, then its layers).
    ground : GroundPlane, optional
    shadow : ShadowMap, optional
        The key light's map; the ground's centre part receives shadows.
    """

    def __init__(self, renderers, *, ground=None, shadow=None):
        self.renderers = list(renderers)
        self.ground = ground
        self.shadow = shadow

    def shadow_pass(self, casters, look: Look, spheres=None) -> None:
        """Aim the shadow map at ``casters`` (``[(mesh, params), ...]``: their
        bounding spheres, with the ground's centre, and ``spheres``: (k, 4)
        ``x, y, z, r`` more, e.g. generated tiles whose instances live on the GPU)
        and draw every renderer into it (one map, cleared once).  Without a shadow map, nothing."""
        if self.shadow is None:
            return
        extra = [np.zeros((0, 4))] if spheres is None else [np.asarray(spheres, dtype=np.float64).reshape(-1, 4)]
        if self.ground is not None:  # the ground's centre part receives the shadows
            extra.append(np.array([[*self.ground.center, 0.5 * self.ground.radius]]))
        extra = np.vstack(extra)
        self.shadow.fit_layers(casters, look.light_dir, extra=extra)
        for k, renderer in enumerate(self.renderers):
            renderer.render_shadow(self.shadow, clear=k == 0)

    def draw(self, view, projection, mode: str, look: Look) -> None:
        """The ground, then every renderer, into the bound framebuffer."""
        if self.ground is not None:
            self.ground.render(view, projection, look=look, shadow=self.shadow)
        for renderer in self.renderers:
            renderer.render(view, projection, mode, look=look, shadow=self.shadow)

"""Step 6 of the data flow: pictures.  Render every instance offscreen with a
camera that frames them all, and save PNGs atomically (Pillow)."""

from __future__ import annotations

import os

import numpy as np

from ..core.atomic import atomic_path
from .camera import UP_VECTORS, Camera, frame_instances
from .context import Offscreen, check_image_size, create_context
from ..core.errors import ArgumentError
from .ground import GroundPlane
from .renderer import MODES, AxialRenderer
from .shadow import ShadowMap

__all__ = ["render_image", "save_png", "parse_size"]


def parse_size(text: str) -> tuple[int, int]:
    """``"800x600"`` -> ``(800, 600)``.  Only the form is checked here; what
    the OpenGL context can make is checked where the image is made
    (:func:`~axialdeform.gl.context.check_image_size`), and the error says
    the context's limit."""
    try:
        w, h = (int(x) for x in str(text).lower().split("x"))
    except ValueError:
        raise ArgumentError(f"size: expected WIDTHxHEIGHT such as 800x600, found {text!r}") from None
    if not (w > 0 and h > 0):
        raise ArgumentError(f"size: expected positive WIDTHxHEIGHT, found {text!r}")
    return w, h


def render_image(mesh, params, size=(800, 600), modes="solid", *, ctx=None, camera: Camera | None = None,
                 up: str = "y", samples: int = 4, background=(0.93, 0.94, 0.96), renderer=None,
                 fast: bool = False, ground: bool | None = None, shadow: bool | None = None, parts=None,
                 hidden_line=None,
                 **render_options) -> np.ndarray:
    """Render all instances to an ``(height, width, 3) uint8`` image.

    ``modes`` is one mode or a sequence of modes drawn side by side with the
    same parameters and camera (e.g. ``("solid", "wireframe")``).
    A context is created (EGL) if ``ctx`` is None and released afterwards.
    ``render_options`` go to :meth:`AxialRenderer.render` (``color``,
    ``line_color``, ``light_dir``, ``ambient``).

    By default the picture has the extras: ``samples``-fold multisampling
    (where ``ctx.max_samples`` allows), a ground plane under the instances, a
    shadow map from the key light (instances shadow the ground and each
    other) and hidden-line wireframes (lines of the front-most surface only).
    ``fast=True`` turns all of them off (no multisampling, no ground, no
    shadow, every edge drawn): what the benchmark times.  ``ground`` overrides
    the ground alone, ``shadow`` the shadow map alone, ``hidden_line`` the wireframe style (default ``"fill"``:
    front-most edges over washed-out faces; ``True``: front-most edges only;
    ``False``: every edge; see :meth:`AxialRenderer.render`); ``parts``
    picks the base mesh's parts to draw.
    """
    modes = (modes,) if isinstance(modes, str) else tuple(modes)
    for m in modes:
        if m not in MODES:
            raise ArgumentError(f"mode: expected one of {', '.join(MODES)}, found {m!r}")
    own_ctx = ctx is None
    ctx = create_context() if own_ctx else ctx
    try:
        w, h = parse_size(f"{size[0]}x{size[1]}")
        check_image_size(ctx, (w, h), samples, panels=len(modes))  # before any work: the error says the limit
        cam = camera or frame_instances(mesh, params, w / h, up=up)
        view, proj = cam.view(), cam.projection(w / h)
        r = renderer or AxialRenderer(ctx, mesh, params, parts=parts)
        ground = (not fast) if ground is None else bool(ground)
        shadowed = (not fast) if shadow is None else bool(shadow)
        plane = shadow = None
        light = render_options.get("light_dir", (0.35, 0.85, 0.4))
        try:
            if ground:
                plane = GroundPlane(ctx, up=up).fit(mesh, params)
            if "time" in render_options:  # the shadows bend in the same wind as the picture
                r.time = float(render_options["time"])
            if "wind" in render_options:
                r.wind = render_options["wind"]
            if shadowed and r.count:
                extra = None
                if plane is not None:  # the ground's centre part receives the shadows
                    extra = [[*plane.center, 0.5 * plane.radius]]
                shadow = ShadowMap(ctx).fit(mesh, params, light, extra=extra)
                r.render_shadow(shadow)
            with Offscreen(ctx, (w, h), samples=0 if fast else samples) as target:
                panels = []
                for m in modes:
                    target.use(background)
                    if plane is not None:
                        plane.render(view, proj, background=background, light_dir=light,
                                     ambient=render_options.get("ambient", 0.35), shadow=shadow)
                    r.render(view, proj, m, up=UP_VECTORS[up], shadow=shadow,
                             hidden_line=("fill" if not fast else False) if hidden_line is None else hidden_line,
                             **render_options)
                    panels.append(target.read())
        finally:
            for obj in (plane, shadow):
                if obj is not None:
                    obj.release()
            if renderer is None:
                r.release()
        return np.concatenate(panels, axis=1)
    finally:
        if own_ctx:
            ctx.release()


def save_png(path: str | os.PathLike, image: np.ndarray) -> None:
    """Write an ``(h, w, 3|4) uint8`` array as PNG, atomically."""
    from PIL import Image

    with atomic_path(path, suffix=".png") as tmp:
        Image.fromarray(np.ascontiguousarray(image)).save(tmp, format="PNG")

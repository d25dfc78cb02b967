"""Step 6 of the data flow: pictures.  Render every instance offscreen with a
camera that frames them all, and save PNGs atomically (Pillow)."""

from __future__ import annotations

import os

import numpy as np

from ..core.atomic import atomic_path
from .camera import UP_VECTORS, Camera, frame_instances
from .context import Offscreen, check_image_size, create_context
from ..core.errors import ArgumentError
from ..core.look import DEFAULT_LOOK, Look
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


#: render_image's keywords of the old signature, now fields of :class:`Look`
_LOOK_KEYWORDS = ("fast", "ground", "shadow", "samples", "background", "hidden_line", "light_dir", "ambient",
                  "line_color")


def look_from_keywords(look: Look | None, keywords: dict, where: str = "render_image") -> Look:
    """``look`` (default :data:`DEFAULT_LOOK`) with the old keywords folded in
    (``fast=True``, ``ground=False``, ...), each with a DeprecationWarning
    naming the field of :class:`Look` that replaces it."""
    look = DEFAULT_LOOK if look is None else look
    if not isinstance(look, Look):
        raise ArgumentError(f"{where}: look: expected an axialdeform.Look, found {type(look).__name__}")
    unknown = sorted(set(keywords) - set(_LOOK_KEYWORDS))
    if unknown:
        raise TypeError(f"{where}() got an unexpected keyword argument {unknown[0]!r}")
    changes = {k: v for k, v in keywords.items() if v is not None}
    if changes:
        import warnings

        warnings.warn(f"{where}({', '.join(f'{k}=' for k in changes)}): pass look=axialdeform.Look"
                      f"({', '.join(f'{k}=...' for k in changes)}) instead", DeprecationWarning, stacklevel=3)
        look = look.replace(**changes)
    return look


def render_image(mesh, params, size=(800, 600), modes="solid", *, look: Look | None = None,
                 camera: Camera | None = None, up: str = "y", ctx=None, renderer=None, parts=None,
                 time: float | None = None, wind=None, **old_keywords) -> np.ndarray:
    """Render all instances to an ``(height, width, 3) uint8`` image.

    Parameters
    ----------
    mesh : BaseMesh
    params : (n, 16) or (n, 19) float32
    size : (int, int)
        Width and height of one panel.
    modes : str or sequence of str
        One mode or several drawn side by side with the same parameters and
        camera (e.g. ``("solid", "wireframe")``).
    look : Look, optional
        How the picture looks (:class:`axialdeform.Look`): by default the
        extras -- multisampling (where ``ctx.max_samples`` allows), a ground
        plane, a shadow map from the key light, hidden-line wireframes;
        ``Look(fast=True)`` turns them all off (what the benchmark times).
    camera : Camera, optional
        Default: :func:`~axialdeform.gl.camera.frame_instances` for ``size``.
    up : {"x", "y", "z"}
        World up.
    ctx : moderngl.Context, optional
        Created (EGL) and released afterwards if None.
    renderer : AxialRenderer, optional
        Draw with this renderer (its parameters) instead of a new one.
    parts : sequence of str, optional
        The base mesh's parts to draw.
    time, wind : optional
        The wind's clock (seconds) and a :class:`axialdeform.Wind`.

    Returns
    -------
    image : (h, w * len(modes), 3) uint8
        First row at the top.

    The old keywords ``fast``, ``ground``, ``shadow``, ``samples``,
    ``background``, ``hidden_line``, ``light_dir`` and ``ambient`` still work
    for one release, with a DeprecationWarning: they are fields of ``look``.
    """
    look = look_from_keywords(look, old_keywords)
    modes = (modes,) if isinstance(modes, str) else tuple(modes)
    for m in modes:
        if m not in MODES:
            raise ArgumentError(f"mode: expected one of {', '.join(MODES)}, found {m!r}")
    own_ctx = ctx is None
    ctx = create_context() if own_ctx else ctx
    try:
        w, h = parse_size(f"{size[0]}x{size[1]}")
        check_image_size(ctx, (w, h), look.samples, panels=len(modes))  # before any work: the error says the limit
        r = renderer or AxialRenderer(ctx, mesh, params, parts=parts)
        plane = shadow = None
        try:
            if look.draws_ground:
                plane = GroundPlane(ctx, up=up).fit(mesh, params)
            cam = camera or frame_instances(mesh, params, w / h, up=up)
            if plane is not None:  # near and far enclose everything drawn: the ground reaches the edges
                cam = cam.enclosing_square(plane.center, UP_VECTORS[up], plane.radius, w / h)
            view, proj = cam.view(), cam.projection(w / h)
            if time is not None:  # the shadows bend in the same wind as the picture
                r.time = float(time)
            if wind is not None:
                r.wind = wind
            r.up = UP_VECTORS[up]
            if look.draws_shadow and r.count:
                extra = None
                if plane is not None:  # the ground's centre part receives the shadows
                    extra = [[*plane.center, 0.5 * plane.radius]]
                shadow = ShadowMap(ctx).fit(mesh, params, look.light_dir, extra=extra)
                r.render_shadow(shadow)
            with Offscreen(ctx, (w, h), samples=look.msaa) as target:
                panels = []
                for m in modes:
                    target.use(look.background)
                    if plane is not None:
                        plane.render(view, proj, look=look, shadow=shadow)
                    r.render(view, proj, m, look=look, shadow=shadow)
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

"""Step 6 of the data flow: pictures.  Render every instance offscreen with a
camera that frames them all, and save PNGs atomically (Pillow)."""

from __future__ import annotations

import warnings

import numpy as np

from ..core.bounds import stack_spheres
from ..core.camera import UP_VECTORS, Camera
from ..core.errors import ArgumentError
from ..core.look import DEFAULT_LOOK, Look
from ..core.options import RenderOptions
from ..core.scene import Scene
from .context import Offscreen, check_image_size, create_context
from .frame import Frame
from .ground import GroundPlane
from .renderer import MODES
from .scene import TERRAIN_INSTANCE, SceneRenderer, ground_spheres, scene_camera
from .shadow import ShadowMap

__all__ = ["render_image", "parse_size", "look_from_keywords", "pop_look_keywords"]


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


def pop_look_keywords(fields: dict) -> dict:
    """Take the old :class:`Look` keywords (``fast``, ``ground``, ...) out of ``fields``, for
    :func:`look_from_keywords`; the rest stay."""
    return {k: fields.pop(k) for k in list(fields) if k in _LOOK_KEYWORDS}


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

        warnings.warn(f"{where}({', '.join(f'{k}=' for k in changes)}): pass look=axialdeform.Look"
                      f"({', '.join(f'{k}=...' for k in changes)}) instead", DeprecationWarning, stacklevel=3)
        look = look.replace(**changes)
    return look


def render_image(scene, params=None, size=(800, 600), modes="solid", *, look: Look | None = None,
                 camera: Camera | None = None, ctx=None, options: RenderOptions | None = None,
                 **fields) -> np.ndarray:
    """Render a scene to an ``(height, width, 3) uint8`` image.

    Parameters
    ----------
    scene : Scene or BaseMesh
        What to draw: a :class:`axialdeform.Scene` (layers, terrain, the
        file's camera and wind), or a mesh with its ``params``
        (:meth:`Scene.single`).
    params : (n, 16) or (n, 19) float32, optional
        The instances, when ``scene`` is a mesh.
    size : (int, int)
        Width and height of one panel.
    modes : str or sequence of str
        One mode or several drawn side by side with the same instances and
        camera (e.g. ``("solid", "wireframe")``).
    look : Look, optional
        How the picture looks (:class:`axialdeform.Look`; default: the
        scene file's light and background with every extra -- multisampling
        where ``ctx.max_samples`` allows, a ground plane (none under a
        terrain), a shadow map from the key light, hidden-line wireframes;
        ``Look(fast=True)`` turns them all off: what the benchmark times).
    camera : Camera, optional
        Default: :func:`~axialdeform.gl.scene.scene_camera`, the one framing
        rule (tight, bend-aware) at this aspect; near and far enclose the
        ground too.
    ctx : moderngl.Context, optional
        Created (EGL) and released afterwards if None.
    options : RenderOptions, optional
        What is drawn and how (:class:`axialdeform.RenderOptions`): a mesh's
        ``up`` and ``parts``, a ``wind`` that replaces the scene's and its
        ``time``, a ``renderer`` to draw a one-layer scene with, and every
        layer's ``culling``, ``lod``, ``lod_error`` and ``position_ids`` (a scene's generated
        layers have them whatever it says).
    **fields
        Deprecated (still working for one release, with a DeprecationWarning):
        fields of :class:`RenderOptions` that replace ``options``' (``up="z", time=1.5``).  The old keywords ``fast``, ``ground``,
        ``shadow``, ``samples``, ``background``, ``hidden_line``,
        ``light_dir``, ``ambient`` and ``line_color`` still work for one
        release, with a DeprecationWarning: they are fields of ``look``.

    Returns
    -------
    image : (h, w * len(modes), 3) uint8
        First row at the top.
    """

    old_keywords = pop_look_keywords(fields)
    opts = RenderOptions.of(options, fields, "render_image",
                            ("up", "parts", "wind", "time", "renderer", "culling", "lod", "lod_error", "position_ids"))
    wind, time, renderer = opts.wind, opts.time, opts.renderer
    scene = Scene.of(scene, params, up=opts.up, wind=wind, parts=opts.parts)  # the one mesh-or-scene check
    if wind is not None:
        scene.wind = wind
    look = look_from_keywords(scene.look if look is None else look, old_keywords)
    modes = (modes,) if isinstance(modes, str) else tuple(modes)
    for m in modes:
        if m not in MODES:
            raise ArgumentError(f"mode: expected one of {', '.join(MODES)}, found {m!r}")
    own_ctx = ctx is None
    ctx = create_context() if own_ctx else ctx
    try:
        w, h = parse_size(f"{size[0]}x{size[1]}")
        check_image_size(ctx, (w, h), look.samples, panels=len(modes))  # before any work: the error says the limit
        layers = [(layer.mesh, layer.params) for layer in scene.layers]
        with SceneRenderer(ctx, scene, renderer=renderer, culling=opts.culling, lod=opts.lod,
                           lod_error=opts.lod_error, position_ids=opts.position_ids) as drawn:
            plane = shadow = None
            try:
                if look.draws_ground and scene.terrain is None:
                    # the page's and the widget's rule too (gl/scene.py)
                    plane = GroundPlane(ctx, up=scene.up).fit_spheres(*stack_spheres(ground_spheres(scene)),
                                                                      height=scene.ground_height)
                cam = camera or scene_camera(scene, w / h)
                if plane is not None:  # near and far enclose everything drawn: the ground reaches the edges
                    cam = cam.enclosing_square(plane.center, UP_VECTORS[scene.up], plane.drawn_radius, w / h)
                view, proj = cam.view(), cam.projection(w / h)
                drawn.prepare(time)  # the shadows bend in the same wind as the picture
                if look.draws_shadow and scene.count:
                    shadow = ShadowMap(ctx)
                    if plane is None and scene.terrain is not None:  # the terrain casts and receives them
                        layers.append((scene.terrain, TERRAIN_INSTANCE))
                frame = Frame([r for r, _, _ in drawn.renderers], ground=plane, shadow=shadow)
                frame.shadow_pass(layers, look)
                with Offscreen(ctx, (w, h), samples=look.msaa) as target:
                    panels = []
                    for m in modes:
                        target.use(look.background)
                        frame.draw(view, proj, m, look)
                        panels.append(target.read())
            finally:
                for obj in (plane, shadow):
                    if obj is not None:
                        obj.release()
        return np.concatenate(panels, axis=1)
    finally:
        if own_ctx:
            ctx.release()

"""An offscreen OpenGL 3.3 core context (EGL) and an offscreen render target."""

from __future__ import annotations

import os

import moderngl
import numpy as np

from ..core.errors import ContextError
from ..core.io import safeio
from ..core.look import BACKGROUND

__all__ = ["create_context", "Offscreen", "GL_REQUIRE", "bind_framebuffer", "release_framebuffer", "read_pixels",
           "require_framebuffer", "size_limits", "check_image_size", "check_alive", "check_released",
           "flush_interval", "is_software", "texture_anisotropy", "flush_budget", "draw_in_batches", "SOFTWARE_FLUSH_PRIMITIVES"]

GL_REQUIRE = 330

_HELP = (
    "install an EGL driver: on Debian/Ubuntu 'apt-get install libegl1 libgl1-mesa-dri' "
    "(Mesa's llvmpipe runs without a GPU); on other systems the vendor's OpenGL/EGL driver"
)


def create_context(backend: str = "egl"):
    """A standalone (windowless) moderngl context, OpenGL 3.3 core or newer.

    Parameters
    ----------
    backend : str
        moderngl's backend: ``"egl"`` (offscreen, no display needed) by default.

    Returns
    -------
    moderngl.Context
        Raises :class:`ContextError` saying which system packages provide one.
    """
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - moderngl is a dependency
        raise ContextError(f"moderngl is not installed ({exc}); pip install moderngl") from None
    try:
        ctx = moderngl.create_standalone_context(backend=backend, require=GL_REQUIRE)
    except Exception as exc:
        version = f"{GL_REQUIRE // 100}.{GL_REQUIRE % 100 // 10}"
        raise ContextError(f"no OpenGL {version} context via {backend.upper()} ({exc}); {_HELP}") from None
    if ctx.version_code < GL_REQUIRE:
        version = ctx.version_code
        ctx.release()
        raise ContextError(f"the {backend.upper()} context is OpenGL {version}, expected {GL_REQUIRE} or newer; {_HELP}")
    return ctx


#: most primitives (instances x triangles, or x lines) a software rasteriser is
#: given before the draws are finished.  Mesa's llvmpipe keeps every primitive
#: drawn into a multisampled target until the frame is finished -- 30 to 130
#: bytes a triangle: one draw of 100 instances of a 0.5 M-triangle mesh into a
#: 64x64 4-sample target peaked at 2.4 GB, 213 MB when finished after each
#: 0.5 M triangles -- so big draws are split there (lines: a third as many;
#: the cost, a finish a slice: +18 % on a frame of 20 000 stones, sliced by instances;
#: ``tests/gl/test_render.py::test_multisampled_frame_memory_does_not_grow_with_triangles``).
SOFTWARE_FLUSH_PRIMITIVES = 250_000
_SOFTWARE = ("llvmpipe", "softpipe", "swrast", "swiftshader", "lavapipe")


def is_software(ctx) -> bool:
    """Whether ``ctx`` draws on a software rasteriser (``GL_RENDERER`` names
    llvmpipe, softpipe, swrast, SwiftShader or lavapipe)."""
    renderer = str(ctx.info.get("GL_RENDERER", "")).lower()
    return any(name in renderer for name in _SOFTWARE)


def texture_anisotropy(ctx) -> float:
    """The anisotropic filtering textures get: 8x (or the driver's most) on a
    GPU, none on a software rasteriser, where it costs a frame 30x (100
    textured models on llvmpipe); ``AXIALDEFORM_ANISOTROPY`` (a number)
    overrides it."""
    env = os.environ.get("AXIALDEFORM_ANISOTROPY", "").strip()
    most = float(getattr(ctx, "max_anisotropy", 1.0) or 1.0)
    try:
        wanted = float(env) if env else (1.0 if is_software(ctx) else 8.0)
    except ValueError:
        wanted = 1.0 if is_software(ctx) else 8.0
    return max(1.0, min(wanted, most))


def flush_interval(ctx) -> int | None:
    """Primitives to draw between finishes on ``ctx``: :data:`SOFTWARE_FLUSH_PRIMITIVES`
    on a software rasteriser (``GL_RENDERER`` names llvmpipe, softpipe, ...), None on
    a GPU (whose memory does not grow with what one frame draws).  The environment
    variable ``AXIALDEFORM_FLUSH_PRIMITIVES`` overrides it (0: never split)."""

    cached = getattr(ctx, "_axialdeform_flush", False)
    if cached is not False:
        return cached
    env = os.environ.get("AXIALDEFORM_FLUSH_PRIMITIVES")
    if env is not None and env.strip().isdigit():
        value = int(env) or None
    else:
        value = SOFTWARE_FLUSH_PRIMITIVES if is_software(ctx) else None
    try:
        ctx._axialdeform_flush = value
    except AttributeError:  # pragma: no cover - a context that takes no attributes: ask every time
        pass
    return value


def _multisampled(ctx) -> bool:
    """Whether the bound framebuffer is multisampled (a window's default
    framebuffer, whose attachments moderngl cannot see, counts as one)."""
    fbo = ctx.fbo
    attachments = list(getattr(fbo, "color_attachments", ()) or ())
    depth = getattr(fbo, "depth_attachment", None)
    if depth is not None:
        attachments.append(depth)
    if not attachments:
        return True
    return any(getattr(a, "samples", 0) > 1 for a in attachments)


def _depth_only(ctx) -> bool:
    """Whether the bound framebuffer has a depth attachment and no colour one (a shadow map)."""
    fbo = ctx.fbo
    return not list(getattr(fbo, "color_attachments", ()) or ()) and getattr(fbo, "depth_attachment", None) is not None


def flush_budget(ctx, per_primitive: int = 3) -> int | None:
    """Primitives to give ``ctx`` between finishes now: None (never slice) on a GPU
    or into a single-sampled colour target (one draw call: llvmpipe bins a
    bounded scene and flushes it by itself); else :func:`flush_interval` (lines:
    a third) -- into a multisampled target, and into a depth-only one (the
    shadow map's pass of a 4.5 M-triangle terrain held ~50 MB more unsliced,
    docs/reliability.md)."""
    budget = flush_interval(ctx)
    if budget is None or not (_multisampled(ctx) or _depth_only(ctx)):
        return None
    return max(1, budget // 3) if per_primitive == 2 else budget  # a line costs ~140 bytes, a triangle ~48


def draw_in_batches(ctx, draw, vertices: int, first: int, per_primitive: int, instances: int) -> None:
    """Call ``draw(vertices, first)`` once, or -- on a software rasteriser drawing
    into a multisampled target, when ``instances`` x ``vertices / per_primitive``
    exceeds :func:`flush_budget` --
    once per slice of the index range (whole primitives, every instance each time),
    finishing the GL queue after each slice, so that the driver's memory for one
    frame stays bounded.  The picture is the same for depth-tested opaque drawing
    (the slices reorder primitives only; a blended draw must not be split)."""
    budget = flush_budget(ctx, per_primitive)
    primitives = vertices // per_primitive
    if budget is None or primitives * max(int(instances), 1) <= budget or primitives <= 1:
        draw(vertices, first)
        return
    step = max(1, budget // max(int(instances), 1)) * per_primitive
    for start in range(0, vertices, step):
        draw(min(step, vertices - start), first + start)
        ctx.finish()


def check_alive(ctx, what: str = "this object") -> None:
    """Raise :class:`ContextError` if ``ctx`` was released (every GL wrapper
    calls this before touching GL, so a call after the context is gone is an
    error of the library's own family, not an AttributeError from moderngl)."""

    if ctx is None or isinstance(getattr(ctx, "mglo", None), moderngl.InvalidObject):
        raise ContextError(f"the OpenGL context of {what} was released; create a new context (and new objects in it)")


def check_released(released: bool, what: str) -> None:
    """Raise :class:`ContextError` for a call on a released wrapper."""
    if released:
        raise ContextError(f"{what} was released; create a new one")


def _alive(obj) -> bool:
    return obj is not None and not isinstance(obj.mglo, moderngl.InvalidObject)


def bind_framebuffer(ctx, fbo) -> None:
    """Bind ``fbo`` if it is still alive, else the default framebuffer (0).

    moderngl re-binds "the bound framebuffer" after creating a new one; if
    that one was deleted, GL reports GL_INVALID_OPERATION.  Always leaving a
    live framebuffer bound avoids it.
    """
    (fbo if _alive(fbo) else ctx.detect_framebuffer(0)).use()


def require_framebuffer(ctx, what: str = "draw") -> None:
    """Raise :class:`ContextError` unless a usable framebuffer is bound.

    A surfaceless (EGL, windowless) context has no default framebuffer: a
    draw there only leaves ``GL_INVALID_FRAMEBUFFER_OPERATION`` behind and
    draws nothing.  So does a framebuffer that was released while bound.
    """
    fbo = ctx.fbo
    if fbo is None or not _alive(fbo) or 0 in tuple(fbo.size):
        raise ContextError(
            f"{what}: no usable framebuffer is bound (a windowless context has none of its own); "
            "expected one bound first, e.g. Offscreen(ctx, (w, h)).use() or ctx.simple_framebuffer((w, h)).use()"
        )


def release_framebuffer(ctx, fbo) -> None:
    """Release ``fbo``, first un-binding it if it is the bound one."""
    if ctx.fbo is fbo:
        ctx.detect_framebuffer(0).use()
    fbo.release()


def size_limits(ctx) -> tuple[int, int, str]:
    """The largest ``(width, height)`` a render target of ``ctx`` may have, and
    where that comes from: the smallest of ``GL_MAX_RENDERBUFFER_SIZE``,
    ``GL_MAX_TEXTURE_SIZE`` and ``GL_MAX_VIEWPORT_DIMS``."""
    info = ctx.info
    rb = int(info.get("GL_MAX_RENDERBUFFER_SIZE", 16384))
    tex = int(info.get("GL_MAX_TEXTURE_SIZE", 16384))
    vw, vh = (int(x) for x in info.get("GL_MAX_VIEWPORT_DIMS", (16384, 16384)))
    text = f"GL_MAX_RENDERBUFFER_SIZE {rb}, GL_MAX_TEXTURE_SIZE {tex}, GL_MAX_VIEWPORT_DIMS {vw}x{vh}"
    return min(rb, tex, vw), min(rb, tex, vh), text


def check_image_size(ctx, size, samples: int = 4, panels: int = 1) -> None:
    """Raise :class:`ContextError` if an image of ``size = (width, height)``
    (``panels`` of them side by side) cannot be made by ``ctx``: a side past
    the GL limits (:func:`size_limits`) or more memory than is available
    (colour + depth at ``samples``, the resolved copy and the read-back)."""

    check_alive(ctx, "the image")
    w, h = (int(size[0]), int(size[1]))
    mw, mh, text = size_limits(ctx)
    if not (0 < w <= mw and 0 < h <= mh):
        raise ContextError(f"size: {w}x{h} pixels; expected 1..{mw} x 1..{mh}, the most this OpenGL context can render "
                           f"({text})")
    per_pixel = 8 * max(samples, 1) + 4 + 3 * (panels + 1)
    need, have = w * h * per_pixel, int(0.8 * safeio.memory_available())
    if need > have:
        side = int((have / per_pixel) ** 0.5)
        raise ContextError(f"size: {w}x{h} pixels need about {need / 1024**3:.3g} GB; expected at most about "
                           f"{side}x{side} (what {have / 1024**3:.3g} GB of available memory holds)")


def read_pixels(ctx, fbo, *, resolve: bool | None = None) -> np.ndarray:
    """The colour of ``fbo`` as ``(height, width, 3) uint8``, first row at the
    top (OpenGL's first row is the bottom one: this is the one place that
    flips it).

    resolve : bool or None
        Copy into a plain single-sample framebuffer first (needed for a
        multisampled one, e.g. a window's).  ``None``: when ``fbo`` has a
        multisampled colour attachment or none that moderngl knows of (a
        window's default framebuffer).  The bound framebuffer is left as it was.
    """
    w, h = (int(x) for x in fbo.size)
    if resolve is None:
        attachments = fbo.color_attachments
        resolve = not attachments or any(getattr(a, "samples", 0) for a in attachments)
    if resolve:
        previous = ctx.fbo
        color = ctx.renderbuffer((w, h), 4)
        plain = ctx.framebuffer(color)
        try:
            ctx.copy_framebuffer(plain, fbo)
            data = plain.read(components=3, alignment=1)
        finally:
            release_framebuffer(ctx, plain)
            color.release()
            bind_framebuffer(ctx, previous)
    else:
        data = fbo.read(components=3, alignment=1)
    return np.frombuffer(data, dtype=np.uint8).reshape(h, w, 3)[::-1].copy()


class Offscreen:
    """A multisampled colour + depth framebuffer, resolved into a plain one for reading back.

    Parameters
    ----------
    ctx : moderngl.Context
    size : (int, int)
        Width and height in pixels.
    samples : int
        Multisampling samples (0 or 1: none; at most ``ctx.max_samples``).

    Notes
    -----
    ``use()`` binds it and sets the viewport; ``read()`` returns ``(height, width, 3) uint8`` with
    the first row at the top.  A context manager: ``release()`` on exit (safe twice).
    """

    def __init__(self, ctx, size: tuple[int, int], samples: int = 4):
        width, height = (int(size[0]), int(size[1]))
        check_image_size(ctx, (width, height), samples)
        self.ctx = ctx
        self.size = (width, height)
        samples = min(samples, ctx.max_samples) if samples > 1 else 0
        self._released = True  # until everything exists: release() does nothing
        while True:
            # a driver may refuse a multisampled target that it can make with
            # fewer samples (llvmpipe: one resource of at most 2 GiB): fall back
            color = depth = None
            try:
                color = ctx.renderbuffer(self.size, 4, samples=samples)
                depth = ctx.depth_renderbuffer(self.size, samples=samples)
                fbo = ctx.framebuffer(color, depth)
                break
            except moderngl.Error as exc:
                for obj in (depth, color):
                    if obj is not None:
                        obj.release()
                bind_framebuffer(ctx, None)
                if samples == 0:
                    _w, _h, text = size_limits(ctx)
                    raise ContextError(f"size: this OpenGL context cannot make a {width}x{height} render target ({exc}); "
                                       f"expected a smaller size (its limits: {text})") from None
                samples //= 2
                samples = 0 if samples < 2 else samples
        self.samples = samples
        self._color, self._depth, self.fbo = color, depth, fbo
        if samples:
            self._resolved_color = ctx.renderbuffer(self.size, 4)
            self._resolved = ctx.framebuffer(self._resolved_color)
        else:
            self._resolved_color = None
            self._resolved = self.fbo
        self._released = False

    def _check(self) -> None:
        check_released(self._released, "this Offscreen target")
        check_alive(self.ctx, "this Offscreen target")

    def use(self, background=BACKGROUND) -> None:
        """Draw into this target from now on, cleared to ``background`` (linear RGB) and the far depth."""
        self._check()
        self.fbo.use()
        self.ctx.viewport = (0, 0) + self.size
        self.fbo.clear(*background, 1.0, depth=1.0)

    def read(self) -> np.ndarray:
        self._check()
        if self._resolved is not self.fbo:
            self.ctx.copy_framebuffer(self._resolved, self.fbo)
        return read_pixels(self.ctx, self._resolved, resolve=False)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        if self._resolved_color is not None:
            release_framebuffer(self.ctx, self._resolved)
            self._resolved_color.release()
        release_framebuffer(self.ctx, self.fbo)
        self._color.release()
        self._depth.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()

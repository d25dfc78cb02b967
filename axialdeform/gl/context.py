"""An offscreen OpenGL 3.3 core context (EGL) and an offscreen render target."""

from __future__ import annotations

import numpy as np

from ..core.errors import ArgumentError, ContextError

__all__ = ["create_context", "Offscreen", "GL_REQUIRE", "bind_framebuffer", "release_framebuffer", "read_pixels", "require_framebuffer"]

GL_REQUIRE = 330

_HELP = (
    "install an EGL driver: on Debian/Ubuntu 'apt-get install libegl1 libgl1-mesa-dri' "
    "(Mesa's llvmpipe runs without a GPU); on other systems the vendor's OpenGL/EGL driver"
)


def create_context(backend: str = "egl"):
    """A standalone (windowless) moderngl context, OpenGL 3.3 core or newer.

    Raises :class:`ContextError` saying which system packages provide one.
    """
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - moderngl is a dependency
        raise ContextError(f"moderngl is not installed ({exc}); pip install moderngl") from None
    try:
        ctx = moderngl.create_standalone_context(backend=backend, require=GL_REQUIRE)
    except Exception as exc:
        raise ContextError(f"no OpenGL {GL_REQUIRE // 100}.{GL_REQUIRE % 100 // 10} context via {backend.upper()} ({exc}); {_HELP}") from None
    if ctx.version_code < GL_REQUIRE:
        version = ctx.version_code
        ctx.release()
        raise ContextError(f"the {backend.upper()} context is OpenGL {version}, expected {GL_REQUIRE} or newer; {_HELP}")
    return ctx


def _alive(obj) -> bool:
    import moderngl

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
    """A multisampled colour + depth framebuffer of ``size = (width, height)``
    pixels, resolved into a plain one for reading back.

    ``use()`` binds it and sets the viewport; ``read()`` returns
    ``(height, width, 3) uint8`` with the first row at the top.
    """

    def __init__(self, ctx, size: tuple[int, int], samples: int = 4):
        width, height = (int(size[0]), int(size[1]))
        if width <= 0 or height <= 0 or width > 16384 or height > 16384:
            raise ArgumentError(f"image size: expected 1..16384 pixels each way, found {width}x{height}")
        self.ctx = ctx
        self.size = (width, height)
        samples = min(samples, ctx.max_samples) if samples > 1 else 0
        self._color = ctx.renderbuffer(self.size, 4, samples=samples)
        self._depth = ctx.depth_renderbuffer(self.size, samples=samples)
        self.fbo = ctx.framebuffer(self._color, self._depth)
        if samples:
            self._resolved_color = ctx.renderbuffer(self.size, 4)
            self._resolved = ctx.framebuffer(self._resolved_color)
        else:
            self._resolved_color = None
            self._resolved = self.fbo
        self._released = False

    def use(self, background=(0.93, 0.94, 0.96)) -> None:
        self.fbo.use()
        self.ctx.viewport = (0, 0) + self.size
        self.fbo.clear(*background, 1.0, depth=1.0)

    def read(self) -> np.ndarray:
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

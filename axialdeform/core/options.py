"""What is drawn and how the GPU draws it: ONE value object, :class:`RenderOptions`, whose
defaults are written here and nowhere else.

:class:`~axialdeform.gl.renderer.AxialRenderer`, :func:`axialdeform.render_image` and the viewer
take one (``options=``), or its fields as keywords (``culling=False``), so that their own
signatures stay short.  How the picture looks is the other value, :class:`~axialdeform.Look`.
Pure data: no GL here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

from .axis import AXIS_NAMES
from .errors import ArgumentError

__all__ = ["RenderOptions", "RENDERER_FIELDS"]


@dataclass(frozen=True)
class RenderOptions:
    """What is drawn of a scene and how the GPU draws it; the look and the camera are elsewhere.

    Attributes
    ----------
    up : {"x", "y", "z"}
        World up of a mesh drawn with its parameters (a :class:`~axialdeform.Scene` has its own).
    parts : sequence of str, optional
        The mesh's parts to draw (default: all).
    wind : Wind, optional
        A :class:`~axialdeform.Wind` that replaces the scene's.
    time : float, optional
        The wind's clock, seconds.
    renderer : AxialRenderer, optional
        Draw a one-layer scene with this renderer (its instances): :func:`render_image` only.
    culling : bool
        Per-instance frustum culling on the GPU (docs/culling.md).
    lod : bool
        Levels of detail by projected size.
    lod_error : float
        The largest screen error a coarser level may make, pixels (> 0).
    indirect : bool, optional
        Indirect draws (GL 4.3); None picks them where they measure faster.
    quantized : bool
        A quantized (uint16) instance buffer: half the bytes.
    cull_back_faces : bool, optional
        Back-face culling; None: on for closed meshes.
    bend : bool
        False draws every instance unbent (placed, turned and scaled only).
    extended : bool, optional
        Room for the 19-number extension; None: as the first instances given.
    """

    up: str = "y"
    parts: tuple | None = None
    wind: object = None
    time: float | None = None
    renderer: object = None
    culling: bool = True
    lod: bool = False
    lod_error: float = 1.0
    indirect: bool | None = None
    quantized: bool = False
    cull_back_faces: bool | None = None
    bend: bool = True
    extended: bool | None = None

    def __post_init__(self):
        if self.up not in AXIS_NAMES:
            raise ArgumentError(f"up: expected one of x, y, z, found {self.up!r}")
        if isinstance(self.parts, str):
            object.__setattr__(self, "parts", (self.parts,))
        elif self.parts is not None:
            object.__setattr__(self, "parts", tuple(self.parts))
        if self.time is not None and not (isinstance(self.time, (int, float)) and math.isfinite(self.time)):
            raise ArgumentError(f"time: expected a finite number of seconds, found {self.time!r}")

    def replace(self, **changes) -> RenderOptions:
        """A copy with some fields changed (checked again)."""
        return replace(self, **changes)

    @classmethod
    def of(cls, options=None, changes: dict | None = None, where: str = "options",
           allowed: tuple[str, ...] | None = None) -> RenderOptions:
        """``options`` (a RenderOptions, a dict of its fields, or None) with ``changes`` applied: the
        one way a function that takes ``options=`` and its fields as keywords reads them.  A keyword
        that is no field, or a field that ``where`` does not use (not in ``allowed``) set to other
        than its default, is an :class:`ArgumentError` naming it."""
        if options is None:
            base = cls()
        elif isinstance(options, dict):
            base, changes = cls(), {**options, **(changes or {})}
        elif isinstance(options, cls):
            base = options
        else:
            raise ArgumentError(f"{where}: options: expected an axialdeform.RenderOptions, "
                                f"found {type(options).__name__}")
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(changes or {}) - set(names))
        if unknown:
            raise TypeError(f"{where}() got an unexpected keyword argument {unknown[0]!r}")
        out = replace(base, **changes) if changes else base
        if allowed is not None:
            default = cls()
            for name in names:
                if name not in allowed and getattr(out, name) is not getattr(default, name) \
                        and getattr(out, name) != getattr(default, name):
                    raise ArgumentError(f"{where}: {name}: not used here; expected the default "
                                        f"({getattr(default, name)!r})")
        return out


#: the fields an :class:`~axialdeform.gl.renderer.AxialRenderer` reads (``up``, ``time`` and
#: ``renderer`` belong to a picture)
RENDERER_FIELDS = ("parts", "wind", "culling", "lod", "lod_error", "indirect", "quantized", "cull_back_faces",
                   "bend", "extended")

"""What is drawn and how the GPU draws it: ONE value object, :class:`RenderOptions`, whose
defaults are written here and nowhere else.

:class:`~axialdeform.gl.renderer.AxialRenderer`, :func:`axialdeform.render_image` and the viewer
take one (``options=``), so that their own signatures stay short; its fields as keywords
(``culling=False``) still work for one release, with a DeprecationWarning.  How the picture
looks is the other value, :class:`~axialdeform.Look`.  Pure data: no GL here.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, fields, replace

from .axis import AXIS_NAMES
from .errors import ArgumentError

__all__ = ["RenderOptions", "RENDERER_FIELDS", "warn_field_keywords"]


@dataclass(frozen=True)
class RenderOptions:
    """What is drawn of a scene and how the GPU draws it; the look and the camera are elsewhere.

    Attributes
    ----------
    up : {"x", "y", "z"}
        World up of a mesh drawn with its parameters (a :class:`~axialdeform.Scene` has its own).
    parts : sequence of str, optional
        Names of the base mesh's parts to draw (all by default); see
        :attr:`BaseMesh.parts`.  Every part is one instanced draw call over
        the same instance buffer, and all share the mesh's ONE control axis.
    wind : Wind or None
        The wind drawn (and captured) from now on; see :attr:`wind` and
        :attr:`time`.  It moves control points in the vertex shader from
        uniforms alone: animating it writes no buffer.
    time : float, optional
        The wind's clock, seconds.
    renderer : AxialRenderer, optional
        Draw a one-layer scene with this renderer (its instances): :func:`render_image` only.
    culling : bool
        Per-instance frustum culling on the GPU (:mod:`axialdeform.gl.cull`):
        a transform-feedback pass keeps only the instances whose bounding
        sphere reaches the view, and the draw reads those.  On by default: it
        cannot change the picture (an instance is dropped only when every one
        of its vertices lies outside one frustum plane).
    lod : bool or None
        Draw each instance with one of up to four levels of detail of the
        base mesh (:func:`axialdeform.core.lod.build_lod_levels`), the
        coarsest whose geometric error projects to at most ``lod_error``
        pixels; one instanced draw per level and part (plain switches, no
        dithering).  Changes pixels, so ``None`` (the default) is off, except in the
        viewer, where it is on from :data:`~axialdeform.viewer.LOD_AUTO_COUNT` instances.  Every part is
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
    quantized : bool
        Store each instance as 16 uint16 (32 bytes of GPU memory instead of
        64), decoded in the vertex shader (``glsl/quantized.glsl``) with the
        per-column table of :func:`axialdeform.core.quantize.quantize_params`; what
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
    bend : bool
        False draws only rotation + position (the "all the same" method).
    extended : bool or None
        Store 19 numbers per instance (``AXIAL_EXTENDED``: 76 bytes, 40
        quantized).  ``None`` (the default): exactly when ``params`` has 19
        columns.  An extended renderer takes 16-number parameters too (as
        ``s = 1, tw = 0, tp = 0``); a 16-number one refuses 19.
    position_ids : bool
        The instances' wind phases and shades hash where they stand
        (:func:`~axialdeform.core.wind.position_ids`), not their index: a generated layer's, whose
        index changes as tiles come and go (a scene's generated layers are drawn so by themselves).
    """

    up: str = "y"
    parts: tuple | None = None
    wind: object = None
    time: float | None = None
    renderer: object = None
    culling: bool = True
    lod: bool | None = None
    lod_error: float = 1.0
    indirect: bool | None = None
    quantized: bool = False
    cull_back_faces: bool | None = None
    bend: bool = True
    extended: bool | None = None
    position_ids: bool = False

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
        """A copy with the fields in ``changes`` changed (checked again)."""
        return replace(self, **changes)

    @classmethod
    def of(cls, options=None, changes: dict | None = None, where: str = "options",
           allowed: tuple[str, ...] | None = None, *, stacklevel: int = 2) -> RenderOptions:
        """``options`` (a RenderOptions, a dict of its fields, or None) with ``changes`` applied: the
        one way a function that takes ``options=`` and its fields as keywords reads them.  A keyword
        that is no field, or a field that ``where`` does not use (not in ``allowed``) set to other
        than its default, is an :class:`ArgumentError` naming it.  Fields given as keywords still work
        for one release, with a DeprecationWarning (``stacklevel``: the caller's frame)."""
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
        warn_field_keywords(where, changes, "options", "RenderOptions", stacklevel=stacklevel + 1)
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
                   "bend", "extended", "position_ids")


def warn_field_keywords(where: str, changes: dict | None, parameter: str, value: str, *, stacklevel: int = 2) -> None:
    """The DeprecationWarning of fields of a value object given to ``where`` as keywords (``bend=0.1``) instead of
    the object (``variation=axialdeform.Variation(bend=0.1)``); nothing when ``changes`` is empty.

    Parameters
    ----------
    where : str
        The public callable, as its users write it (``"random_params"``).
    changes : dict or None
        The keywords given.
    parameter, value : str
        The parameter that takes the value object, and its class's name.
    stacklevel : int
        Frames between this function and the user's call (2: called by the public callable itself).
    """
    if changes:
        names = ", ".join(f"{k}=..." for k in changes)
        warnings.warn(f"{where}({names}): fields as keywords are deprecated and go in a later release; pass "
                      f"{parameter}=axialdeform.{value}({names}) instead", DeprecationWarning, stacklevel=stacklevel + 1)

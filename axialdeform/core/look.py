"""How a picture looks: ONE value object, :class:`Look`, whose defaults are
written here and nowhere else.

Every picture takes one: :func:`axialdeform.render_image`,
:meth:`axialdeform.AxialRenderer.render`, the ground plane, the shadow map,
the viewer, scene files (``[light]`` and ``background``), the web page (as
JSON, :meth:`Look.to_json`) and the notebook widget.  Pure data: no GL here.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .errors import ArgumentError

__all__ = ["Look", "DEFAULT_LOOK", "LIGHT_DIR", "LIGHT_COLOR", "SKY_COLOR", "GROUND_COLOR", "BACKGROUND", "AMBIENT",
           "LINE_COLOR"]

#: unit-less direction towards the key light (world space; normalised where used)
LIGHT_DIR = (0.35, 0.85, 0.4)
#: the clear colour (sRGB) the ground plane fades into
BACKGROUND = (0.93, 0.94, 0.96)
#: share of the sky/ground hemisphere ambient, 0 .. 1
AMBIENT = 0.35
#: the colour of wireframe lines (linear RGB)
LINE_COLOR = (0.12, 0.14, 0.18)
#: the key light's colour (linear RGB): a warm sun
LIGHT_COLOR = (1.0, 0.96, 0.88)
#: the hemisphere ambient: the sky above (cool) and the bounce from the ground below (warm), linear RGB
SKY_COLOR = (0.80, 0.88, 1.05)
GROUND_COLOR = (0.50, 0.44, 0.38)
_HIDDEN_LINE = ("fill", True, False)


@dataclass(frozen=True)
class Look:
    """How a picture looks; the instances and the camera are elsewhere.

    Parameters
    ----------
    light_dir : (3,) float
        Direction towards the key light, world space (normalised where used).
    light_color : (3,) float
        The key light's colour (linear RGB).
    ambient : float
        Share of the sky/ground hemisphere ambient light, 0 .. 1.
    sky_color : (3,) float
        The hemisphere ambient from the sky above (linear RGB).
    ground_color : (3,) float
        The hemisphere ambient bounced from the ground below (linear RGB).
    background : (3,) float
        The clear colour (sRGB, 0 .. 1); the ground plane fades into it.
    line_color : (3,) float
        Wireframe line colour (linear RGB).
    ground : bool
        A ground plane under the instances.
    shadow : bool
        A shadow map from the key light (instances shadow the ground and
        each other).
    samples : int
        Multisampling (0: none); capped by the context's ``max_samples``.
    hidden_line : {"fill", True, False}
        Wireframe style: ``"fill"`` front-most edges over washed-out faces,
        ``True`` front-most edges only, ``False`` every edge.
    fast : bool
        The plain path the benchmark times: no multisampling, ground, shadow
        or hidden lines, whatever the fields above say.

    Examples
    --------
    >>> Look().replace(light_dir=(0, 1, 0), ground=False)   # doctest: +ELLIPSIS
    Look(light_dir=(0, 1, 0), ...)
    """

    light_dir: tuple = LIGHT_DIR
    light_color: tuple = LIGHT_COLOR
    ambient: float = AMBIENT
    sky_color: tuple = SKY_COLOR
    ground_color: tuple = GROUND_COLOR
    background: tuple = BACKGROUND
    line_color: tuple = LINE_COLOR
    ground: bool = True
    shadow: bool = True
    samples: int = 4
    hidden_line: object = "fill"
    fast: bool = False

    def __post_init__(self) -> None:
        for name in ("light_dir", "light_color", "sky_color", "ground_color", "background", "line_color"):
            value = getattr(self, name)
            try:
                vec = tuple(float(x) for x in value)
            except (TypeError, ValueError):
                raise ArgumentError(f"look.{name}: expected three numbers, found {value!r}") from None
            if len(vec) != 3 or not all(abs(x) < float("inf") for x in vec):
                raise ArgumentError(f"look.{name}: expected three finite numbers, found {value!r}")
            object.__setattr__(self, name, vec)
        if not any(self.light_dir):
            raise ArgumentError("look.light_dir: expected a non-zero direction, found (0, 0, 0)")
        if not 0.0 <= float(self.ambient) <= 1.0:
            raise ArgumentError(f"look.ambient: expected a number in 0 .. 1, found {self.ambient!r}")
        object.__setattr__(self, "ambient", float(self.ambient))
        if isinstance(self.samples, bool) or not isinstance(self.samples, int) or self.samples < 0:
            raise ArgumentError(f"look.samples: expected a whole number >= 0, found {self.samples!r}")
        if self.hidden_line not in _HIDDEN_LINE or isinstance(self.hidden_line, int) and not isinstance(
                self.hidden_line, bool):
            raise ArgumentError(f"look.hidden_line: expected 'fill', True or False, found {self.hidden_line!r}")

    def replace(self, **changes) -> Look:
        """A copy with ``changes`` (:func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    # what is drawn, once ``fast`` is taken into account
    @property
    def draws_ground(self) -> bool:
        return self.ground and not self.fast

    @property
    def draws_shadow(self) -> bool:
        return self.shadow and not self.fast

    @property
    def msaa(self) -> int:
        """Samples to ask for (0 when ``fast``)."""
        return 0 if self.fast else int(self.samples)

    @property
    def wire_style(self):
        """The ``hidden_line`` in effect (``False`` when ``fast``)."""
        return False if self.fast else self.hidden_line

    def to_json(self) -> dict:
        """The look as the web page receives it (its config's ``"look"``)."""
        return {"light_dir": list(self.light_dir), "light_color": list(self.light_color), "ambient": self.ambient,
                "sky_color": list(self.sky_color), "ground_color": list(self.ground_color),
                "background": list(self.background),
                "line_color": list(self.line_color), "ground": self.draws_ground, "shadow": self.draws_shadow,
                "samples": self.msaa, "hidden_line": self.wire_style}


#: the look every picture has unless told otherwise
DEFAULT_LOOK = Look()

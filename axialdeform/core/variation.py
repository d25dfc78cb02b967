"""Seeded variation: random parameters for ``count`` instances.

The same seed gives the same numbers on every platform and numpy version:
all randomness is PCG64's raw 64-bit output (a fixed algorithm), turned into
uniform doubles in [0, 1) as ``(x >> 11) * 2**-53``; every distribution
below is written out from those uniforms.

Canonical form: the five offsets of an instance have zero mean (a shift
shared by all five is the same as a translation, see docs/parameter-files.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from dataclasses import fields as dataclass_fields

import numpy as np

from .axes import child_offsets, droop_offsets, level_bends, sag_offsets
from .axis import AXIS_NAMES
from .errors import ParamError
from .options import warn_field_keywords
from .params import as_params
from .record import (
    ANGLES,
    OFFSETS,
    POSITION,
    SCALE,
    TAPER,
    TINT,
    TWIST,
    WIDTHS,
    Instances,
    join_record,
)

__all__ = ["Variation", "random_params", "iter_random_params", "PLACEMENTS", "uniforms", "tint_of", "check_tint_hue"]

PLACEMENTS = ("grid", "box", "disc")


def uniforms(seed: int, n: int) -> np.ndarray:
    """``n`` uniform doubles in [0, 1) from PCG64(seed), platform-independent."""
    _check_seed(seed)
    return _stream(seed, 0, n)


def _number(value, name: str) -> float:
    if isinstance(value, (bool, np.bool_)):
        raise ParamError(f"{name}: expected a number, found {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ParamError(f"{name}: expected a number, found {value!r}") from None


def _range(value, name: str) -> tuple[float, float]:
    lo, hi = (float(value), float(value)) if np.isscalar(value) else (float(value[0]), float(value[1]))
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi < lo:
        raise ParamError(f"{name}: expected a finite range (min, max) with min <= max, found {value!r}")
    return lo, hi



def check_tint_hue(value, name: str = "tint_hue") -> float:
    """``value`` as a float in 0..1, or a ParamError naming ``name``."""
    hue = _number(value, name)
    if not (math.isfinite(hue) and 0 <= hue <= 1):
        raise ParamError(f"{name}: expected an amount between 0 and 1, found {value!r}")
    return hue


def tint_of(u, amount: float, color, hue: float = 0.0, dtype=np.float64) -> np.ndarray:
    """Tints ``(n, 3)`` from ``u`` (n, 3) uniform in 0..1: ``color (1 - amount (u_r + hue (u - u_r)))``.

    ``hue`` 0: the first column's ``u`` for every channel (shades of ``color``, its hue kept); 1: each
    channel its own ``u``.  ``dtype`` the arithmetic's (float32: as ``glsl/generate.glsl`` computes it)."""
    f = np.dtype(dtype).type
    u = np.asarray(u, dtype)
    mixed = u[:, :1] + f(hue) * (u - u[:, :1])
    return np.asarray(color, dtype) * (f(1.0) - f(amount) * mixed)

@dataclass(frozen=True)
class Variation:
    """How far instances differ: the ranges every random number of an instance is drawn from.

    One value read by :func:`random_params`, :func:`axialdeform.scatter`, the viewer and the command
    line (whose defaults are this class's).  Fields are checked when the value is made; a bad one is
    a :class:`ParamError` naming it.  ``Variation(bend=0.2)`` changes one field,
    ``variation.replace(twist=1.0)`` another.

    Attributes
    ----------
    bend : float or sequence of float
        Offsets are drawn uniformly in ``±bend·L`` per component, then made canonical (zero mean over
        the five control points).  A mesh of several axes takes one amplitude per level of its
        hierarchy (``(trunk, branches, twigs)``; the last one for any deeper level).
    yaw : (float, float)
        Range of the angle about the up axis (radians).
    tilt : (float, float)
        Range of the two other angles (radians).
    height : (float, float)
        Range of the position along the up axis (``random_params``' grid and disc).
    scale : (float, float) or None
        ``0 < min <= max``: a uniform scale per instance (a single number: every instance that size).
    twist : float or None
        ``tw`` uniform in ``[-|twist|, |twist|]`` radians.
    taper : float or None
        ``tp`` uniform between 0 and ``taper`` (< 1).
    tint : float or None
        An amount in 0..1: each instance's tint is ``tint_color`` times ``1 - tint·u``, ``u`` uniform
        in 0..1 (:func:`tint_of`): lighter and darker shades of ``tint_color``.
    tint_hue : float
        How far each colour channel's ``u`` goes its own way, 0..1: 0 (default) one ``u`` for the three
        channels, so the tint keeps ``tint_color``'s hue; 1 one ``u`` each (the hue varies too).
    tint_color : (float, float, float)
        Linear RGB in 0..1, the brightest tint (white: the mesh's own colours).
    droop : float
        A sag toward the world's down, beside the isotropic ``bend`` (0: none), by this fraction
        of an axis's length at its far end (:func:`~axialdeform.core.axes.sag_offsets`): every child
        axis of a mesh of several axes (a leaf, a frond), clamped at its joint; a single axis (a
        blade, a leaf card) from its ``t = 0`` end (``scatter``: from the anchor it stands on;
        ``random_params`` keeps the offsets' zero mean).

    Any of ``scale``, ``twist``, ``taper`` makes 19-number (extended) instances, ``tint`` 22-number
    (tinted) ones; the first 16 numbers of an instance stay what they are without them.
    """

    bend: float | tuple = 0.08
    yaw: tuple = (0.0, 2 * math.pi)
    tilt: tuple = (-0.25, 0.25)
    height: tuple = (0.0, 0.0)
    scale: tuple | None = None
    twist: float | None = None
    taper: float | None = None
    tint: float | None = None
    tint_color: tuple = (1.0, 1.0, 1.0)
    droop: float = 0.0
    tint_hue: float = 0.0

    def __post_init__(self):
        put = object.__setattr__
        bends = level_bends(self.bend)  # several axes: each level its own amplitude (the last one beyond)
        put(self, "bend", bends[0] if np.isscalar(self.bend) else bends)
        for name in ("yaw", "tilt", "height"):
            put(self, name, _range(getattr(self, name), name))
        if self.scale is not None:
            lo, hi = _range(self.scale, "scale")
            if not lo > 0:
                raise ParamError(f"scale: expected MIN,MAX with 0 < MIN <= MAX, found {self.scale!r}")
            put(self, "scale", (lo, hi))
        if self.twist is not None:
            twist = _number(self.twist, "twist")
            if not math.isfinite(twist):
                raise ParamError(f"twist: expected a finite number of radians, found {self.twist!r}")
            put(self, "twist", twist)
        if self.taper is not None:
            taper = _number(self.taper, "taper")
            if not (math.isfinite(taper) and taper < 1):
                raise ParamError(f"taper: expected a number < 1, found {self.taper!r}")
            put(self, "taper", taper)
        if self.tint is not None:
            amount = _number(self.tint, "tint")
            if not (math.isfinite(amount) and 0 <= amount <= 1):
                raise ParamError(f"tint: expected a variation amount between 0 and 1, found {self.tint!r}")
            put(self, "tint", amount)
        color = np.asarray(self.tint_color, dtype=np.float64) if np.ndim(self.tint_color) == 1 else None
        if color is None or color.shape != (3,) or not (np.isfinite(color).all() and (color >= 0).all()
                                                         and (color <= 1).all()):
            raise ParamError(f"tint_color: expected three linear RGB numbers in 0..1, found {self.tint_color!r}")
        put(self, "tint_color", tuple(float(c) for c in color))
        put(self, "tint_hue", check_tint_hue(self.tint_hue))
        droop = _number(self.droop, "droop")
        if not (math.isfinite(droop) and droop >= 0):
            raise ParamError(f"droop: expected a fraction of an axis's length >= 0, found {self.droop!r}")
        put(self, "droop", droop)

    @property
    def bends(self) -> tuple[float, ...]:
        """The bend amplitude of each level of a hierarchy (one number: every level)."""
        return self.bend if isinstance(self.bend, tuple) else (self.bend,)

    @property
    def extended(self) -> bool:
        """Whether instances get the 19-number extension (scale, twist, taper) or wider."""
        return any(x is not None for x in (self.scale, self.twist, self.taper, self.tint))

    def replace(self, **fields) -> Variation:
        """A copy with some fields changed (checked again)."""
        return replace(self, **fields)

    @classmethod
    def of(cls, variation: Variation | None = None, fields: dict | None = None, error: type = ParamError, *,
           where: str = "", stacklevel: int = 2) -> Variation:
        """``variation`` (default: the default variation) with ``fields`` changed: the one way a function
        that takes ``variation=`` and its fields as keywords reads them.  A keyword that is no field is
        ``error``, naming it.  ``where``: the public callable whose keywords ``fields`` are -- they still
        work for one release, with a DeprecationWarning (``stacklevel``: the caller's frame)."""
        base = cls() if variation is None else variation
        if not isinstance(base, cls):
            raise error(f"variation: expected an axialdeform.Variation, found {type(base).__name__}")
        fields = fields or {}
        unknown = sorted(set(fields) - {f.name for f in dataclass_fields(cls)})
        if unknown:
            raise error(f"{unknown[0]}: not an option; expected one of the fields of axialdeform.Variation "
                        f"({', '.join(f.name for f in dataclass_fields(cls))})")
        if not fields:
            return base
        if where:
            warn_field_keywords(where, fields, "variation", "Variation", stacklevel=stacklevel + 1)
        try:
            return replace(base, **fields)
        except ParamError as exc:
            raise (exc if error is ParamError else error(str(exc))) from None


@dataclass(frozen=True)
class _Spec:
    """Checked options of :func:`random_params`."""

    count: int
    seed: int
    length: float
    placement: str
    spacing: float
    up: int
    variation: Variation
    tree: object = None  # several axes: the mesh's AxisTree
    axis: object = None  # the mesh's ControlAxis (droop of a single axis)


def _spec(mesh, count: int, seed: int, variation: Variation | None, fields: dict, placement: str = "grid",
          spacing: float | None = None, up: str = "y", where: str = "random_params") -> _Spec:
    """The checked options of :func:`random_params`."""
    if not isinstance(count, (int, np.integer)) or count < 0:
        raise ParamError(f"count: expected a non-negative integer, found {count!r}")
    if placement not in PLACEMENTS:
        raise ParamError(f"placement: expected one of {', '.join(PLACEMENTS)}, found {placement!r}")
    if up not in AXIS_NAMES:
        raise ParamError(f"up: expected one of x, y, z, found {up!r}")
    variation = Variation.of(variation, fields, where=where, stacklevel=3)
    length = mesh.axis.length
    spacing = 1.1 * length if spacing is None else float(spacing)
    if not (math.isfinite(spacing) and spacing > 0):
        raise ParamError(f"spacing: expected a finite distance > 0, found {spacing!r}")
    _check_seed(seed)
    return _Spec(int(count), int(seed), length, placement, spacing, AXIS_NAMES.index(up), variation,
                 getattr(mesh, "tree", None), mesh.axis)


def random_params(mesh, count: int, seed: int = 0, variation: Variation | None = None, *, placement: str = "grid",
                  spacing: float | None = None, up: str = "y", **fields) -> np.ndarray:
    """Random parameters: ``(count, 16) float32``, or ``(count, 19)`` (extended
    instances) when any of ``scale``, ``twist``, ``taper`` is given, or
    ``(count, 22)`` (tinted instances) with ``tint``.

    Parameters
    ----------
    mesh : BaseMesh
        Its axis length ``L`` scales the bend.
    count, seed : int
        How many instances, and the seed of the random stream.
    variation : Variation, optional
        How far the instances differ (:class:`Variation`: bend, yaw, tilt, height, scale, twist,
        taper, tint); default ``Variation()``.
    placement : {"grid", "disc", "box"}
        A square grid on the ground plane, uniform in a disc on it, or uniform in a cube (for
        falling leaves).
    spacing : float, optional
        Distance between neighbours in world units (default ``1.1·L``); disc and box sizes are
        chosen so each instance gets about that much room.
    up : {"x", "y", "z"}
        The world up axis; the ground plane is across it.
    **fields
        Deprecated (still working for one release, with a DeprecationWarning): fields of
        :class:`Variation` that replace ``variation``'s (``bend=0.1, twist=0.5``); write
        ``variation=Variation(bend=0.1, twist=0.5)``.

    Returns
    -------
    Instances
        ``(count, 16|19|22)`` float32, or ``10·(K − 1)`` more columns for K axes.

    Notes
    -----
    A child axis ``j`` of a mesh of several axes (:meth:`BaseMesh.with_axes`) has offsets uniform in
    ``±bend[level]·L_j``, clamped at its anchor (``D_j(t_a) = 0``, ``D_j'(t_a) = 0``: joints stay
    closed), drawn after every other number.  The first 16 numbers of an instance are the same
    with or without the extension (the extra numbers come from the same random stream, after the
    others).  Instance ``i`` depends only on the seed, the options, ``count`` and ``i``:
    :func:`iter_random_params` yields the same rows in pieces.
    """
    spec = _spec(mesh, count, seed, variation, fields, placement, spacing, up)
    return Instances.of(_rows(spec, 0, spec.count))


def iter_random_params(mesh, count: int, seed: int = 0, variation: Variation | None = None, *,
                       chunk: int = 1 << 18, placement: str = "grid", spacing: float | None = None, up: str = "y",
                       **fields):
    """The rows of :func:`random_params` (same arguments) in pieces of at most
    ``chunk`` instances, an iterator of ``(m, 16)`` (or ``(m, 19)``) float32
    arrays: concatenated they are exactly ``random_params(mesh, count, seed,
    ...)``, bit for bit, but memory holds one piece at a time (each piece
    starts the random stream where it is, PCG64's ``advance``)."""
    spec = _spec(mesh, count, seed, variation, fields, placement, spacing, up, "iter_random_params")  # said before the first piece
    if not isinstance(chunk, (int, np.integer)) or chunk < 1:
        raise ParamError(f"chunk: expected a number of instances >= 1, found {chunk!r}")
    chunk = int(chunk)
    return (_rows(spec, start, min(spec.count, start + chunk)) for start in range(0, spec.count, chunk))


def _check_seed(seed) -> None:
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParamError(f"seed: expected a non-negative integer, found {seed!r}")


def _stream(seed: int, skip: int, n: int) -> np.ndarray:
    """Uniform doubles ``skip .. skip + n - 1`` of PCG64(seed)'s stream (see :func:`uniforms`)."""
    bits = np.random.PCG64(int(seed))
    if skip:
        bits.advance(int(skip))
    raw = bits.random_raw(int(n))
    return (np.asarray(raw, dtype=np.uint64) >> np.uint64(11)).astype(np.float64) * 2.0**-53


def _rows(spec: _Spec, start: int, stop: int) -> np.ndarray:
    """Instances ``start .. stop - 1`` of the ``spec.count`` a spec describes: (m, 16|19|22) float32."""
    n, m = spec.count, stop - start
    spacing, up_i, placement = spec.spacing, spec.up, spec.placement
    u = _stream(spec.seed, 16 * start, 16 * m).reshape(m, 16)  # one row of uniforms per instance
    var = spec.variation
    out = np.zeros((m, WIDTHS[2 if var.tint is not None else 1 if var.extended else 0]), dtype=np.float64)

    offsets = (2.0 * u[:, OFFSETS] - 1.0) * var.bends[0] * spec.length
    offsets = offsets.reshape(m, 5, 2)
    offsets -= offsets.mean(axis=1, keepdims=True)
    out[:, OFFSETS] = offsets.reshape(m, 10)

    ground = [i for i in range(3) if i != up_i]
    pos = np.zeros((m, 3))
    if placement == "grid":
        cols = max(1, math.ceil(math.sqrt(n)))
        k = np.arange(start, stop)
        jitter = (u[:, POSITION][:, :2] - 0.5) * 0.2 * spacing
        pos[:, ground[0]] = (k % cols - (cols - 1) / 2) * spacing + jitter[:, 0]
        pos[:, ground[1]] = (k // cols - (math.ceil(n / cols) - 1) / 2) * spacing + jitter[:, 1]
    elif placement == "disc":
        radius = spacing * math.sqrt(max(n, 1) / math.pi)
        r = radius * np.sqrt(u[:, 10])
        phi = 2 * math.pi * u[:, 11]
        pos[:, ground[0]] = r * np.cos(phi)
        pos[:, ground[1]] = r * np.sin(phi)
    else:  # box
        side = spacing * max(n, 1) ** (1 / 3)
        pos = (u[:, POSITION] - 0.5) * side
    if placement != "box":
        height = var.height
        pos[:, up_i] = height[0] + (height[1] - height[0]) * u[:, 12]
    out[:, POSITION] = pos

    yaw, tilt = var.yaw, var.tilt
    angles = tilt[0] + (tilt[1] - tilt[0]) * u[:, ANGLES]
    angles[:, up_i] = yaw[0] + (yaw[1] - yaw[0]) * u[:, 13 + up_i]
    out[:, ANGLES] = angles
    if var.droop and spec.tree is None:  # one axis (a leaf, a blade): it sags from its t = 0 end, kept canonical
        sag = sag_offsets([spec.axis], [0.0], var.droop, angles, up_i)[:, 0]
        sag -= sag.mean(axis=1, keepdims=True)
        out[:, OFFSETS] += sag.reshape(m, 10)
    del u, offsets, pos, angles
    if var.extended:
        # the same stream, after the 16 numbers of every instance: 3 a row
        extra = _stream(spec.seed, 16 * n + 3 * start, 3 * m).reshape(m, 3)
        (s_lo, s_hi) = var.scale or (1.0, 1.0)
        tw, tp = var.twist or 0.0, var.taper or 0.0
        out[:, SCALE] = s_lo + (s_hi - s_lo) * extra[:, 0]
        out[:, TWIST] = abs(tw) * (2.0 * extra[:, 1] - 1.0)
        out[:, TAPER] = tp * extra[:, 2]
    if var.tint is not None:
        # then 3 a row for the tint, after the extended numbers of every instance
        amount, color = var.tint, var.tint_color
        u_tint = _stream(spec.seed, 19 * n + 3 * start, 3 * m).reshape(m, 3)
        out[:, TINT] = tint_of(u_tint, amount, color, var.tint_hue)
    if spec.tree is not None:
        # several axes: 10 numbers per child axis, after the tint block of every instance
        k = spec.tree.count - 1
        u_child = _stream(spec.seed, 22 * n + 10 * k * start, 10 * k * m).reshape(m, k, 5, 2)
        children = child_offsets(spec.tree, var.bends, u_child)
        if var.droop:
            children = children + droop_offsets(spec.tree, var.droop, out[:, ANGLES], up_i)
        return as_params(join_record(out, children), axes=k + 1)
    return as_params(out)

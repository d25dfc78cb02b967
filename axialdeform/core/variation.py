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
from dataclasses import dataclass

import numpy as np

from .axes import child_offsets, level_bends
from .axis import AXIS_NAMES
from .errors import ParamError
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

__all__ = ["random_params", "iter_random_params", "PLACEMENTS", "uniforms"]

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


@dataclass(frozen=True)
class _Spec:
    """Checked options of :func:`random_params`."""

    count: int
    seed: int
    bend: float
    length: float
    placement: str
    spacing: float
    up: int
    yaw: tuple
    tilt: tuple
    height: tuple
    extended: bool
    scale: tuple
    twist: float
    taper: float
    tint: tuple | None = None  # (amount, (r, g, b)): tinted instances
    tree: object = None  # several axes: the mesh's AxisTree ...
    bends: tuple = ()  # ... and the bend amplitude of each level of it


def _spec(
    mesh,
    count: int,
    seed: int = 0,
    *,
    bend: float = 0.08,
    placement: str = "grid",
    spacing: float | None = None,
    up: str = "y",
    yaw=(0.0, 2 * math.pi),
    tilt=(-0.25, 0.25),
    height=(0.0, 0.0),
    scale=None,
    twist=None,
    taper=None,
    tint=None,
    tint_color=(1.0, 1.0, 1.0),
) -> _Spec:
    """The checked options of :func:`random_params`."""
    if not isinstance(count, (int, np.integer)) or count < 0:
        raise ParamError(f"count: expected a non-negative integer, found {count!r}")
    if placement not in PLACEMENTS:
        raise ParamError(f"placement: expected one of {', '.join(PLACEMENTS)}, found {placement!r}")
    if up not in AXIS_NAMES:
        raise ParamError(f"up: expected one of x, y, z, found {up!r}")
    bends = level_bends(bend)  # several axes: each level its own amplitude (the last one beyond)
    bend = bends[0]
    length = mesh.axis.length
    spacing = 1.1 * length if spacing is None else float(spacing)
    if not (math.isfinite(spacing) and spacing > 0):
        raise ParamError(f"spacing: expected a finite distance > 0, found {spacing!r}")
    yaw, tilt, height = _range(yaw, "yaw"), _range(tilt, "tilt"), _range(height, "height")
    extended = any(x is not None for x in (scale, twist, taper, tint))
    tinting = None
    if tint is not None:
        amount = _number(tint, "tint")
        if not (math.isfinite(amount) and 0 <= amount <= 1):
            raise ParamError(f"tint: expected a variation amount between 0 and 1, found {tint!r}")
        color = np.asarray(tint_color, dtype=np.float64) if np.ndim(tint_color) == 1 else None
        if color is None or color.shape != (3,) or not (np.isfinite(color).all() and (color >= 0).all()
                                                         and (color <= 1).all()):
            raise ParamError(f"tint_color: expected three linear RGB numbers in 0..1, found {tint_color!r}")
        tinting = (amount, tuple(float(c) for c in color))
    s_lo, s_hi = _range(1.0 if scale is None else scale, "scale")
    if not s_lo > 0:
        raise ParamError(f"scale: expected MIN,MAX with 0 < MIN <= MAX, found {scale!r}")
    tw = 0.0 if twist is None else float(twist)
    tp = 0.0 if taper is None else float(taper)
    if not math.isfinite(tw):
        raise ParamError(f"twist: expected a finite number of radians, found {twist!r}")
    if not (math.isfinite(tp) and tp < 1):
        raise ParamError(f"taper: expected a number < 1, found {taper!r}")
    _check_seed(seed)
    return _Spec(int(count), int(seed), bend, length, placement, spacing, AXIS_NAMES.index(up), yaw, tilt,
                 height, extended, (s_lo, s_hi), tw, tp, tinting, getattr(mesh, "tree", None), bends)


def random_params(
    mesh,
    count: int,
    seed: int = 0,
    *,
    bend: float = 0.08,
    placement: str = "grid",
    spacing: float | None = None,
    up: str = "y",
    yaw=(0.0, 2 * math.pi),
    tilt=(-0.25, 0.25),
    height=(0.0, 0.0),
    scale=None,
    twist=None,
    taper=None,
    tint=None,
    tint_color=(1.0, 1.0, 1.0),
) -> np.ndarray:
    """Random parameters: ``(count, 16) float32``, or ``(count, 19)`` (extended
    instances) when any of ``scale``, ``twist``, ``taper`` is given, or
    ``(count, 22)`` (tinted instances) with ``tint``.

    mesh : BaseMesh (its axis length ``L`` scales the bend).
    bend : offsets are drawn uniformly in ``±bend·L`` per component, then
        made canonical (zero mean over the five control points).  A mesh of
        several axes (:meth:`BaseMesh.with_axes`) takes one amplitude per level
        of its hierarchy (``(trunk, branches, twigs)``; the last one for any
        deeper level): a child axis ``j``'s offsets are uniform in
        ``±bend[level]·L_j`` with ``d₁ = 0`` (its root stays where its parent
        puts it: joints stay closed), drawn after every other number.
    placement : ``"grid"`` (square grid on the ground plane), ``"disc"``
        (uniform in a disc on the ground plane) or ``"box"`` (uniform in a
        cube, for falling leaves).
    spacing : distance between neighbours in world units (default ``1.1·L``);
        disc and box sizes are chosen so each instance gets about that much room.
    up : ``"x"``, ``"y"`` or ``"z"``: the world up axis; the ground plane is
        across it.
    yaw : range of the angle about the up axis (radians).
    tilt : range of the two other angles (radians).
    height : range of the position along the up axis (grid and disc).
    scale : ``(min, max)`` with ``0 < min <= max``: uniform scale ``s``, drawn
        uniformly (a single number: every instance that size).
    twist : ``max`` radians: ``tw`` uniform in ``[-|max|, |max|]``.
    taper : ``max`` (< 1): ``tp`` uniform between 0 and ``max``.
    tint : ``amount`` in 0..1: each instance's tint (linear RGB multiplying
        the mesh's base colour) is ``tint_color`` times ``1 - amount * u``,
        ``u`` uniform in 0..1 drawn per channel.
    tint_color : ``(r, g, b)`` in 0..1, the brightest tint (default white:
        the mesh's own colours).
    The first 16 numbers of an instance are the same as without these (the
    extra numbers come from the same random stream, after the others).
    Instance ``i`` depends only on the seed, the options, ``count`` and ``i``:
    :func:`iter_random_params` yields the same rows in pieces.
    """
    spec = _spec(mesh, count, seed, bend=bend, placement=placement, spacing=spacing, up=up, yaw=yaw, tilt=tilt,
                 height=height, scale=scale, twist=twist, taper=taper, tint=tint, tint_color=tint_color)
    return Instances.of(_rows(spec, 0, spec.count))


def iter_random_params(mesh, count: int, seed: int = 0, *, chunk: int = 1 << 18, **options):
    """The rows of :func:`random_params` (same arguments) in pieces of at most
    ``chunk`` instances, an iterator of ``(m, 16)`` (or ``(m, 19)``) float32
    arrays: concatenated they are exactly ``random_params(mesh, count, seed,
    ...)``, bit for bit, but memory holds one piece at a time (each piece
    starts the random stream where it is, PCG64's ``advance``)."""
    spec = _spec(mesh, count, seed, **options)  # bad options are said here, before the first piece
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
    out = np.zeros((m, WIDTHS[2 if spec.tint else 1 if spec.extended else 0]), dtype=np.float64)

    offsets = (2.0 * u[:, OFFSETS] - 1.0) * spec.bend * spec.length
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
        height = spec.height
        pos[:, up_i] = height[0] + (height[1] - height[0]) * u[:, 12]
    out[:, POSITION] = pos

    yaw, tilt = spec.yaw, spec.tilt
    angles = tilt[0] + (tilt[1] - tilt[0]) * u[:, ANGLES]
    angles[:, up_i] = yaw[0] + (yaw[1] - yaw[0]) * u[:, 13 + up_i]
    out[:, ANGLES] = angles
    del u, offsets, pos, angles
    if spec.extended:
        # the same stream, after the 16 numbers of every instance: 3 a row
        extra = _stream(spec.seed, 16 * n + 3 * start, 3 * m).reshape(m, 3)
        (s_lo, s_hi), tw, tp = spec.scale, spec.twist, spec.taper
        out[:, SCALE] = s_lo + (s_hi - s_lo) * extra[:, 0]
        out[:, TWIST] = abs(tw) * (2.0 * extra[:, 1] - 1.0)
        out[:, TAPER] = tp * extra[:, 2]
    if spec.tint:
        # then 3 a row for the tint, after the extended numbers of every instance
        amount, color = spec.tint
        u_tint = _stream(spec.seed, 19 * n + 3 * start, 3 * m).reshape(m, 3)
        out[:, TINT] = np.asarray(color) * (1.0 - amount * u_tint)
    if spec.tree is not None:
        # several axes: 10 numbers per child axis, after the tint block of every instance
        k = spec.tree.count - 1
        u_child = _stream(spec.seed, 22 * n + 10 * k * start, 10 * k * m).reshape(m, k, 5, 2)
        return as_params(join_record(out, child_offsets(spec.tree, spec.bends, u_child)), axes=k + 1)
    return as_params(out)

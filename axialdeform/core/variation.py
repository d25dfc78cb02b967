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

import numpy as np

from .axis import AXIS_NAMES
from .errors import ParamError
from .params import ANGLES, OFFSETS, POSITION, as_params

__all__ = ["random_params", "PLACEMENTS", "uniforms"]

PLACEMENTS = ("grid", "box", "disc")


def uniforms(seed: int, n: int) -> np.ndarray:
    """``n`` uniform doubles in [0, 1) from PCG64(seed), platform-independent."""
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParamError(f"seed: expected a non-negative integer, found {seed!r}")
    raw = np.random.PCG64(int(seed)).random_raw(int(n))
    return (np.asarray(raw, dtype=np.uint64) >> np.uint64(11)).astype(np.float64) * 2.0**-53


def _range(value, name: str) -> tuple[float, float]:
    lo, hi = (float(value), float(value)) if np.isscalar(value) else (float(value[0]), float(value[1]))
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi < lo:
        raise ParamError(f"{name}: expected a finite range (min, max) with min <= max, found {value!r}")
    return lo, hi


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
) -> np.ndarray:
    """Random parameters: ``(count, 16) float32``, or ``(count, 19)`` (extended
    instances) when any of ``scale``, ``twist``, ``taper`` is given.

    mesh : BaseMesh (its axis length ``L`` scales the bend).
    bend : offsets are drawn uniformly in ``±bend·L`` per component, then
        made canonical (zero mean over the five control points).
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
    The first 16 numbers of an instance are the same as without these (the
    extra numbers come from the same random stream, after the others).
    """
    if not isinstance(count, (int, np.integer)) or count < 0:
        raise ParamError(f"count: expected a non-negative integer, found {count!r}")
    if placement not in PLACEMENTS:
        raise ParamError(f"placement: expected one of {', '.join(PLACEMENTS)}, found {placement!r}")
    if up not in AXIS_NAMES:
        raise ParamError(f"up: expected one of x, y, z, found {up!r}")
    if not (math.isfinite(bend) and bend >= 0):
        raise ParamError(f"bend: expected a finite fraction of L >= 0, found {bend!r}")
    length = mesh.axis.length
    spacing = 1.1 * length if spacing is None else float(spacing)
    if not (math.isfinite(spacing) and spacing > 0):
        raise ParamError(f"spacing: expected a finite distance > 0, found {spacing!r}")
    yaw, tilt, height = _range(yaw, "yaw"), _range(tilt, "tilt"), _range(height, "height")
    extended = any(x is not None for x in (scale, twist, taper))
    s_lo, s_hi = _range(1.0 if scale is None else scale, "scale")
    if not s_lo > 0:
        raise ParamError(f"scale: expected MIN,MAX with 0 < MIN <= MAX, found {scale!r}")
    tw = 0.0 if twist is None else float(twist)
    tp = 0.0 if taper is None else float(taper)
    if not math.isfinite(tw):
        raise ParamError(f"twist: expected a finite number of radians, found {twist!r}")
    if not (math.isfinite(tp) and tp < 1):
        raise ParamError(f"taper: expected a number < 1, found {taper!r}")
    n = int(count)
    u = uniforms(seed, n * 16).reshape(n, 16)  # one row of uniforms per instance
    out = np.zeros((n, 16), dtype=np.float64)

    offsets = (2.0 * u[:, OFFSETS] - 1.0) * bend * length
    offsets = offsets.reshape(n, 5, 2)
    offsets -= offsets.mean(axis=1, keepdims=True)
    out[:, OFFSETS] = offsets.reshape(n, 10)

    up_i = AXIS_NAMES.index(up)
    ground = [i for i in range(3) if i != up_i]
    pos = np.zeros((n, 3))
    if placement == "grid":
        cols = max(1, math.ceil(math.sqrt(n)))
        k = np.arange(n)
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
        pos[:, up_i] = height[0] + (height[1] - height[0]) * u[:, 12]
    out[:, POSITION] = pos

    angles = tilt[0] + (tilt[1] - tilt[0]) * u[:, ANGLES]
    angles[:, up_i] = yaw[0] + (yaw[1] - yaw[0]) * u[:, 13 + up_i]
    out[:, ANGLES] = angles
    if not extended:
        return as_params(out)
    extra = uniforms(seed, n * 19)[n * 16 :].reshape(n, 3)  # the same stream, after the 16 numbers a row
    ext = np.empty((n, 19))
    ext[:, :16] = out
    ext[:, 16] = s_lo + (s_hi - s_lo) * extra[:, 0]
    ext[:, 17] = abs(tw) * (2.0 * extra[:, 1] - 1.0)
    ext[:, 18] = tp * extra[:, 2]
    return as_params(ext)

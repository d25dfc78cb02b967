"""Wind: the CPU reference of ``glsl/wind.glsl`` (see ``docs/wind.md``).

The wind moves each instance's control points, never its vertices directly,
so the exact normals of the deformation still hold.  It is a function of the
instance (its index, position and angles), the base mesh's axis and a few
numbers that are uniforms on the GPU: direction, strength, gustiness,
frequency, gust wavelength and the time.  Nothing per instance is uploaded
per frame.

For instance ``i`` at time ``T``::

    h    = (pcg(i) >> 8) / 2**24                    # per-instance phase, bit-exact on CPU and GPU
    ph   = h - dot(p, dir) / wavelength             # gust fronts travel along dir (no term if wavelength = 0)
    wave = 0.6 sin(2π (c1 + ph)) + 0.4 sin(2π (c2 + 1.7 ph)),  c1 = frac(f T), c2 = frac(2.31 f T)
    amp  = strength · L · (1 + gustiness · wave)    # tip displacement, model units
    u    = amp · (Rᵀ dir) across the axis           # the wind in the instance's own frame
    d_k += c_k · u,  c = (0, 0, 1/6, 1/2, 1)        # the control polygon of D(t) = t²

``P1`` and ``P2`` do not move, so the base point and the base tangent stay;
the tip moves by ``u``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .axes import sag_weights
from .axis import ControlAxis
from .errors import ParamError
from .params import as_params, check_tree_params
from .record import ANGLES, OFFSETS, POSITION, split_record
from .transforms import rotation_matrices

__all__ = ["Wind", "WIND_WEIGHTS", "WIND_UNIFORMS",
           "SECOND_HARMONIC", "wind_hash", "wind_phase", "position_ids", "wind_offsets", "apply_wind",
           "wind_wave",
           "tree_wind_offsets"]

#: how much of the tip displacement each control point P1..P5 gets (D(t) = t²: an axis anchored at t = 0)
WIND_WEIGHTS = sag_weights(0.0)
#: frequency ratio of the second sine of the gust wave
SECOND_HARMONIC = 2.31

#: the wind's uniforms, in the order glsl/wind.glsl's functions take them: (name, GLSL type, what).  Spelled
#: ``u_wind_<name>`` in glsl/ and ``axialWind<Name>`` in the npm module and the page; tools/make_tables.py writes
#: their declarations (glsl/scene.vert) and the module's table (js/src/core/record.js's WIND_UNIFORMS) from this one
WIND_UNIFORMS = (("dir", "vec3", "unit direction, world"),
                 ("strength", "float", "tip displacement, in units of L; 0: still"),
                 ("gust", "float", "gustiness"),
                 ("cycles", "vec2", "(fract(f T), fract(2.31 f T)), computed on the CPU"),
                 ("wavenumber", "float", "1 / gust wavelength (world units), 0: no travelling fronts"))


#: the most a wind may displace a tip, in axis lengths (``strength``, ``gustiness``): more draws nothing a
#: picture can show (a parameter file's offsets have the same kind of bound)
MAX_WIND = 100.0


@dataclass(frozen=True)
class Wind:
    """A wind, the same on CPU and GPU.

    Parameters
    ----------
    direction : (3,) float
        World direction (normalized on creation).
    strength : float
        Tip displacement as a fraction of the axis length ``L`` (>= 0).
    gustiness : float
        How much the displacement swings around its mean (>= 0; 0 = a steady lean).
    frequency : float
        Gust cycles per second (>= 0).
    wavelength : float
        Distance between gust fronts in world units (> 0), or 0 for none.
    """

    direction: tuple = (1.0, 0.0, 0.0)
    strength: float = 0.15
    gustiness: float = 0.6
    frequency: float = 0.5
    wavelength: float = 0.0
    _unit: tuple = field(default=(1.0, 0.0, 0.0), init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        try:
            d = np.asarray(self.direction, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            d = np.zeros(0)
        norm = float(np.linalg.norm(d)) if d.size == 3 and np.isfinite(d).all() else 0.0
        if not norm > 0:
            raise ParamError(f"wind direction: expected 3 finite numbers, not all zero, found {self.direction!r}")
        for name in ("strength", "gustiness", "frequency", "wavelength"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float, np.floating, np.integer)) and math.isfinite(value) and value >= 0):
                raise ParamError(f"wind {name}: expected a finite number >= 0, found {value!r}")
            if name in ("strength", "gustiness") and value > MAX_WIND:
                raise ParamError(f"wind {name}: expected at most {MAX_WIND:g} (axis lengths), found {value!r}")
        object.__setattr__(self, "direction", tuple(float(x) for x in d))
        object.__setattr__(self, "_unit", tuple(float(x) for x in d / norm))

    @property
    def unit_direction(self) -> np.ndarray:
        """(3,) float64: the direction, normalized."""
        return np.array(self._unit)

    @property
    def wavenumber(self) -> float:
        """``1 / wavelength`` (0 when there are no travelling fronts)."""
        return 1.0 / self.wavelength if self.wavelength > 0 else 0.0

    def cycles(self, time: float) -> np.ndarray:
        """(2,) float64: ``(frac(f T), frac(2.31 f T))``, the time as the shader gets it."""
        time = float(time)
        if not math.isfinite(time):
            raise ParamError(f"time: expected a finite number of seconds, found {time!r}")
        return np.array([(self.frequency * time) % 1.0, (SECOND_HARMONIC * self.frequency * time) % 1.0])

    def uniforms(self, time: float) -> dict:
        """``{u_wind_<name>: value}``: every one of :data:`WIND_UNIFORMS` at ``time`` seconds, as a program is given them."""
        values = {"dir": tuple(self.unit_direction), "strength": float(self.strength), "gust": float(self.gustiness),
                  "cycles": tuple(self.cycles(time)), "wavenumber": float(self.wavenumber)}
        return {f"u_wind_{name}": values[name] for name, _type, _what in WIND_UNIFORMS}

    @classmethod
    def parse(cls, text: str, direction=(1.0, 0.0, 0.0), name: str = "--wind") -> Wind:
        """A wind from ``text``, ``STRENGTH[,GUSTINESS[,FREQUENCY[,WAVELENGTH]]]`` (the CLI's ``--wind``),
        blowing along ``direction``; errors name the option ``name``."""
        parts = [p for p in str(text).split(",")]
        keys = ("strength", "gustiness", "frequency", "wavelength")
        if not 1 <= len(parts) <= 4:
            raise ParamError(f"{name}: expected STRENGTH[,GUSTINESS[,FREQUENCY[,WAVELENGTH]]], found {text!r}")
        values = {}
        for key, part in zip(keys, parts):
            try:
                values[key] = float(part)
            except ValueError:
                raise ParamError(f"{name}: {key}: expected a number >= 0, found {part!r}") from None
            if not (math.isfinite(values[key]) and values[key] >= 0):
                raise ParamError(f"{name}: {key}: expected a finite number >= 0, found {part!r}")
        return cls(direction=tuple(direction), **values)


def wind_hash(ids) -> np.ndarray:
    """The PCG hash of ``glsl/wind.glsl``: (n,) integer instance indices -> (n,) uint32."""
    i = np.asarray(ids).astype(np.uint32)
    with np.errstate(over="ignore"):
        h = i * np.uint32(747796405) + np.uint32(2891336453)
        h = ((h >> ((h >> np.uint32(28)) + np.uint32(4))) ^ h) * np.uint32(277803737)
        return (h >> np.uint32(22)) ^ h


def wind_phase(ids) -> np.ndarray:
    """(n,) float32 in [0, 1): 24 bits of the hash, exactly as the shader computes it."""
    return (wind_hash(ids) >> np.uint32(8)).astype(np.float32) * np.float32(1.0 / 16777216.0)


def position_ids(params) -> np.ndarray:
    """A generated instance's lasting identity, ``axial_position_id`` of ``glsl/wind.glsl``: (n,) uint32, the
    hash of the float32 bits of its x and z (``params``: the standard record, (n, 16|19|22)).  Its index
    changes as tiles come and go; this does not, so neither do its wind phase and shade."""
    p = np.ascontiguousarray(as_params(params)[:, POSITION], dtype=np.float32)
    return wind_hash(p[:, 0].view(np.uint32) ^ wind_hash(p[:, 2].view(np.uint32)))


def _phase_ids(params, start: int, ids: str) -> np.ndarray:
    """The ids the wind's phase hashes: the instance indices ``start + row`` (``ids="index"``) or, for a
    generated layer's instances, :func:`position_ids` (``ids="position"``)."""
    if ids == "position":
        return position_ids(params)
    if ids != "index":
        raise ParamError(f"wind: ids: expected 'index' or 'position', found {ids!r}")
    return np.arange(start, start + len(params))


def wind_offsets(wind: Wind, axis: ControlAxis, params, time: float, *, start: int = 0,
                 ids: str = "index") -> np.ndarray:
    """What the wind adds to every instance's control-point offsets at ``time``.

    params : (n, 16) or (n, 19) — the instances (their index is ``start + row``); ids : the phases' ids
    (``"index"``, or ``"position"``: a generated layer's, :func:`position_ids`).
    Returns (n, 5, 2) float64 (model units; the first two rows are 0).
    """
    wave, local = wind_wave(wind, params, time, start=start, ids=ids)
    amp = wind.strength * axis.length * (1.0 + wind.gustiness * wave)  # (n,)
    u = amp[:, None] * axis.across(local)  # (n, 2): the push across the axis (any frame)
    return WIND_WEIGHTS[None, :, None] * u[:, None, :]


def wind_wave(wind: Wind, params, time: float, *, start: int = 0, ids: str = "index") -> tuple[np.ndarray, np.ndarray]:
    """The wind's ``wave`` (n,) float64 at ``time`` and its direction in each
    instance's model frame ``Rᵀ dir`` (n, 3) float64 (``params``: the
    standard record, (n, 16|19|22)): what every axis's push is made of."""
    phase_ids = _phase_ids(params, start, ids)
    params = as_params(params).astype(np.float64)
    d = wind.unit_direction
    c1, c2 = wind.cycles(time)
    ph = wind_phase(phase_ids).astype(np.float64) - params[:, POSITION] @ d * wind.wavenumber
    wave = 0.6 * np.sin(2.0 * np.pi * (c1 + ph)) + 0.4 * np.sin(2.0 * np.pi * (c2 + 1.7 * ph))
    local = np.einsum("nji,j->ni", rotation_matrices(params[:, ANGLES]), d)  # Rᵀ dir
    return wave, local


def apply_wind(wind: Wind | None, axis, params, time: float, *, start: int = 0, ids: str = "index") -> np.ndarray:
    """``params`` with the wind's offsets added (same shape, float32); ``None`` returns them unchanged.
    ``axis``: the mesh's :class:`ControlAxis`, or its :class:`~axialdeform.core.axes.AxisTree`
    (several axes: every axis is pushed, :func:`tree_wind_offsets`); ``ids``: the phases' ids, the
    instance indices from ``start`` (``"index"``) or a generated layer's :func:`position_ids` (``"position"``)."""
    if getattr(axis, "axes", None) is not None:  # an AxisTree
        params = check_tree_params(params, axis.count)
        if wind is None or wind.strength == 0:
            return params
        out = params.copy()
        k = axis.count
        moved = params[:, :10 * k].astype(np.float64) + tree_wind_offsets(
            wind, axis, params, time, start=start, ids=ids).reshape(len(params), -1)
        out[:, :10 * k] = moved.astype(np.float32)
        return out
    params = as_params(params)
    if wind is None or wind.strength == 0:
        return params
    out = params.copy()
    moved = params[:, OFFSETS].astype(np.float64) + wind_offsets(wind, axis, params, time, start=start,
                                                                 ids=ids).reshape(-1, 10)
    out[:, OFFSETS] = moved.astype(np.float32)
    return as_params(out)


def tree_wind_offsets(wind: Wind, tree, params, time: float, *, start: int = 0, ids: str = "index") -> np.ndarray:
    """What the wind adds to every axis's offsets: (n, K, 5, 2) float64.  Each
    axis ``j`` is pushed across itself by ``strength·L_j·(1 + gustiness·wave)``
    (one wave per instance, :func:`~axialdeform.core.wind.wind_wave`), on its
    control points :func:`~axialdeform.core.axes.sag_weights` of its anchor (``c = (0, 0, 1/6, 1/2, 1)`` for
    an axis anchored at its root end): the tips of the branches move most and the joints stay.
    Axis 0's push is :func:`~axialdeform.core.wind.wind_offsets` exactly."""
    k = tree.count
    standard, _ = split_record(check_tree_params(params, k), k)
    wave, local = wind_wave(wind, standard, time, start=start, ids=ids)
    out = np.empty((len(standard), k, 5, 2))
    for j, axis in enumerate(tree.axes):
        amp = wind.strength * axis.length * (1.0 + wind.gustiness * wave)  # (n,)
        weights = WIND_WEIGHTS if j == 0 else sag_weights(tree.anchors[j])
        out[:, j] = weights[None, :, None] * (amp[:, None] * axis.across(local))[:, None, :]
    return out

"""Step 3 of the data flow: the 16 numbers per instance, and their files.

One instance is ``d1u d1v d2u d2v d3u d3v d4u d4v d5u d5v px py pz rx ry rz``
(offsets in model units, position in world units, angles in radians applied
about fixed X, then Y, then Z).  In memory a set of instances is a
``(n, 16) float32`` array.  An **extended** instance adds ``s tw tp`` (uniform
scale > 0, twist in radians over the axis, taper < 1; see the extension
section of ``docs/method.md``): ``(n, 19) float32``.  A **tinted** instance
adds ``tr tg tb`` after those (linear RGB in 0..1 multiplying the base colour):
``(n, 22) float32``.  The fields and their levels: :mod:`.record`.

Files
-----
* **text** (``.txt``, ``.csv``, ``.dat``; and anything that does not start
  with the binary magic): 16 numbers a line (or 19 on EVERY line: extended;
  22: tinted),
  separated by commas or white space; lines starting with ``#`` are comments.
* **binary** (``.adp``): see ``docs/parameter-files.md``.  A fixed header
  (magic, version, encoding, count, the axis and a SHA-256 fingerprint of the
  base mesh it was made for), the payload (float32, 64 bytes per instance, or
  uint16 quantized, 32 bytes per instance) and a CRC-32 trailer over header
  and payload.  Version 1 holds 16 numbers per instance, version 2 the 19
  of extended instances (76 bytes float32, 38 uint16 quantized), version 3
  the 22 of tinted ones (88, 44).

NaN and infinite parameters are refused everywhere (reading, writing,
uploading) with a :class:`ParamError`: a non-finite number has no shape.
"""

from __future__ import annotations

import numpy as np

from .arrays import as_array
from .errors import ParamError
from .record import (  # the record's columns and slices: one home
    ANGLES,
    EXTENDED_FIELDS,
    EXTENDED_WIDTH,
    EXTRA,
    FIELDS,
    IDENTITY_EXTRA,
    IDENTITY_TINT,
    OFFSETS,
    POSITION,
    SCALE,
    TAPER,
    TINT,
    TINTED_WIDTH,
    TWIST,
    WIDTHS,
    Instances,
    describe_widths,
    is_record_width,
    record_fields,
    tree_shape,
    tree_widths,
)

__all__ = [
    "FIELDS", "EXTENDED_FIELDS", "OFFSETS", "EXTRA", "SCALE", "TWIST", "TAPER", "is_extended", "is_tinted",
    "extend_params", "tint_params", "TINT", "POSITION", "ANGLES", "as_params", "make_params", "range_warning",
    "SAFE_DISTANCE_L", "check_drawable", "DRAWABLE_MAGNITUDE",
]


def as_params(values, *, name: str = "parameters", error: type = ParamError, rows=None, widths=WIDTHS,
              axes=None) -> np.ndarray:
    """Check and convert to a C-contiguous ``(n, 16)``, ``(n, 19)`` or ``(n, 22) float32`` array.

    A single record of 16 (19, 22) numbers becomes ``(1, 16)`` (``(1, 19)``, ...).
    Raises :class:`ParamError` (or ``error``) for a wrong shape, a non-finite
    number, (19 columns or more) a scale ``s <= 0`` or a taper ``tp >= 1``,
    or (22) a tint outside 0..1;
    ``rows`` optionally names each row (e.g. its line in a file).  ``widths``
    lists the accepted numbers per instance (``(16,)`` where only the plain
    form makes sense).  ``axes``: K, the axes of the mesh (several axes:
    ``10·K + 6`` numbers, ``+ 3``, ``+ 6``; core/axes.py), or ``"any"`` (a
    file, whose width says K).
    """
    try:
        arr = np.asarray(values, dtype=np.float32)
    except (TypeError, ValueError) as exc:
        raise error(f"{name}: expected numbers, found {type(values).__name__} ({exc})") from None
    if axes == "any":
        width = arr.shape[-1] if arr.ndim in (1, 2) else -1
        widths = (width,) if is_record_width(width) else WIDTHS
    elif axes is not None and axes != 1:
        widths = tree_widths(axes)
    if arr.ndim == 1 and arr.shape[0] in widths:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] not in widths:
        expected = describe_widths(tuple(f"(n, {w})" for w in widths))
        many = "" if axes in (None, 1, "any") else f" for a mesh of {axes} axes (10·K + 6 numbers an instance)"
        raise error(f"{name}: expected an array of shape {expected}{many}, found {arr.shape}")
    fields = record_fields(arr.shape[1])
    finite = np.isfinite(arr)
    if not finite.all():
        row, col = (int(x) for x in np.argwhere(~finite)[0])
        where = f"instance {row}" if rows is None else rows[row]
        raise error(f"{name}: {where}, field {fields[col]}: expected a finite number, found {arr[row, col]}")
    k, level = tree_shape(arr.shape[1])
    tail = 10 * (k - 1)  # the rigid part and the extension come after every axis's offsets
    if level:
        checks = [(SCALE, arr[:, tail + SCALE] <= 0, "a scale s > 0"), (TAPER, arr[:, tail + TAPER] >= 1, "a taper tp < 1")]
        if level >= 2:
            checks += [(c, (arr[:, tail + c] < 0) | (arr[:, tail + c] > 1), "a tint in 0..1 (linear RGB)")
                       for c in range(TINT.start, TINT.stop)]
        for col, bad, expected in checks:
            if bad.any():
                row = int(np.argmax(bad))
                where = f"instance {row}" if rows is None else rows[row]
                raise error(f"{name}: {where}, field {fields[tail + col]}: expected {expected}, found {arr[row, tail + col]:.9g}")
    return np.ascontiguousarray(arr)


def is_extended(values) -> bool:
    """True for extended instances: an array whose last axis holds 19
    numbers (or 22: tinted instances are extended too)."""
    return _level(values) >= 1


def is_tinted(values) -> bool:
    """True for tinted instances: an array whose last axis holds 22 numbers (``10·K + 12`` with K axes)."""
    return _level(values) >= 2


def _level(values) -> int:
    """The record level of an array's last axis (several axes too); 0 when it is no record's width."""
    width = np.shape(values)[-1]
    return tree_shape(width)[1] if is_record_width(width) else (2 if width >= TINTED_WIDTH else int(width >= EXTENDED_WIDTH))


def extend_params(values) -> np.ndarray:
    """``(n, 19) float32``: 16-number instances get ``s = 1, tw = 0, tp = 0``
    (the same shapes); extended ones are returned checked, unchanged; tinted
    ones lose their tint."""
    values = as_params(values)
    if values.shape[1] == EXTENDED_WIDTH:
        return values
    if values.shape[1] > EXTENDED_WIDTH:
        return np.ascontiguousarray(values[:, :EXTENDED_WIDTH])
    out = np.empty((len(values), EXTENDED_WIDTH), dtype=np.float32)
    out[:, :16] = values
    out[:, EXTRA] = IDENTITY_EXTRA
    return out


def tint_params(values, tint=IDENTITY_TINT) -> np.ndarray:
    """``(n, 22) float32``: the instances with the tint ``tint`` ((n, 3) or
    (3,) linear RGB in 0..1; a 16-number instance gets ``s = 1, tw = 0, tp = 0``
    first).  ``Instances`` views: ``params.tint``."""
    values = extend_params(values)
    out = np.empty((len(values), TINTED_WIDTH), dtype=np.float32)
    out[:, :EXTENDED_WIDTH] = values
    tint = np.asarray(tint, dtype=np.float32)
    if tint.shape not in ((3,), (len(values), 3)):
        raise ParamError(f"tint: expected (3,) or ({len(values)}, 3) linear RGB, found shape {tint.shape}")
    out[:, TINT] = tint
    return Instances.of(as_params(out, name="tint"))


def make_params(offsets=None, positions=None, angles=None, count: int | None = None, *,
                scale=None, twist=None, taper=None, tint=None) -> np.ndarray:
    """Assemble ``(n, 16)`` parameters from parts (``(n, 19)`` when any of
    ``scale``, ``twist``, ``taper`` is given; ``(n, 22)`` with ``tint``).

    offsets : (n, 5, 2) model units; positions : (n, 3) world units;
    angles : (n, 3) radians.  Missing parts are zero.
    scale : (n,) > 0 (default 1); twist : (n,) radians (default 0);
    taper : (n,) < 1 (default 0); tint : (n, 3) or (3,) linear RGB in 0..1.
    """

    parts = {}
    for name, value, shape in (("offsets", offsets, (None, 5, 2)), ("positions", positions, (None, 3)),
                               ("angles", angles, (None, 3))):
        if value is not None:
            arr = as_array(value, shape, name, np.float32, error=ParamError)
            if len(shape) == 3 and arr.shape == (5, 2):
                arr = arr[None]
            parts[name] = arr
    lengths = {len(a) for a in parts.values()} | ({int(count)} if count is not None else set())
    if len(lengths) > 1:
        found = ", ".join(f"{k} {len(a)}" for k, a in parts.items()) + (f", count {count}" if count is not None else "")
        raise ParamError(f"make_params: expected the same number of instances in every part, found {found}")
    extra = (scale, twist, taper)
    lengths |= {len(np.atleast_1d(x)) for x in extra if x is not None and np.ndim(x) > 0}
    if tint is not None and np.ndim(tint) == 2:
        lengths.add(len(tint))
    if len(lengths) > 1:
        raise ParamError(f"make_params: expected the same number of instances in every part, found {sorted(lengths)}")
    n = lengths.pop() if lengths else 0
    extended = any(x is not None for x in extra)
    out = np.zeros((n, 19 if extended else 16), dtype=np.float32)
    if extended:
        for col, x, default in zip((SCALE, TWIST, TAPER), extra, IDENTITY_EXTRA):
            out[:, col] = default if x is None else np.broadcast_to(np.asarray(x, dtype=np.float32), (n,))
    if "offsets" in parts:
        out[:, OFFSETS] = parts["offsets"].reshape(n, 10)
    if "positions" in parts:
        out[:, POSITION] = parts["positions"]
    if "angles" in parts:
        out[:, ANGLES] = parts["angles"]
    if tint is not None:
        return tint_params(out, tint)
    return Instances.of(as_params(out))


# --------------------------------------------------------------------- text


# ------------------------------------------------------------------- binary


# -------------------------------------------------------------------- files


#: world distances (positions, offsets) up to this many axis lengths L keep
#: float32 precision of about 1e-5 L; beyond it errors grow in proportion
#: (measured: ``tools/precision.py``, see docs/reliability.md)
SAFE_DISTANCE_L = 100.0


#: the largest offset or position a picture can be drawn with (world units): float32
#: holds 3.4e38, and clip = proj * view * world multiplies two such magnitudes
DRAWABLE_MAGNITUDE = 1e18


def check_drawable(values, name: str = "parameters") -> None:
    """:class:`ParamError` naming ``name``, the instance and the field when an
    offset or position is too large to draw (:data:`DRAWABLE_MAGNITUDE`);
    files may hold such numbers (they are finite float32), pictures cannot."""
    from .record import record_fields, tree_shape

    v = np.asarray(values)
    if v.size == 0:
        return
    try:
        k = tree_shape(v.shape[1])[0]
    except ValueError:
        k = 1
    placed = 10 * k + 3  # every axis's offsets (10 each), then the position
    mag = np.abs(v[:, :placed])
    row_max = mag.max(axis=1)
    worst = int(np.argmax(row_max))
    if row_max[worst] > DRAWABLE_MAGNITUDE:
        col = int(np.argmax(mag[worst]))
        field = record_fields(v.shape[1])[col] if k > 1 else FIELDS[col]
        raise ParamError(f"{name}: instance {worst}, field {field} = {float(v[worst, col]):.6g}; expected at most "
                         f"{DRAWABLE_MAGNITUDE:g} in magnitude to draw it (float32 cannot project it)")


def range_warning(mesh, values, name: str = "parameters") -> str | None:
    """A one-line warning if any instance of ``values`` places its mesh, or
    bends it, further than :data:`SAFE_DISTANCE_L` axis lengths (float32
    keeps about 7 significant digits, so the deformed mesh loses detail in
    proportion to the distance); None when every value is in range.

    values : (n, 16) float32.
    """
    v = np.asarray(values)
    if v.size == 0:
        return None
    L = float(mesh.axis.length)
    limit = SAFE_DISTANCE_L * L
    mag = np.abs(v[:, :13])  # offsets and position, model/world units
    row_max = mag.max(axis=1)
    worst = int(np.argmax(row_max))
    if not row_max[worst] > limit:
        return None
    col = int(np.argmax(mag[worst]))
    count = int((row_max > limit).sum())
    ulp = float(np.spacing(np.float32(row_max[worst])))
    return (f"{name}: instance {worst}, field {FIELDS[col]} = {float(v[worst, col]):.6g} is {row_max[worst] / L:.3g} L "
            f"({count} instance{'s' if count != 1 else ''} beyond the safe {SAFE_DISTANCE_L:g} L); float32 steps there are "
            f"{ulp / L:.2g} L, so detail finer than that is lost (see docs/reliability.md, safe ranges)")


def check_tree_params(values, axes: int, *, name: str = "parameters", error: type = ParamError) -> np.ndarray:
    """:func:`as_params` for a mesh of ``axes`` axes: ``(n, 10·K + 6)`` (``+ 3``, ``+ 6``) float32."""
    return as_params(values, name=name, error=error, axes=axes)

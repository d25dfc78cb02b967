"""Quantization: each column of a record stored as a uint16 level of its own range, ``lo + q · step``
(the binary parameter files' compact form and the GPU's quantized instance buffer).  Pure numpy."""

from __future__ import annotations

import numpy as np

from .errors import ParamError
from .params import as_params
from .record import describe_widths, is_record_width

__all__ = ["quantization_error_bound", "quantize_params", "quantize_with_table", "dequantize_params", "quant_range",
           "quant_steps", "quant_levels"]


def quantization_error_bound(values: np.ndarray) -> np.ndarray:
    """Per-column bound on ``|decoded - original|`` of the quantized form: (w,) float64.

    Each column is stored as ``min + q * step`` with ``q`` a uint16 and
    ``step = (max - min) / 65535``, so the rounding error is at most
    ``step / 2``; the float32 arithmetic of the decode adds at most one
    float32 ulp of the column's largest magnitude.
    """
    v = as_params(values, axes="any").astype(np.float64)
    if len(v) == 0:
        return np.zeros(v.shape[1])
    lo, hi = v.min(axis=0), v.max(axis=0)
    mag = np.maximum(np.abs(lo), np.abs(hi))
    return (hi - lo) / 65535.0 / 2.0 + mag * 2.0**-23



def quantize_params(values) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The uint16 quantization of the binary file form, as arrays.

    values : (n, w) float — parameters (w = 16, 19 or 22 columns).
    Returns ``lo`` (w,) float32 (per-column minimum), ``step`` (w,) float32
    (per-column step, ``(max - min) / 65535`` widened by at most one ulp) and
    ``q`` (n, w) uint16, so that a value decodes as ``lo + q * step``
    (:func:`dequantize_params`).  The GPU quantized instance buffer
    (``AxialRenderer(..., quantized=True)``) stores exactly these.
    """
    values = as_params(values, axes="any")
    lo32, step32 = quant_steps(*quant_range([values], values.shape[1]))
    return lo32, step32, quant_levels(values, lo32, step32).astype(np.uint16)



def quantize_with_table(values, lo, step, *, name: str = "update", setter: str = "set()") -> np.ndarray:
    """Encode ``values`` with an existing table (``lo``, ``step`` from
    :func:`quantize_params`): ``q`` (n, 16) uint16.

    values : (n, 16) float; lo, step : (16,) float32.  A value outside the
    table's range ``lo .. lo + 65535 * step`` raises :class:`ParamError`
    naming ``name``, the instance and the field (no clipping), and pointing
    to ``setter`` (the call that re-quantizes every instance).
    """
    v = as_params(values, axes="any").astype(np.float64)
    w = v.shape[1]  # 16, 19 (extended) or 22 (tinted)
    lo = np.asarray(lo, dtype=np.float32).reshape(w).astype(np.float64)
    step = np.asarray(step, dtype=np.float32).reshape(w).astype(np.float64)
    q = _levels(v, lo, step)
    fits = (q >= 0) & (q <= 65535) & ((step > 0) | (v == lo))
    if not fits.all():
        row, col = (int(x) for x in np.argwhere(~fits)[0])
        raise ParamError(
            f"{name}: instance {row}, field {col}: {v[row, col]:.9g} is outside the quantized range "
            f"{lo[col]:.9g}..{lo[col] + 65535 * step[col]:.9g} of the buffer; "
            f"expected values inside it (call {setter} with every instance to re-quantize)"
        )
    return q.astype(np.uint16)



def _levels(v: np.ndarray, lo: np.ndarray, step: np.ndarray) -> np.ndarray:
    """The quantization levels ``rint((v - lo) / step)`` (float64; a zero step maps to level ``v - lo``)."""
    return np.rint((v - lo) / np.where(step > 0, step, 1.0))



def dequantize_params(lo, step, q) -> np.ndarray:
    """``lo + q * step`` per column, computed in float64 and rounded to float32: (n, w).

    lo, step : (w,) float32; q : (n, w) uint16, w = 16, 19 or 22.  The same
    decode as a quantized binary file.
    """
    w = np.size(lo)
    if not is_record_width(w):
        raise ParamError(f"quantization table: expected {describe_widths()} columns (10·K + 6 with K axes), found {w}")
    lo = np.asarray(lo, dtype=np.float32).reshape(w).astype(np.float64)
    step = np.asarray(step, dtype=np.float32).reshape(w).astype(np.float64)
    q = np.asarray(q, dtype="<u2").reshape(-1, w).astype(np.float64)
    with np.errstate(over="ignore", invalid="ignore"):  # a non-finite result is refused by as_params
        return (lo + q * step).astype(np.float32)



def quant_range(pieces, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-column minimum and maximum (float64, exact) over ``pieces`` of
    ``(m, width)`` float32 values, zeros when there are none: the same
    whether the values come whole or in pieces."""
    lo = hi = None
    for piece in pieces:
        if len(piece):
            p_lo, p_hi = piece.min(axis=0).astype(np.float64), piece.max(axis=0).astype(np.float64)
            lo = p_lo if lo is None else np.minimum(lo, p_lo)
            hi = p_hi if hi is None else np.maximum(hi, p_hi)
    if lo is None:
        return np.zeros(width), np.zeros(width)
    return lo, hi



def quant_steps(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The decode table of a column range: ``lo`` (w,) float32 and ``step`` (w,) float32."""
    lo32 = lo.astype(np.float32)
    step32 = ((hi - lo32.astype(np.float64)) / 65535.0).astype(np.float32)
    # a step that rounds to a value whose 65535 multiple falls short of the range is widened by one ulp
    short = lo32.astype(np.float64) + 65535.0 * step32.astype(np.float64) < hi
    step32[short] = np.nextafter(step32[short], np.float32(np.inf))
    return lo32, step32



def quant_levels(values: np.ndarray, lo32: np.ndarray, step32: np.ndarray) -> np.ndarray:
    """``values`` (m, w) as uint16 levels (little-endian) of the table ``lo32``, ``step32``."""
    v = values.astype(np.float64)
    return np.clip(_levels(v, lo32.astype(np.float64), step32.astype(np.float64)), 0, 65535).astype("<u2")

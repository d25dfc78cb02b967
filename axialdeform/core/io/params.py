"""Parameter files: text (one instance a line) and binary ``.adp``
(float32 or uint16-quantized, CRC-32 checked), read through the bounded
reader and written atomically; the quantization they share with the GPU
buffer.  The formats: ``docs/parameter-files.md``."""

from __future__ import annotations

import io
import os
import re
import struct
import warnings
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..axis import AXIS_NAMES, ControlAxis
from ..errors import MeshMismatchError, ParamError, ParamFileError
from ..params import as_params
from ..record import (  # the record's columns and slices: one home
    MAX_RECORD_AXES,
    WIDTHS,
    Instances,
    describe_widths,
    is_record_width,
    record_fields,
    tree_shape,
    tree_width,
    tree_widths,
)
from . import safeio
from .atomic import atomic_path
from .safeio import open_regular

__all__ = [
    "AXIS_FRAMED", "AxisRecord", "BINARY_SUFFIXES", "BinaryHeader", "ENCODING_FLOAT32", "ENCODING_UINT16",
    "HEADER_SIZE", "MAGIC", "ParamFile", "TEXT_SUFFIXES", "VERSION", "VERSION_EXTENDED", "VERSION_TINTED",
    "axis_letter", "check_mesh", "decode_binary", "dequantize_params", "encode_binary", "format_text",
    "param_file_bytes", "parse_text", "quantization_error_bound", "quantize_params", "quantize_with_table",
    "read_binary_header", "read_param_bytes", "read_param_file", "read_params", "write_param_chunks", "write_params",
]


BINARY_SUFFIXES = (".adp",)


TEXT_SUFFIXES = (".txt", ".csv", ".dat")


MAGIC = b"\x89ADP\r\n\x1a\n"


VERSION = 1  # 16 numbers per instance


VERSION_EXTENDED = 2  # 19 numbers per instance (s tw tp after the 16)


VERSION_TINTED = 3  # 22 numbers per instance (tr tg tb after the 19)


#: a file's version is its record level + 1 (core/record.py): version -> numbers per instance
_VERSIONS = {level + 1: width for level, width in enumerate(WIDTHS)}


ENCODING_FLOAT32 = 0


ENCODING_UINT16 = 1


_ENCODINGS = {ENCODING_FLOAT32: ("float32", 64), ENCODING_UINT16: ("uint16-quantized", 32)}


# magic, version, encoding, header size, count, axis, 3 pad, reserved, lo, L, fingerprint, frame digest
# (16 bytes, zero for an axis-aligned axis: the bytes every earlier file has there)
_HEADER = struct.Struct("<8sHHIQb3xIdd32s16s")


#: the header's axis byte of a chosen (not axis-aligned) frame: its rows' digest follows the fingerprint
AXIS_FRAMED = 3
#: the header's axis byte of a mesh of several axes: the tree's digest follows the fingerprint,
#: the count of axes K is the uint32 at offset 28 (0 in every earlier file: one axis)
AXIS_TREE = 4


@dataclass(frozen=True)
class AxisRecord:
    """The axis a parameter file records: enough to refuse another mesh's
    axis, not to bend (a frame is recorded by its digest).

    index : 0, 1, 2 (x, y, z) or -1 for a chosen frame; lo, length : the
    axis's ``lo`` and ``L``; frame_digest : 16 bytes (zero when aligned,
    :attr:`ControlAxis.frame_digest`)."""

    index: int
    lo: float
    length: float
    frame_digest: bytes = bytes(16)
    axes: int = 1

    @classmethod
    def of(cls, source) -> AxisRecord:
        """The record of a mesh (its axis, or its tree of several axes), a
        :class:`ControlAxis` or another record."""
        tree = getattr(source, "tree", None)
        if tree is not None:  # several axes: the root's lo and L, the tree's digest
            root = tree.axes[0]
            return cls(-2, float(root.lo), float(root.length), tree.digest, tree.count)
        axis = getattr(source, "axis", source)
        return cls(int(axis.index), float(axis.lo), float(axis.length), bytes(axis.frame_digest),
                   int(getattr(axis, "axes", 1)))

    @property
    def framed(self) -> bool:
        return self.index == -1

    def matches(self, source) -> bool:
        """Whether ``source`` (a mesh, or a :class:`ControlAxis`) has the axis recorded."""
        other = AxisRecord.of(source)
        return (self.index == other.index and self.frame_digest == other.frame_digest and self.axes == other.axes
                and bool(np.isclose(self.lo, other.lo)) and bool(np.isclose(self.length, other.length)))

    def describe(self) -> str:
        if self.axes > 1:
            return f"{self.axes} axes in a hierarchy (digest {self.frame_digest.hex()[:16]}), root lo={self.lo:.9g}, L={self.length:.9g}"
        if self.framed:
            return f"a chosen axis frame (digest {self.frame_digest.hex()[:16]}), lo={self.lo:.9g}, L={self.length:.9g}"
        return ControlAxis(self.index, self.lo, self.length).describe()


HEADER_SIZE = _HEADER.size  # 96


#: the decode table of a quantized file: per-column minimum, then per-column step
_QUANT_TABLES = {w: struct.Struct(f"<{w}f{w}f") for w in WIDTHS}


_TRAILER = struct.Struct("<I")


_MAX_TEXT_LINE = 4096


def format_text(values: np.ndarray, header: str | None = None) -> str:
    """The text form: one instance a line, 16 (19, 22) numbers separated by spaces.

    Numbers are written with 9 significant digits, which round-trips float32
    exactly.  ``header`` lines are written as ``#`` comments.
    """
    values = as_params(values, axes="any")
    return "".join(_text_pieces(values, header))


#: rows formatted at a time by the text writer: its memory stays bounded
_TEXT_ROWS = 4096


def _text_pieces(values: np.ndarray, header: str | None):
    """The text form in pieces of at most ``_TEXT_ROWS`` lines (a generator)."""
    yield _text_header(values.shape[1], header)
    yield from _text_body(values)


def _text_header(width: int, header: str | None) -> str:
    """The comment lines that start a text file: ``header``, then the field names."""
    lines = ["# " + line for line in (header or "").splitlines()]
    lines.append("# " + " ".join(record_fields(width)))
    return "\n".join(lines) + "\n"


def _text_body(values: np.ndarray):
    """The lines of ``values``, at most ``_TEXT_ROWS`` a piece (a generator)."""
    for s in range(0, len(values), _TEXT_ROWS):
        body = np.char.mod("%.9g", values[s : s + _TEXT_ROWS].astype(np.float64))
        yield "\n".join(" ".join(row) for row in body.tolist()) + "\n"


#: bytes of text parsed at a time: the parser's working memory is a few
#: times this, whatever the file's size
_TEXT_CHUNK = 1 << 18


_LINE_BREAK = re.compile(rb"[\r\n]")


_SEPARATORS = re.compile(r"[,\s]+")


def parse_text(data: bytes, name: str = "<text>") -> np.ndarray:
    """Parse the text form (bytes, UTF-8) into ``(n, 16) float32``, or
    ``(n, 19)`` / ``(n, 22)`` when every line holds 19 / 22 numbers (a mix is
    an error naming the line; the first data line fixes the width for the
    whole file).

    The text is parsed in pieces of about 256 KiB cut at line breaks, each
    turned into float32 rows at once, so the memory needed beyond ``data``
    and the result is bounded (peak under 3x the text's size plus the
    result, ``tests/app/test_hostile.py::test_text_parser_memory``)."""
    view = memoryview(data).cast("B") if not isinstance(data, (bytes, bytearray)) else data
    n = len(view)
    start = 3 if bytes(view[:3]) == b"\xef\xbb\xbf" else 0  # a leading byte-order mark is tolerated
    pieces: list[np.ndarray] = []
    lineno = 0
    first = None  # (width, line number) of the first data line: it fixes the width of every other
    window = 4 * _MAX_TEXT_LINE + 8  # a line of at most _MAX_TEXT_LINE characters has at most 4x as many bytes
    while start < n:
        end = min(n, start + _TEXT_CHUNK)
        if end < n:
            m = _LINE_BREAK.search(view, end, min(n, end + window)) if isinstance(view, (bytes, bytearray)) else \
                _LINE_BREAK.search(bytes(view[end : min(n, end + window)]))
            if m is None:
                before = bytes(view[start:end]).count(b"\n")
                raise ParamFileError(
                    f"{name}: line {lineno + before + 1} is longer than {window} bytes; "
                    f"expected at most {_MAX_TEXT_LINE} characters a line")
            cut = m.end() + (0 if isinstance(view, (bytes, bytearray)) else end)
            if view[cut - 1] == 0x0D and cut < n and view[cut] == 0x0A:
                cut += 1
            end = cut
        chunk = bytes(view[start:end])
        fast = _fast_chunk(chunk, None if first is None else first[0])
        if fast is not None:
            arr, lines_in_chunk = fast
            if len(arr):
                if first is None:
                    first = (arr.shape[1], lineno + _first_data_line(chunk))
                pieces.append(arr)
        else:
            rows, linenos, lines_in_chunk, first = _split_lines(chunk, name, lineno, start, first)
            if rows:
                pieces.append(_rows_to_float32(rows, linenos, name))
        lineno += lines_in_chunk
        start = end
    if not pieces:
        return np.zeros((0, 16), dtype=np.float32)
    return pieces[0] if len(pieces) == 1 else np.concatenate(pieces)


_PLAIN = re.compile(rb"[0-9eE+\-., \t\n]*")


_COMMENT_LINE = re.compile(rb"^[ \t]*#[\x20-\x7e\t]*$", re.M)


def _first_data_line(chunk: bytes) -> int:
    """1-based index in ``chunk`` of its first line that is neither blank nor a comment."""
    for k, line in enumerate(chunk.split(b"\n"), start=1):
        stripped = line.strip()
        if stripped and not stripped.startswith(b"#"):
            return k
    return 1


def _fast_chunk(chunk: bytes, width: int | None = None):
    """``(values (n, width) float32, lines)`` of a piece made only of numbers,
    commas, blanks and ``\n`` line breaks, parsed by numpy's C reader; None
    when the piece holds anything else (comments, ``\r``, other text) or
    does not parse into ``width`` columns (one of the record's widths when ``width`` is None):
    the line-by-line parser then finds the exact line and field for its message."""
    if b"#" in chunk:  # whole-line ASCII comments are dropped (their line breaks kept)
        chunk = _COMMENT_LINE.sub(b"", chunk)
    if not _PLAIN.fullmatch(chunk):
        return None
    breaks = np.flatnonzero(np.frombuffer(chunk, dtype=np.uint8) == 10)
    if np.diff(np.concatenate([[-1], breaks, [len(chunk)]])).max() > _MAX_TEXT_LINE + 1:
        return None  # a line too long: the slow path says which

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "empty input" of a piece with blank lines only
            arr = np.loadtxt(io.StringIO(chunk.replace(b",", b" ").decode("ascii")), dtype=np.float64, ndmin=2)
    except ValueError:
        return None
    if arr.size:
        if not is_record_width(arr.shape[1]) or (width is not None and arr.shape[1] != width):
            return None
        width = arr.shape[1]
    with np.errstate(over="ignore", invalid="ignore"):
        arr32 = arr.reshape(-1, width or 16).astype(np.float32)
    if not np.isfinite(arr32).all():  # beyond float32: the slow path names the line
        return None
    if len(arr32) and tree_shape(arr32.shape[1])[1]:
        try:
            as_params(arr32, axes="any")
        except ParamError:
            return None  # a bad scale, taper or tint: the slow path names the line and field
    lines = chunk.count(b"\n") + (0 if not chunk or chunk.endswith(b"\n") else 1)
    return np.ascontiguousarray(arr32), lines


def _split_lines(chunk: bytes, name: str, lineno: int, offset: int, first=None):
    """``(rows, line numbers, lines in chunk, first)`` of one piece, line by
    line; ``first`` is the ``(width, line number)`` of the file's first data
    line (None until one is seen): every data line must have its width."""
    try:
        text = chunk.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ParamFileError(
            f"{name}: not a parameter file: byte {offset + exc.start} is not UTF-8 text and the file does not start with the binary magic"
        ) from None
    rows: list[list[str]] = []
    linenos: list[int] = []
    lines = text.splitlines()
    for k, line in enumerate(lines, start=lineno + 1):
        if len(line) > _MAX_TEXT_LINE:
            raise ParamFileError(f"{name}: line {k} is {len(line)} characters long; expected at most {_MAX_TEXT_LINE}")
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        tokens = [tok for tok in _SEPARATORS.split(stripped) if tok]
        if not is_record_width(len(tokens)):
            raise ParamFileError(
                f"{name}: line {k}: expected 16 numbers, found {len(tokens)} (or 19 on every line: extended instances; "
                "22: tinted; 10·K + 6 with K axes)")
        if first is None:
            first = (len(tokens), k)
        elif len(tokens) != first[0]:
            raise ParamFileError(
                f"{name}: line {k}: expected {first[0]} numbers like line {first[1]}, found {len(tokens)} "
                f"(a file holds the same count on every line: {describe_widths()})"
            )
        rows.append(tokens)
        linenos.append(k)
    return rows, linenos, len(lines), first


def _rows_to_float32(rows: list[list[str]], linenos: list[int], name: str) -> np.ndarray:
    try:
        arr = np.array(rows, dtype=np.float64)
    except ValueError:
        arr = None
    if arr is None:
        # find the offending token for the message (only on the error path)
        for k, row in enumerate(rows):
            for c, tok in enumerate(row):
                try:
                    float(tok)
                except ValueError:
                    raise ParamFileError(
                        f"{name}: line {linenos[k]}, field {record_fields(len(row))[c]}: expected a number, found {tok[:40]!r}"
                    ) from None
        # numpy refused what Python's float() accepts: parse token by token
        arr = np.array([[float(tok) for tok in row] for row in rows], dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        arr32 = arr.astype(np.float32)  # beyond float32's range becomes inf and is refused below
    overflow = np.isfinite(arr) & ~np.isfinite(arr32)
    if overflow.any():
        k, c = (int(x) for x in np.argwhere(overflow)[0])
        raise ParamFileError(
            f"{name}: line {linenos[k]}, field {record_fields(arr.shape[1])[c]}: {arr[k, c]:.9g} does not fit in float32; "
            f"expected a finite number of magnitude at most {float(np.finfo(np.float32).max):.7g}"
        )
    return as_params(arr32, name=name, error=ParamFileError, rows=[f"line {n}" for n in linenos], axes="any")


@dataclass(frozen=True)
class ParamFile:
    """What a parameter file holds.

    values : (n, 16), (n, 19) or (n, 22) float32 — the parameters (decoded if quantized).
    format : ``"text"`` or ``"binary"``.
    encoding : ``"text"``, ``"float32"`` or ``"uint16-quantized"``.
    axis : the control axis it was made for (an :class:`AxisRecord`), or None if not recorded.
    mesh_fingerprint : 32-byte SHA-256 of the base mesh, or None.
    checksum : CRC-32 stored in the file (binary only; verified on read).
    size : file size in bytes.
    """

    values: np.ndarray
    format: str
    encoding: str
    axis: AxisRecord | None = None
    mesh_fingerprint: bytes | None = None
    checksum: int | None = None
    size: int = 0
    version: int | None = None

    @property
    def count(self) -> int:
        return len(self.values)


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
    w = values.shape[1]
    table, payload = _quantize(values)
    raw = _quant_table(w).unpack(table)
    q = np.frombuffer(payload, dtype="<u2").reshape(len(values), w).astype(np.uint16)
    return np.array(raw[:w], dtype=np.float32), np.array(raw[w:], dtype=np.float32), q


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
    lo = np.asarray(lo, dtype=np.float32).reshape(w)
    step = np.asarray(step, dtype=np.float32).reshape(w)
    q = np.asarray(q, dtype="<u2").reshape(-1, w)
    return _dequantize(_quant_table(w).pack(*lo.tolist(), *step.tolist()), q.tobytes(), len(q), w)


def _quant_table(width: int) -> struct.Struct:
    table = _QUANT_TABLES.get(width)
    if table is None:  # several axes: 10·K + 6 (+ 3, + 6) columns
        table = _QUANT_TABLES[width] = struct.Struct(f"<{width}f{width}f")
    return table


def _quantize(values: np.ndarray) -> tuple[bytes, bytes]:
    lo32, step32 = _quant_steps(*_quant_range([values], values.shape[1]))
    return _quant_table(values.shape[1]).pack(*lo32.tolist(), *step32.tolist()), _quant_levels(values, lo32, step32).tobytes()


def _quant_range(pieces, width: int) -> tuple[np.ndarray, np.ndarray]:
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


def _quant_steps(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The decode table of a column range: ``lo`` (w,) float32 and ``step`` (w,) float32."""
    lo32 = lo.astype(np.float32)
    step32 = ((hi - lo32.astype(np.float64)) / 65535.0).astype(np.float32)
    # a step that rounds to a value whose 65535 multiple falls short of the range is widened by one ulp
    short = lo32.astype(np.float64) + 65535.0 * step32.astype(np.float64) < hi
    step32[short] = np.nextafter(step32[short], np.float32(np.inf))
    return lo32, step32


def _quant_levels(values: np.ndarray, lo32: np.ndarray, step32: np.ndarray) -> np.ndarray:
    """``values`` (m, w) as uint16 levels (little-endian) of the table ``lo32``, ``step32``."""
    v = values.astype(np.float64)
    return np.clip(_levels(v, lo32.astype(np.float64), step32.astype(np.float64)), 0, 65535).astype("<u2")


def _dequantize(table: bytes, payload: bytes, count: int, width: int = 16) -> np.ndarray:
    raw = _quant_table(width).unpack(table)
    lo = np.array(raw[:width], dtype=np.float64)
    step = np.array(raw[width:], dtype=np.float64)
    q = np.frombuffer(payload, dtype="<u2", count=count * width).reshape(count, width).astype(np.float64)
    with np.errstate(over="ignore", invalid="ignore"):  # a non-finite result is refused by as_params
        return (lo + q * step).astype(np.float32)


def encode_binary(
    values: np.ndarray,
    *,
    axis: ControlAxis | None = None,
    mesh_fingerprint: bytes | None = None,
    quantize: bool = False,
) -> bytes:
    """The binary form of ``values`` (see ``docs/parameter-files.md``): version 1
    for 16 numbers per instance (unchanged), version 2 for 19 (extended),
    version 3 for 22 (tinted)."""
    values = as_params(values, axes="any")
    header = _binary_header(values.shape[1], quantize, len(values), axis, mesh_fingerprint)
    if quantize:
        table, payload = _quantize(values)
        body = header + table + payload
    else:
        body = header + values.astype("<f4").tobytes()  # 64 (76, 88) bytes per instance
    return body + _TRAILER.pack(zlib.crc32(body))


def _binary_header(width: int, quantize: bool, count: int, axis: ControlAxis | None,
                   mesh_fingerprint: bytes | None) -> bytes:
    """The fixed header of a binary file (:data:`HEADER_SIZE` bytes)."""
    if mesh_fingerprint is not None and len(mesh_fingerprint) != 32:
        raise ParamError(f"mesh fingerprint: expected 32 bytes, found {len(mesh_fingerprint)}")
    k, level = tree_shape(width)
    if axis is None:
        index, lo, length, digest = -1, 0.0, 0.0, bytes(16)
    else:
        record = AxisRecord.of(axis)
        if record.axes != k:
            raise ParamError(f"axis: the mesh has {record.axes} axes, but the parameters are {width} numbers "
                             f"an instance ({k} axes); expected 10·K + 6 numbers for K = {record.axes}")
        index = {-1: AXIS_FRAMED, -2: AXIS_TREE}.get(record.index, record.index)
        lo, length, digest = record.lo, record.length, record.frame_digest
    return _HEADER.pack(
        MAGIC, level + 1, ENCODING_UINT16 if quantize else ENCODING_FLOAT32,
        HEADER_SIZE, count, index, 0 if k == 1 else k, lo, length, mesh_fingerprint or bytes(32), digest,
    )


@dataclass(frozen=True)
class BinaryHeader:
    """The header of a binary parameter file, with both checksums.

    Structural checks (magic, version, encoding, header size, a length that
    matches the count) have passed; ``checksum_ok`` says whether the CRC-32
    stored in the file matches the one computed over header and payload.
    """

    version: int
    encoding: int
    count: int
    axis_index: int
    lo: float
    length: float
    fingerprint: bytes
    stored_crc: int
    computed_crc: int
    size: int
    frame_digest: bytes = bytes(16)
    axes: int = 1

    def axis_record(self, name: str = "<binary>") -> AxisRecord | None:
        """The recorded axis (None: not recorded); a value outside the format
        is a :class:`ParamFileError` naming the field."""
        if self.axis_index not in (-1, 0, 1, 2, AXIS_FRAMED, AXIS_TREE):
            raise ParamFileError(f"{name}: axis: expected -1 (not recorded), 0, 1, 2 (x, y, z), {AXIS_FRAMED} "
                                 f"(a chosen frame) or {AXIS_TREE} (several axes), found {self.axis_index}")
        if (self.axis_index == AXIS_TREE) != (self.axes > 1):
            raise ParamFileError(f"{name}: axis: expected {AXIS_TREE} (several axes) exactly when the file has "
                                 f"more than one axis, found axis {self.axis_index} with {self.axes} axes")
        if self.axis_index == -1:
            return None
        if self.axis_index == AXIS_TREE:
            if not (np.isfinite(self.lo) and np.isfinite(self.length) and self.length > 0):
                raise ParamFileError(f"{name}: axis: axis length must be a finite number > 0, found L={self.length!r}")
            return AxisRecord(-2, self.lo, self.length, self.frame_digest, self.axes)
        if self.axis_index != AXIS_FRAMED and any(self.frame_digest):
            raise ParamFileError(f"{name}: frame digest: expected zeros for axis {AXIS_NAMES[self.axis_index]}, "
                                 f"found {self.frame_digest.hex()}")
        try:
            if self.axis_index == AXIS_FRAMED:
                if not (np.isfinite(self.lo) and np.isfinite(self.length) and self.length > 0):
                    raise ParamFileError(f"axis length must be a finite number > 0, found L={self.length!r}")
                return AxisRecord(-1, self.lo, self.length, self.frame_digest)
            return AxisRecord.of(ControlAxis(index=self.axis_index, lo=self.lo, length=self.length))
        except Exception as exc:
            raise ParamFileError(f"{name}: axis: {exc}") from None

    @property
    def checksum_ok(self) -> bool:
        return self.stored_crc == self.computed_crc

    @property
    def encoding_name(self) -> str:
        return _ENCODINGS[self.encoding][0]

    @property
    def columns(self) -> int:
        """Numbers per instance: 16 (version 1), 19 (version 2, extended) or 22 (version 3, tinted);
        ``10·K + 6`` (``+ 3``, ``+ 6``) with K axes."""
        return tree_width(self.axes, self.version - 1)

    @property
    def payload_bytes(self) -> int:
        """Bytes of the instance records alone: the file less its header,
        decode table (quantized files) and checksum."""
        table = _quant_table(self.columns).size if self.encoding == ENCODING_UINT16 else 0
        return self.size - HEADER_SIZE - table - _TRAILER.size


def read_binary_header(data: bytes, name: str = "<binary>", *, size: int | None = None) -> BinaryHeader | None:
    """Check the structure of a binary parameter file and read its header.

    Every check happens before any allocation that depends on the declared
    count; the CRC-32 is computed but not judged (see ``checksum_ok``).
    With ``size`` (the file's size on disk), ``data`` may be the header
    alone: the structure is checked against ``size`` and None is returned
    (nothing is checksummed), so a file is read only once its header and its
    size agree."""
    head = bytes(data[: len(MAGIC)])
    if head != MAGIC[: len(head)]:  # say "not this format" before "too short"
        raise ParamFileError(
            f"{name}: magic: expected {MAGIC!r}, found {head!r}; not a binary parameter file "
            f"(the text form uses {', '.join(TEXT_SUFFIXES)})"
        )
    total = len(data) if size is None else int(size)
    if total < HEADER_SIZE + _TRAILER.size:
        raise ParamFileError(
            f"{name}: truncated: {total} bytes, expected at least {HEADER_SIZE + _TRAILER.size} (header + checksum)"
        )
    magic, version, encoding, header_size, count, axis_index, axes, lo, length, fingerprint, digest = _HEADER.unpack_from(data)
    axes = max(int(axes), 1)
    if magic != MAGIC:
        raise ParamFileError(f"{name}: magic: expected {MAGIC!r}, found {magic!r}")
    if version not in _VERSIONS:
        raise ParamFileError(
            f"{name}: version: expected "
            + ", ".join(f"{v} ({w} numbers)" for v, w in _VERSIONS.items()) + f", found {version} "
            "(written by a newer axialdeform?)"
        )
    if encoding not in _ENCODINGS:
        raise ParamFileError(f"{name}: encoding: expected 0 (float32) or 1 (uint16-quantized), found {encoding}")
    if header_size != HEADER_SIZE:
        raise ParamFileError(f"{name}: header size: expected {HEADER_SIZE}, found {header_size}")
    if axes > MAX_RECORD_AXES:
        raise ParamFileError(f"{name}: axes: expected 1 to {MAX_RECORD_AXES} axes, found {axes}")
    width = tree_width(axes, version - 1)
    record = _ENCODINGS[encoding][1] * width // 16
    table = _quant_table(width).size if encoding == ENCODING_UINT16 else 0
    expected = HEADER_SIZE + table + count * record + _TRAILER.size  # Python int: no overflow
    if total != expected:
        raise ParamFileError(
            f"{name}: count: the header declares {count} instances ({expected} bytes), but the file has {total} bytes"
            + (" (truncated?)" if total < expected else "")
        )
    if size is not None:
        return None
    (stored,) = _TRAILER.unpack_from(data, len(data) - _TRAILER.size)
    computed = zlib.crc32(memoryview(data)[: len(data) - _TRAILER.size])
    return BinaryHeader(version, encoding, count, axis_index, lo, length, fingerprint, stored, computed, len(data),
                        digest, axes)


def decode_binary(data: bytes, name: str = "<binary>") -> ParamFile:
    """Parse the binary form (see :func:`read_binary_header` for the checks
    before the checksum, which must match)."""
    h = read_binary_header(data, name)
    if not h.checksum_ok:
        raise ParamFileError(
            f"{name}: checksum: stored CRC-32 {h.stored_crc:08x}, computed {h.computed_crc:08x}; the file is corrupt"
        )
    encoding, count, fingerprint = h.encoding, h.count, h.fingerprint
    enc_name = h.encoding_name
    width = h.columns
    table = _quant_table(width).size if encoding == ENCODING_UINT16 else 0
    stored, version = h.stored_crc, h.version
    axis = h.axis_record(name)
    payload = memoryview(data)[HEADER_SIZE + table : len(data) - _TRAILER.size]
    if encoding == ENCODING_UINT16:
        values = _dequantize(bytes(data[HEADER_SIZE : HEADER_SIZE + table]), payload, count, width)
    else:
        values = np.frombuffer(payload, dtype="<f4", count=count * width).reshape(count, width).astype(np.float32)
    values = as_params(values, name=name, error=ParamFileError, axes="any")
    return ParamFile(
        values=values, format="binary", encoding=enc_name, axis=axis,
        mesh_fingerprint=None if fingerprint == bytes(32) else fingerprint,
        checksum=stored, size=len(data), version=version,
    )


def _is_binary_suffix(path: Path) -> bool:
    return path.suffix.lower() in BINARY_SUFFIXES


def read_param_file(path: str | os.PathLike) -> ParamFile:
    """Read a parameter file, text or binary (told apart by the magic bytes).

    The file must be a regular file (a FIFO, a device or a symlink to one is
    refused without blocking, :func:`~axialdeform.core.io.safeio.open_regular`);
    a binary file is read only if its size is what its header declares, a
    text file only if it fits in the memory available."""
    data, binary = read_param_bytes(path)
    if binary:
        return decode_binary(data, str(path))
    values = parse_text(data, str(path))
    return ParamFile(values=values, format="text", encoding="text", size=len(data))


def read_param_bytes(path: str | os.PathLike) -> tuple[bytes, bool]:
    """The bytes of a parameter file and whether it is binary, read with the
    checks of :func:`read_param_file` (regular file; a binary file's size
    must match its header before it is read; a text file must fit in memory)."""

    path = Path(path)
    with open_regular(path, "a parameter file", ParamFileError) as (fh, size):
        try:
            head = fh.read(HEADER_SIZE)
        except OSError as exc:
            raise ParamFileError(f"{path}: cannot read: {exc.strerror}") from None
        binary = head[: len(MAGIC)] == MAGIC or _is_binary_suffix(path)
        if binary:
            # the declared count bounds the read: a lying header costs nothing
            read_binary_header(head, str(path), size=size if len(head) == HEADER_SIZE else len(head))
            limit = size
        else:
            # text: the file, at most a third of the memory available (the parser needs about twice more)
            limit = max(safeio.memory_available() // 3, 1 << 20)
            if size > limit:
                raise ParamFileError(f"{path}: is {size} bytes; expected a text parameter file of at most {limit} bytes "
                                     "(a third of the memory available); use the binary form (.adp)")
        data = safeio.read_sized(fh, size, path, "a parameter file", ParamFileError)
    return data, binary


def check_mesh(pf: ParamFile, mesh, name: str = "<params>") -> None:
    """Raise :class:`MeshMismatchError` if ``pf`` records a base mesh other than ``mesh``."""
    if pf.mesh_fingerprint is not None and pf.mesh_fingerprint != mesh.fingerprint:
        raise MeshMismatchError(
            f"{name}: made for a different base mesh (fingerprint {pf.mesh_fingerprint.hex()[:16]}, "
            f"expected {mesh.fingerprint.hex()[:16]} of {mesh.name}); use the mesh it was made for, "
            "or override the check (allow_mesh_mismatch=True / --ignore-mesh-mismatch)"
        )
    if pf.axis is not None and not pf.axis.matches(mesh):
        raise MeshMismatchError(
            f"{name}: made for {pf.axis.describe()}, but {mesh.name} has {AxisRecord.of(mesh).describe()}; "
            "use the mesh it was made for, or override the check"
        )
    k = getattr(mesh, "axis_count", 1)
    if len(pf.values) and tree_shape(pf.values.shape[1])[0] != k:
        raise MeshMismatchError(
            f"{name}: {pf.values.shape[1]} numbers an instance ({tree_shape(pf.values.shape[1])[0]} axes), but "
            f"{mesh.name} has {k} axes; expected {describe_widths(tree_widths(k))} numbers an instance")


def read_params(path: str | os.PathLike, mesh=None, *, allow_mesh_mismatch: bool = False) -> np.ndarray:
    """Read a parameter file (text or binary) into ``(n, 16) float32`` (``(n, 19)``: extended; ``(n, 22)``: tinted).

    If ``mesh`` is given and the file records the base mesh it was made for,
    a different mesh raises :class:`MeshMismatchError` unless
    ``allow_mesh_mismatch`` is true.
    """
    pf = read_param_file(path)
    if mesh is not None and not allow_mesh_mismatch:
        check_mesh(pf, mesh, str(path))
    return Instances.of(pf.values)


def write_params(
    path: str | os.PathLike,
    values: np.ndarray,
    mesh=None,
    *,
    quantize: bool = False,
    axis: ControlAxis | None = None,
    mesh_fingerprint: bytes | None = None,
) -> Path:
    """Write parameters atomically; the format follows the extension.

    ``.adp`` is binary (float32, or uint16 with ``quantize=True``); ``.txt``,
    ``.csv`` and ``.dat`` are text.  ``mesh`` (a :class:`BaseMesh`) records
    the axis and fingerprint of the base mesh in a binary file.  Written in
    pieces (:func:`write_param_chunks`): memory beyond ``values`` stays
    bounded whatever the count.
    """
    values = as_params(values, axes="any")

    def pieces():
        return (values[s : s + _WRITE_ROWS] for s in range(0, len(values), _WRITE_ROWS))

    return write_param_chunks(path, pieces, len(values), values.shape[1], mesh, quantize=quantize, axis=axis,
                              mesh_fingerprint=mesh_fingerprint)


class _Rows:
    """``rows`` for :func:`as_params` of a piece that starts at instance ``first``."""

    def __init__(self, first: int):
        self.first = first

    def __getitem__(self, row: int) -> str:
        return f"instance {self.first + row}"


#: instances encoded at a time by the writers (a few MB of temporaries)
_WRITE_ROWS = 1 << 16


def write_param_chunks(
    path: str | os.PathLike,
    pieces,
    count: int,
    width: int = 16,
    mesh=None,
    *,
    quantize: bool = False,
    axis: ControlAxis | None = None,
    mesh_fingerprint: bytes | None = None,
) -> Path:
    """Write ``count`` instances that come in pieces, atomically, with memory
    bounded by one piece: the file is byte for byte what :func:`write_params`
    writes for the pieces concatenated.

    pieces : a callable returning a fresh iterable of ``(m, width)`` arrays
        (float32; ``width`` 16, 19 or 22) whose lengths add up to ``count``.  It
        is called once, or twice for the quantized form (a first pass finds
        each column's range for the decode table, the second encodes).
    Other arguments as :func:`write_params`.  Pieces that do not add up to
    ``count``, or of another width, raise :class:`ParamError` and leave no
    file (nor harm an existing one).
    """
    path = Path(path)
    count, width = int(count), int(width)
    if not is_record_width(width):
        raise ParamError(f"width: expected {describe_widths()} numbers per instance (10·K + 6 with K axes), found {width}")
    if mesh is not None:  # its axis, or its tree of several axes
        axis, mesh_fingerprint = AxisRecord.of(mesh), mesh.fingerprint
    name = str(path)

    def checked():
        done = 0
        for piece in pieces():
            piece = as_params(piece, name=name, widths=(width,), rows=_Rows(done))
            done += len(piece)
            if done > count:
                break
            yield piece
        if done != count:
            raise ParamError(f"{name}: the pieces hold {'at least ' if done > count else ''}{done} instances; expected {count}")

    binary = _output_kind(path, quantize)
    if binary:
        header = _binary_header(width, quantize, count, axis, mesh_fingerprint)
        table = b""
        if quantize:  # first pass: the decode table needs every column's range
            lo32, step32 = _quant_steps(*_quant_range(checked(), width))
            table = _quant_table(width).pack(*lo32.tolist(), *step32.tolist())
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            crc = zlib.crc32(header + table)
            fh.write(header + table)
            for piece in checked():  # the CRC-32 carried along: no copy of the whole payload
                data = (_quant_levels(piece, lo32, step32) if quantize else piece.astype("<f4")).tobytes()
                crc = zlib.crc32(data, crc)
                fh.write(data)
            fh.write(_TRAILER.pack(crc))
        return path
    text = "axialdeform parameters: " + ("unknown axis" if axis is None else axis.describe())
    if mesh is not None:
        text += f"\nbase mesh: {mesh.name} (sha256 {mesh.fingerprint.hex()})"
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(_text_header(width, text))
        for piece in checked():
            for lines in _text_body(piece):
                fh.write(lines)
    return path


def _output_kind(path: Path, quantize: bool) -> bool:
    """True if ``path`` names a binary parameter file, False for text; a
    :class:`ParamFileError` for another suffix, or text with ``quantize``."""
    binary = _is_binary_suffix(path)
    if not binary and path.suffix.lower() not in TEXT_SUFFIXES:
        raise ParamFileError(
            f"{path}: unknown parameter file type {path.suffix!r}; expected {', '.join(BINARY_SUFFIXES)} (binary) "
            f"or {', '.join(TEXT_SUFFIXES)} (text)"
        )
    if quantize and not binary:
        raise ParamFileError(f"{path}: the quantized form is binary only; expected a {'/'.join(BINARY_SUFFIXES)} file name")
    return binary


def param_file_bytes(path: str | os.PathLike, count: int, width: int = 16, *, quantize: bool = False) -> int:
    """Bytes a parameter file of ``count`` instances takes on disk: exact for
    the binary form; for text an upper bound (every number at its longest,
    ``%.9g`` of a float32: 15 characters and a separator, plus the header).
    The path's suffix picks the form (an unknown one is a :class:`ParamFileError`)."""
    count = int(count)
    if _output_kind(Path(path), quantize):
        record = _ENCODINGS[ENCODING_UINT16 if quantize else ENCODING_FLOAT32][1] * width // 16
        table = _quant_table(width).size if quantize else 0
        return HEADER_SIZE + table + count * record + _TRAILER.size
    return _TEXT_HEADER_MAX + count * 16 * width


#: the text header's bound in :func:`param_file_bytes` (field names, axis, mesh name, fingerprint)
_TEXT_HEADER_MAX = 8192


def axis_letter(index: int) -> str:
    return AXIS_NAMES[index]

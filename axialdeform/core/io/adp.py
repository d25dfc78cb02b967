"""The binary parameter file, ``.adp`` (``docs/parameter-files.md``): its header (magic, version,
encoding, count, the base mesh's axis and fingerprint), the float32 or uint16-quantized numbers and
the CRC-32 trailer -- encoded, and decoded with every field checked.  Reading and writing files:
:mod:`.params`."""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass

import numpy as np

from ..axis import AXIS_NAMES, ControlAxis
from ..errors import ParamError, ParamFileError
from ..params import as_params
from ..quantize import dequantize_params, quant_levels, quant_range, quant_steps
from ..record import (  # the record's columns and slices: one home
    MAX_RECORD_AXES,
    WIDTHS,
    tree_shape,
    tree_width,
)

__all__ = [
    "BINARY_SUFFIXES",
    "TEXT_SUFFIXES",
    "MAGIC",
    "VERSION",
    "VERSION_EXTENDED",
    "VERSION_TINTED",
    "ENCODING_FLOAT32",
    "ENCODING_UINT16",
    "ENCODINGS",
    "AXIS_FRAMED",
    "AXIS_TREE",
    "AxisRecord",
    "HEADER_SIZE",
    "TRAILER",
    "ParamFile",
    "quant_table",
    "encode_binary",
    "binary_header",
    "BinaryHeader",
    "read_binary_header",
    "decode_binary",
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


ENCODINGS = {ENCODING_FLOAT32: ("float32", 64), ENCODING_UINT16: ("uint16-quantized", 32)}


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
        tree = getattr(source, "tree", None)
        axis = getattr(source, "axis", source)
        legacy = tree.legacy_digest if tree is not None else getattr(axis, "legacy_frame_digest", other.frame_digest)
        return (self.index == other.index and self.frame_digest in (other.frame_digest, legacy) and self.axes == other.axes
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


TRAILER = struct.Struct("<I")


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


def quant_table(width: int) -> struct.Struct:
    table = _QUANT_TABLES.get(width)
    if table is None:  # several axes: 10·K + 6 (+ 3, + 6) columns
        table = _QUANT_TABLES[width] = struct.Struct(f"<{width}f{width}f")
    return table


def _quantize(values: np.ndarray) -> tuple[bytes, bytes]:
    lo32, step32 = quant_steps(*quant_range([values], values.shape[1]))
    return quant_table(values.shape[1]).pack(*lo32.tolist(), *step32.tolist()), quant_levels(values, lo32, step32).tobytes()


def _dequantize(table: bytes, payload: bytes, count: int, width: int = 16) -> np.ndarray:
    raw = quant_table(width).unpack(table)
    q = np.frombuffer(payload, dtype="<u2", count=count * width).reshape(count, width)
    return dequantize_params(np.array(raw[:width], dtype=np.float32), np.array(raw[width:], dtype=np.float32), q)


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
    header = binary_header(values.shape[1], quantize, len(values), axis, mesh_fingerprint)
    if quantize:
        table, payload = _quantize(values)
        body = header + table + payload
    else:
        body = header + values.astype("<f4").tobytes()  # 64 (76, 88) bytes per instance
    return body + TRAILER.pack(zlib.crc32(body))


def binary_header(width: int, quantize: bool, count: int, axis: ControlAxis | None,
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
        return ENCODINGS[self.encoding][0]

    @property
    def columns(self) -> int:
        """Numbers per instance: 16 (version 1), 19 (version 2, extended) or 22 (version 3, tinted);
        ``10·K + 6`` (``+ 3``, ``+ 6``) with K axes."""
        return tree_width(self.axes, self.version - 1)

    @property
    def payload_bytes(self) -> int:
        """Bytes of the instance records alone: the file less its header,
        decode table (quantized files) and checksum."""
        table = quant_table(self.columns).size if self.encoding == ENCODING_UINT16 else 0
        return self.size - HEADER_SIZE - table - TRAILER.size


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
    if total < HEADER_SIZE + TRAILER.size:
        raise ParamFileError(
            f"{name}: truncated: {total} bytes, expected at least {HEADER_SIZE + TRAILER.size} (header + checksum)"
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
    if encoding not in ENCODINGS:
        raise ParamFileError(f"{name}: encoding: expected 0 (float32) or 1 (uint16-quantized), found {encoding}")
    if header_size != HEADER_SIZE:
        raise ParamFileError(f"{name}: header size: expected {HEADER_SIZE}, found {header_size}")
    if axes > MAX_RECORD_AXES:
        raise ParamFileError(f"{name}: axes: expected 1 to {MAX_RECORD_AXES} axes, found {axes}")
    width = tree_width(axes, version - 1)
    record = ENCODINGS[encoding][1] * width // 16
    table = quant_table(width).size if encoding == ENCODING_UINT16 else 0
    expected = HEADER_SIZE + table + count * record + TRAILER.size  # Python int: no overflow
    if total != expected:
        raise ParamFileError(
            f"{name}: count: the header declares {count} instances ({expected} bytes), but the file has {total} bytes"
            + (" (truncated?)" if total < expected else "")
        )
    if size is not None:
        return None
    (stored,) = TRAILER.unpack_from(data, len(data) - TRAILER.size)
    computed = zlib.crc32(memoryview(data)[: len(data) - TRAILER.size])
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
    table = quant_table(width).size if encoding == ENCODING_UINT16 else 0
    stored, version = h.stored_crc, h.version
    axis = h.axis_record(name)
    payload = memoryview(data)[HEADER_SIZE + table : len(data) - TRAILER.size]
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

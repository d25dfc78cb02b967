"""Parameter files: binary ``.adp`` (float32 or uint16-quantized, CRC-32
checked) and text (:mod:`.params_text`), read through the bounded reader and
written atomically.  The quantization they share with the GPU buffer is
:mod:`axialdeform.core.quantize`.  The formats: ``docs/parameter-files.md``."""

from __future__ import annotations

import os
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..axis import AXIS_NAMES, ControlAxis
from ..errors import MeshMismatchError, ParamError, ParamFileError
from ..params import as_params
from ..quantize import dequantize_params, quant_levels, quant_range, quant_steps
from ..record import (  # the record's columns and slices: one home
    MAX_RECORD_AXES,
    WIDTHS,
    Instances,
    describe_widths,
    is_record_width,
    tree_shape,
    tree_width,
    tree_widths,
)
from . import safeio
from .atomic import atomic_path
from .params_text import format_text, parse_text, text_body, text_header
from .safeio import open_regular

__all__ = [
    "AXIS_FRAMED", "AxisRecord", "BINARY_SUFFIXES", "BinaryHeader", "ENCODING_FLOAT32", "ENCODING_UINT16",
    "HEADER_SIZE", "MAGIC", "ParamFile", "TEXT_SUFFIXES", "VERSION", "VERSION_EXTENDED", "VERSION_TINTED",
    "axis_letter", "check_mesh", "decode_binary", "encode_binary", "format_text", "param_file_bytes", "parse_text",
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


def _quant_table(width: int) -> struct.Struct:
    table = _QUANT_TABLES.get(width)
    if table is None:  # several axes: 10·K + 6 (+ 3, + 6) columns
        table = _QUANT_TABLES[width] = struct.Struct(f"<{width}f{width}f")
    return table


def _quantize(values: np.ndarray) -> tuple[bytes, bytes]:
    lo32, step32 = quant_steps(*quant_range([values], values.shape[1]))
    return _quant_table(values.shape[1]).pack(*lo32.tolist(), *step32.tolist()), quant_levels(values, lo32, step32).tobytes()


def _dequantize(table: bytes, payload: bytes, count: int, width: int = 16) -> np.ndarray:
    raw = _quant_table(width).unpack(table)
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
    """Read a parameter file (text or binary).

    Parameters
    ----------
    path : str or PathLike
    mesh : BaseMesh, optional
        If given and the file records the base mesh it was made for, a different mesh raises
        :class:`MeshMismatchError` ...
    allow_mesh_mismatch : bool
        ... unless this is true.

    Returns
    -------
    Instances
        ``(n, 16) float32`` (``(n, 19)``: extended; ``(n, 22)``: tinted; a K-axis record
        ``10·(K − 1)`` more).
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

    Parameters
    ----------
    path : str or PathLike
        ``.adp`` is binary (float32, or uint16 with ``quantize=True``); ``.txt``, ``.csv`` and
        ``.dat`` are text.
    values : (n, 16|19|22) float32
    mesh : BaseMesh, optional
        Records the axis and fingerprint of the base mesh in a binary file.
    quantize : bool
        The compact uint16 form (binary only).
    axis : ControlAxis, optional
        The axis to record when no mesh is given.
    mesh_fingerprint : bytes, optional
        The fingerprint to record when no mesh is given.

    Returns
    -------
    Path
        The file written, in pieces (:func:`write_param_chunks`): memory beyond ``values`` stays
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
            lo32, step32 = quant_steps(*quant_range(checked(), width))
            table = _quant_table(width).pack(*lo32.tolist(), *step32.tolist())
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            crc = zlib.crc32(header + table)
            fh.write(header + table)
            for piece in checked():  # the CRC-32 carried along: no copy of the whole payload
                data = (quant_levels(piece, lo32, step32) if quantize else piece.astype("<f4")).tobytes()
                crc = zlib.crc32(data, crc)
                fh.write(data)
            fh.write(_TRAILER.pack(crc))
        return path
    text = "axialdeform parameters: " + ("unknown axis" if axis is None else axis.describe())
    if mesh is not None:
        text += f"\nbase mesh: {mesh.name} (sha256 {mesh.fingerprint.hex()})"
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text_header(width, text))
        for piece in checked():
            for lines in text_body(piece):
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

"""Parameter files: binary ``.adp`` (float32 or uint16-quantized, CRC-32
checked) and text (:mod:`.params_text`), read through the bounded reader and
written atomically.  The quantization they share with the GPU buffer is
:mod:`axialdeform.core.quantize`.  The formats: ``docs/parameter-files.md``."""

from __future__ import annotations

import os
import zlib
from pathlib import Path

import numpy as np

from ..axis import AXIS_NAMES, ControlAxis
from ..errors import MeshMismatchError, ParamError, ParamFileError
from ..params import as_params
from ..quantize import quant_levels, quant_range, quant_steps
from ..record import (  # the record's columns and slices: one home
    WIDTH,
    Instances,
    describe_widths,
    is_record_width,
    tree_shape,
    tree_widths,
)
from . import safeio
from .adp import (
    AXIS_FRAMED,
    BINARY_SUFFIXES,
    ENCODING_FLOAT32,
    ENCODING_UINT16,
    ENCODINGS,
    HEADER_SIZE,
    MAGIC,
    TEXT_SUFFIXES,
    TRAILER,
    VERSION,
    VERSION_EXTENDED,
    VERSION_TINTED,
    AxisRecord,
    BinaryHeader,
    ParamFile,
    binary_header,
    decode_binary,
    encode_binary,
    quant_table,
    read_binary_header,
)
from .atomic import atomic_path
from .params_text import format_text, parse_text, text_body, text_header
from .safeio import open_regular

__all__ = [
    "AXIS_FRAMED", "AxisRecord", "BINARY_SUFFIXES", "BinaryHeader", "ENCODING_FLOAT32", "ENCODING_UINT16",
    "HEADER_SIZE", "MAGIC", "ParamFile", "TEXT_SUFFIXES", "VERSION", "VERSION_EXTENDED", "VERSION_TINTED",
    "axis_letter", "check_mesh", "decode_binary", "encode_binary", "format_text", "param_file_bytes", "parse_text",
    "read_binary_header", "read_param_bytes", "read_param_file", "read_params", "write_param_chunks", "write_params",
]


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
            f"expected {mesh.fingerprint.hex()[:16]} of {mesh.name}); load the mesh as it was made for: the same "
            "file and the same parts (parts= / --parts), or use the bundled mesh it names; or skip the check "
            "(allow_mesh_mismatch=True / --ignore-mesh-mismatch)"
        )
    if pf.axis is not None and not pf.axis.matches(mesh):
        raise MeshMismatchError(
            f"{name}: made for {pf.axis.describe()}, but {mesh.name} has {AxisRecord.of(mesh).describe()}; "
            "give the axis frame and the axes it was made with again (axis= and axes= / --axis and --axes, the same "
            "axes file), or skip the check (allow_mesh_mismatch=True / --ignore-mesh-mismatch)"
        )
    k = getattr(mesh, "axis_count", 1)
    if len(pf.values) and tree_shape(pf.values.shape[1])[0] != k:
        raise MeshMismatchError(
            f"{name}: {pf.values.shape[1]} numbers an instance ({tree_shape(pf.values.shape[1])[0]} axes), but "
            f"{mesh.name} has {k} axes; expected {describe_widths(tree_widths(k))} numbers an instance (load the mesh "
            f"with the axes it was made with: axes= / --axes, the same axes file)")


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
    width: int = WIDTH,
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
        header = binary_header(width, quantize, count, axis, mesh_fingerprint)
        table = b""
        if quantize:  # first pass: the decode table needs every column's range
            lo32, step32 = quant_steps(*quant_range(checked(), width))
            table = quant_table(width).pack(*lo32.tolist(), *step32.tolist())
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            crc = zlib.crc32(header + table)
            fh.write(header + table)
            for piece in checked():  # the CRC-32 carried along: no copy of the whole payload
                data = (quant_levels(piece, lo32, step32) if quantize else piece.astype("<f4")).tobytes()
                crc = zlib.crc32(data, crc)
                fh.write(data)
            fh.write(TRAILER.pack(crc))
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
        record = ENCODINGS[ENCODING_UINT16 if quantize else ENCODING_FLOAT32][1] * width // 16
        table = quant_table(width).size if quantize else 0
        return HEADER_SIZE + table + count * record + TRAILER.size
    return _TEXT_HEADER_MAX + count * 16 * width


#: the text header's bound in :func:`param_file_bytes` (field names, axis, mesh name, fingerprint)
_TEXT_HEADER_MAX = 8192


def axis_letter(index: int) -> str:
    return AXIS_NAMES[index]

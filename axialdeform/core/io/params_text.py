"""The text form of parameter files: one instance a line, numbers separated by spaces or commas,
``#`` comments (docs/parameter-files.md), parsed in bounded chunks with every bad token named by its
line and column."""

from __future__ import annotations

import io
import re
import warnings

import numpy as np

from ..errors import ParamError, ParamFileError
from ..params import as_params
from ..record import (  # the record's columns and slices: one home
    describe_widths,
    is_record_width,
    record_fields,
    tree_shape,
)

__all__ = ["format_text", "parse_text", "text_header", "text_body"]

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
    yield text_header(values.shape[1], header)
    yield from text_body(values)


def text_header(width: int, header: str | None) -> str:
    """The comment lines that start a text file: ``header``, then the field names."""
    lines = ["# " + line for line in (header or "").splitlines()]
    lines.append("# " + " ".join(record_fields(width)))
    return "\n".join(lines) + "\n"


def text_body(values: np.ndarray):
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

"""Safe input and output: the one home of the checks every reader and writer
of the library (and of its CLI) goes through.

* :func:`open_regular` / :func:`read_regular` — open a file that must be a
  regular file *without blocking* (``O_NONBLOCK``: a FIFO cannot hang the
  open), check it with ``fstat`` on the open descriptor (no race between the
  check and the read: a symlink to ``/dev/zero`` is refused, a folder too),
  and read at most ``max_bytes``.
* ``SafeResolver`` (:class:`axialdeform.core.material.SafeResolver`) — the
  trimesh resolver whose every read (glTF buffers and images, OBJ
  ``mtllib``, textures) goes through :func:`open_regular`, bounded by what
  the mesh declares (a buffer's ``byteLength``; :data:`MAX_IMAGE_BYTES` for
  a picture).
* :func:`check_output_path` — refuse an output that is the same file as an
  input, or that exists and is not a regular file (or folder, where one is
  allowed): a device, a FIFO, a socket, a symlink to one.
* :func:`check_count` — a count checked against memory before anything is
  allocated; the message says the maximum.
* :func:`check_disk_space` — an output's size checked against the free
  space of its file system before anything is written; the message says both.
* :func:`require_finite` — a computed result with a non-finite number is an
  error naming the instance and the field.
* :func:`quiet_numpy` — numpy floating-point warnings silenced (results are
  checked with :func:`require_finite` instead), for the CLI.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import warnings
from collections.abc import Iterable, Iterator, Sequence

import numpy as np

from ..errors import AxialDeformError, PathError

__all__ = [
    "open_regular", "read_regular", "read_sized", "check_output_path", "check_not_special", "check_new_outputs",
    "memory_available", "check_count", "disk_free", "check_disk_space", "require_finite", "quiet_numpy", "MAX_INSTANCES",
    "MAX_REFERENCED_BYTES", "MAX_IMAGE_BYTES", "format_gb"]

#: The largest instance count any command accepts (GL draws take a signed
#: 32-bit instance count); memory usually limits it earlier, see :func:`check_count`.
MAX_INSTANCES = 2**31 - 1
#: Bound on one file a mesh refers to that declares no size of its own (an
#: OBJ material library); a glTF buffer is bound by its ``byteLength``, a
#: picture by :data:`MAX_IMAGE_BYTES` (``core.material.SafeResolver``).
MAX_REFERENCED_BYTES = 2 * 1024**3
#: Bound on one picture a mesh refers to (a glTF image, an OBJ texture): a
#: 16384 x 16384 RGBA texture, the largest most GL drivers take, is 1 GiB
#: decoded; its compressed file is far smaller.  A larger file is not read
#: (the part is drawn with its base colour, ``AssetWarning``).
MAX_IMAGE_BYTES = 256 * 1024**2


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


@contextlib.contextmanager
def open_regular(path: str | os.PathLike, what: str = "file", error: type = PathError) -> Iterator[tuple[object, int]]:
    """Open ``path`` for reading only if it is a regular file; yield ``(file, size)``.

    The open is non-blocking (a FIFO with no writer does not hang), and the
    check is ``fstat`` on the opened descriptor, so it holds for what is
    actually read, whatever symlinks lead there.  Raises ``error`` (a
    :class:`PathError` by default) naming the file and ``what`` was expected.
    """
    name = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except FileNotFoundError:
        noun = what[2:] if what.startswith("a ") else what[3:] if what.startswith("an ") else what
        raise error(f"{name}: no such {noun}") from None
    except IsADirectoryError:
        raise error(f"{name}: is a folder; expected {what}") from None
    except OSError as exc:
        raise error(f"{name}: cannot open: {exc.strerror}; expected {what}") from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise error(f"{name}: is a folder; expected {what}")
        if not stat.S_ISREG(st.st_mode):
            raise error(f"{name}: not a regular file ({_kind(st.st_mode)}); expected {what}")
        if hasattr(os, "O_NONBLOCK"):
            os.set_blocking(fd, True)
        fh = os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
    with fh:
        yield fh, st.st_size


def read_regular(path: str | os.PathLike, max_bytes: int | None = None, what: str = "file",
                 error: type = PathError) -> bytearray:
    """All bytes of the regular file ``path``, refusing one over ``max_bytes``.

    ``max_bytes`` defaults to the memory available.  A file that grows while
    it is read is still cut at ``max_bytes + 1`` bytes and refused.
    """
    limit = memory_available() if max_bytes is None else int(max_bytes)
    with open_regular(path, what, error) as (fh, size):
        if size > limit:
            raise error(f"{path}: is {size} bytes; expected {what} of at most {limit} bytes")
        return read_sized(fh, size, path, what, error)


def read_sized(fh, size: int, path, what: str = "file", error: type = PathError) -> bytearray:
    """Read the whole of the open file ``fh`` from its start into ONE buffer of
    ``size`` bytes (what ``fstat`` said; no second copy is made), refusing a
    file that grew meanwhile."""
    buf = bytearray(size + 1)
    view = memoryview(buf)
    got = 0
    try:
        fh.seek(0)
        while got <= size:
            k = fh.readinto(view[got:])
            if not k:
                break
            got += k
    except OSError as exc:
        raise error(f"{path}: cannot read: {exc.strerror}") from None
    finally:
        view.release()
    if got > size:
        raise error(f"{path}: grew while being read (fstat said {size} bytes); expected {what} that is not being written")
    del buf[got:]
    return buf


def _same_file(a: os.stat_result, b: os.stat_result) -> bool:
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def check_not_special(path: str | os.PathLike, what: str = "output", allow_folder: bool = False) -> None:
    """Raise :class:`PathError` if ``path`` exists and is not a regular file
    (or a folder, with ``allow_folder``) — following symlinks, so a link to
    ``/dev/null`` or a FIFO is refused too; a dangling symlink is refused."""
    p = os.fspath(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        if os.path.islink(p):
            raise PathError(f"{p}: is a symlink to a missing file; expected a regular file or a new name for the {what}") from None
        return
    except OSError as exc:
        raise PathError(f"{p}: cannot inspect: {exc.strerror}") from None
    if stat.S_ISREG(st.st_mode) or (allow_folder and stat.S_ISDIR(st.st_mode)):
        return
    expected = "a regular file" + (" or a folder" if allow_folder else "")
    raise PathError(f"{p}: not a regular file ({_kind(st.st_mode)}); expected {expected} (or a new name) for the {what}")


def check_output_path(path: str | os.PathLike, inputs: Iterable = (), what: str = "output",
                      allow_folder: bool = False, overwrite: bool = True) -> None:
    """Refuse an output ``path`` that is the same file as one of ``inputs``
    (compared by device and inode, so links and ``..`` are seen through), or
    that exists and is not a regular file (or folder, with ``allow_folder``);
    without ``overwrite``, also a regular file that exists (the command
    line's one rule; checked after the inputs, so an input is named as one)."""
    check_not_special(path, what, allow_folder)
    try:
        out = os.stat(path)
    except OSError:
        return
    for src in inputs:
        if src is None:
            continue
        with contextlib.suppress(OSError):
            if _same_file(out, os.stat(src)):
                raise PathError(f"{path}: is the input file {src}; refusing to overwrite an input with the {what}")
    if not overwrite and stat.S_ISREG(out.st_mode):
        raise PathError(f"{path}: exists; refusing to replace it with the {what} (--overwrite replaces it)")


def check_new_outputs(paths, what: str = "output", overwrite: bool = False) -> None:
    """The command line's one rule for a set of outputs (a folder's files): without ``overwrite``,
    refuse in one line if any of ``paths`` is a file that exists, naming the first and counting
    the rest of ``what`` (``"the page's files"``)."""
    if overwrite:
        return
    there = [p for p in paths if os.path.isfile(p)]
    if there:
        more = f" and {len(there) - 1} more of {what}" if len(there) > 1 else ""
        raise PathError(f"{os.fspath(there[0])}: exists{more}; refusing to replace it (--overwrite replaces it)")


def memory_available() -> int:
    """Bytes of memory the system can give this process now (``MemAvailable``
    of ``/proc/meminfo``; elsewhere the free physical pages)."""
    with contextlib.suppress(OSError, ValueError):
        with open("/proc/meminfo", "rb") as fh:
            for line in fh:
                if line.startswith(b"MemAvailable:"):
                    return int(line.split()[1]) * 1024
    with contextlib.suppress(ValueError, OSError, AttributeError):
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    return 8 * 1024**3


def format_gb(n: float) -> str:
    return f"{n / 1024**3:.3g} GB" if n >= 1024**3 else f"{n / 1024**2:.3g} MB"


def check_count(count, bytes_each: float, what: str = "count", error: type = AxialDeformError,
                budget: int | None = None) -> int:
    """``count`` as an int if ``count * bytes_each`` fits in memory, else ``error``.

    The message says the largest count that fits now (and the absolute
    maximum :data:`MAX_INSTANCES`).  ``budget`` defaults to 80 % of
    :func:`memory_available`.
    """
    try:
        n = int(count)
        if n != count:
            raise ValueError
    except (TypeError, ValueError, OverflowError):
        raise error(f"{what}: expected a whole number of instances, found {count!r}") from None
    if n < 0:
        raise error(f"{what}: expected 0 or more instances, found {n}")
    budget = int(0.8 * memory_available()) if budget is None else int(budget)
    most = int(min(MAX_INSTANCES, budget // max(bytes_each, 1)))
    if n > most:
        need = n * bytes_each
        raise error(f"{what}: {n} instances need about {format_gb(need)}; expected at most {most} "
                    f"(what {format_gb(budget)} of available memory holds; never more than {MAX_INSTANCES})")
    return n


def disk_free(path: str | os.PathLike) -> int:
    """Bytes free for this user on the file system that ``path`` (a file to
    be written: its folder is asked) is on."""

    folder = os.path.dirname(os.path.abspath(os.fspath(path))) or "."
    return shutil.disk_usage(folder).free


def check_disk_space(path: str | os.PathLike, needed: int, what: str = "output", error: type = AxialDeformError,
                     free: int | None = None, expected=None) -> None:
    """Raise ``error`` before anything is written if the file system of
    ``path`` has fewer than ``needed`` bytes free (an atomic write needs the
    whole new file beside the old one); the message names the path, the
    bytes needed and the bytes free.  ``free`` defaults to :func:`disk_free`;
    ``expected(free)`` optionally says what fits instead (the message's end)."""
    try:
        free = disk_free(path) if free is None else int(free)
    except OSError as exc:  # the folder is missing or unreadable: the writer says so itself
        del exc
        return
    if needed > free:
        fits = expected(free) if expected is not None else f"at most {free} bytes"
        raise error(f"{os.fspath(path)}: the {what} needs {int(needed)} bytes ({format_gb(needed)}), but its file system has "
                    f"{free} bytes free ({format_gb(free)}); expected {fits}")


def require_finite(array: np.ndarray, what: str, fields: Sequence[str] | None = None, items: str = "instance",
                   error: type = AxialDeformError, source: str | None = None, first: int = 0) -> None:
    """Raise ``error`` if ``array`` holds a NaN or infinity, naming the first:
    its ``items`` index (axis 0), then the position in the remaining axes
    (``fields`` names the last axis), e.g. ``p.adp: instance 3, positions
    (vertex 5, y)``; ``source`` is the file the input came from.

    array : (n, ...) float — a computed result, checked before it is written.
    """
    a = np.asarray(array)
    if a.size == 0 or not np.issubdtype(a.dtype, np.floating):
        return
    # chunked so a huge result costs no second array of its size
    flat = a.reshape(len(a), -1) if a.ndim > 1 else a.reshape(-1, 1)
    step = max(1, (1 << 22) // max(flat.shape[1], 1))
    for s in range(0, len(flat), step):
        ok = np.isfinite(flat[s : s + step])
        if ok.all():
            continue
        row, col = (int(x) for x in np.argwhere(~ok)[0])
        row += s
        where = (f"{source}: " if source else "") + f"{items} {row + first}, {what}"
        if a.ndim > 1:
            idx = np.unravel_index(col, a.shape[1:])
            if fields is not None:
                parts = [str(i) for i in idx[:-1]] + [str(fields[idx[-1]])]
            else:
                parts = [str(i) for i in idx]
            if a.ndim == 3 and fields is not None:
                where += f" (vertex {parts[0]}, {parts[1]})"
            else:
                where += f" ({', '.join(parts)})"
        value = a[row][np.unravel_index(col, a.shape[1:])] if a.ndim > 1 else a[row]
        raise error(f"{where}: expected a finite number, found {value}; the parameters are too large for float32 "
                    "(see docs/reliability.md, safe ranges)")


@contextlib.contextmanager
def quiet_numpy() -> Iterator[None]:
    """numpy floating-point errors neither warn nor print (results are checked
    with :func:`require_finite` instead); for the CLI, whose promise is one line."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        yield

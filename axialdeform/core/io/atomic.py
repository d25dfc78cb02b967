"""Atomic writes: a write never leaves a half-written file where a good one
was.  Data goes to a temporary file in the destination's folder, is flushed
and fsynced, and only then renamed over the destination (``os.replace`` is
atomic on POSIX and Windows).

Temporary files are named ``.NAME.axtmpPID-XXXXXXXX[SUFFIX].part`` beside
the destination (``PID``: the writing process).  A writer killed mid-write
(SIGKILL, power loss) cannot clean up and leaves its ``.part`` file behind;
the first atomic write of a later process into the same folder removes every
``.part`` of this form whose writer is no longer running, so at most the
leftovers of writers killed since then exist at any time."""

from __future__ import annotations

import contextlib
import os
import re
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..errors import PathError
from .safeio import check_not_special

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_text", "sweep_stale_parts"]

_PART = re.compile(r"^\..*\.axtmp(\d+)-[^.]*.*\.part$")
_swept: set[str] = set()


def _default_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # exists (another user's) or unknown: keep its file
    return True


def sweep_stale_parts(folder: str | os.PathLike) -> list[Path]:
    """Remove the ``.part`` files of writers in ``folder`` that are no longer
    running; returns the paths removed.  Files of live processes are kept."""
    removed = []
    with contextlib.suppress(OSError):
        with os.scandir(folder) as entries:
            for entry in entries:
                m = _PART.match(entry.name)
                if m and not _alive(int(m.group(1))):
                    with contextlib.suppress(OSError):
                        os.unlink(entry.path)
                        removed.append(Path(entry.path))
    return removed


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path``.

    Use it with writers that want a file name (Pillow, numpy, trimesh)::

        with atomic_path("out.png") as tmp:
            image.save(tmp, format="PNG")

    ``suffix`` defaults to the destination's own suffix, so writers that pick
    a format from the name still see the right extension.  If the block
    raises, the temporary file is removed and ``path`` is left as it was.
    """

    path = Path(path)
    # a device, a FIFO or a symlink to one is never replaced by a regular file
    check_not_special(path, "output")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():  # say so in the user's words, not through the temporary file's name
        what = "is not a folder" if folder.exists() else "does not exist"
        raise PathError(f"{path}: its folder {folder} {what}; expected an existing folder for the output")
    key = os.path.abspath(folder)
    if key not in _swept:  # once per folder and process: cheap even for folders of many files
        _swept.add(key)
        sweep_stale_parts(folder)
    fd, tmp_name = tempfile.mkstemp(
        prefix=f".{path.name}.axtmp{os.getpid()}-", suffix=(path.suffix if suffix is None else suffix) + ".part",
        dir=folder,
    )
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        # flush the data to disk before the rename makes it visible
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        # mkstemp makes the file 0600: give it the mode a plain open() would
        # (the replaced file's, else 0666 less the umask)
        os.chmod(tmp, stat.S_IMODE(path.stat().st_mode) if path.exists() else _default_mode())
        os.replace(tmp, path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if exc.filename is None:  # disk full, quota: say which file could not be written
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
        raise
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))

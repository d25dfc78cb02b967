"""Baking: every instance's deformed world positions and normals, by the CPU
reference or the GPU capture, to an ``.npz`` or a folder of mesh files."""

from __future__ import annotations

import contextlib
import os
import re
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .deform import deform
from .errors import AxialDeformError, PathError
from .safeio import check_count, check_not_special, require_finite

__all__ = ["bake", "write_npz", "write_mesh_folder", "check_bake_folder", "ENGINES", "MESH_FORMATS"]

ENGINES = ("cpu", "gpu")
MESH_FORMATS = ("obj", "ply", "glb")


def bake(mesh, params, engine: str = "cpu", *, ctx=None, progress=None,
         source: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Deformed world positions and normals, each ``(instances, vertices, 3) float32``,
    in the base mesh's vertex order.  ``engine`` is ``"cpu"`` (numpy reference)
    or ``"gpu"`` (transform feedback of the drawing vertex shader).
    ``progress``: optional object with ``update(instances_done)`` (a tqdm bar).

    A non-finite result (finite parameters so large that float32 overflows)
    raises :class:`AxialDeformError` naming the instance, array, vertex and
    coordinate (and ``source``, the parameter file): nothing non-finite is
    ever returned to be written."""
    # the result is two (n, v, 3) float32 arrays (the GPU capture holds a
    # third copy while it splits them): refused before anything is allocated
    check_count(len(params), mesh.vertex_count * 12 * (4 if engine == "gpu" else 2.2),
                f"{source + ': ' if source else ''}instances to bake ({mesh.vertex_count} vertices each)")
    positions, normals = _bake(mesh, params, engine, ctx=ctx, progress=progress)
    require_finite(positions, "positions", "xyz", source=source)
    require_finite(normals, "normals", "xyz", source=source)
    return positions, normals


def _bake(mesh, params, engine, *, ctx=None, progress=None):
    if engine == "cpu":
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused by the caller
            return deform(mesh.axis, mesh.positions, mesh.normals, params, progress=progress)
    if engine != "gpu":
        raise AxialDeformError(f"engine: expected one of {', '.join(ENGINES)}, found {engine!r}")
    from ..gl.context import create_context
    from ..gl.renderer import AxialRenderer

    own = ctx is None
    ctx = create_context() if own else ctx
    try:
        with AxialRenderer(ctx, mesh, params) as r:
            return r.capture(progress=progress, check_finite=False)
    finally:
        if own:
            ctx.release()


def write_npz(path: str | os.PathLike, positions: np.ndarray, normals: np.ndarray) -> None:
    """``positions`` and ``normals`` arrays into one ``.npz``, atomically."""
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, positions=positions.astype(np.float32), normals=normals.astype(np.float32))


#: the file names :func:`write_mesh_folder` writes, and recognises as its own
INSTANCE_FILE = re.compile(r"^instance_(\d{6,})\.(" + "|".join(MESH_FORMATS) + r")$")


def write_mesh_folder(folder: str | os.PathLike, mesh, positions, normals, fmt: str = "obj", progress=None,
                      *, overwrite: bool = False) -> list[Path]:
    """One mesh file per instance (``instance_000000.obj`` …), each written atomically.

    ``folder`` must be new or empty (hidden files aside); a folder that holds
    anything else is refused, unless ``overwrite``: then every new file is
    written first (atomically), and only afterwards are the old instance files
    it recognises (``instance_NNNNNN.obj|ply|glb``) that were not just
    rewritten removed; other files are left alone.  So an interrupted
    overwrite leaves every old or new file whole, never a half-written one.
    """
    if fmt not in MESH_FORMATS:
        raise AxialDeformError(f"format: expected one of {', '.join(MESH_FORMATS)}, found {fmt!r}")
    folder = Path(folder)
    old = check_bake_folder(folder, overwrite)
    folder.mkdir(parents=True, exist_ok=True)
    digits = max(6, len(str(max(len(positions) - 1, 0))))
    written = []
    for i in range(len(positions)):  # one file per instance: file I/O, not maths
        path = folder / f"instance_{i:0{digits}d}.{fmt}"
        tm = mesh.to_trimesh(positions[i], normals[i])
        with atomic_path(path) as tmp:
            tm.export(str(tmp), file_type=fmt)
        written.append(path)
        if progress is not None:
            progress.update(1)
    if overwrite:
        keep = {p.name for p in written}
        for name in old:
            if name not in keep and INSTANCE_FILE.match(name):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(folder / name)
    return written


def check_bake_folder(folder: str | os.PathLike, overwrite: bool = False) -> list[str]:
    """Check ``folder`` as the target of :func:`write_mesh_folder` before any
    work: it must be new, empty (hidden files aside), or — with
    ``overwrite`` — anything; never a file, a device or a FIFO.  Returns the
    names it holds now.  Changes nothing."""
    folder = Path(folder)
    check_not_special(folder, "output folder", allow_folder=True)
    if folder.exists() and not folder.is_dir():
        raise PathError(f"{folder}: exists and is not a folder; expected a folder for one mesh file per instance")
    old = _folder_entries(folder)
    if old and not overwrite:
        sample = ", ".join(sorted(old)[:3]) + (", ..." if len(old) > 3 else "")
        raise PathError(f"{folder}: holds {len(old)} files it did not just write ({sample}); expected a new or empty "
                        "folder (--overwrite replaces an earlier bake: it removes the old instance_* files)")
    return old


def _folder_entries(folder: Path) -> list[str]:
    """Names in ``folder`` other than hidden ones (atomic writes' ``.part`` files)."""
    try:
        with os.scandir(folder) as it:
            return [e.name for e in it if not e.name.startswith(".")]
    except FileNotFoundError:
        return []
    except OSError as exc:
        raise PathError(f"{folder}: cannot list: {exc.strerror}") from None

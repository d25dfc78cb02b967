"""Baking: every instance's deformed world positions and normals, by the CPU
reference or the GPU capture, to an ``.npz`` or a folder of mesh files."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .deform import deform
from .errors import AxialDeformError

__all__ = ["bake", "write_npz", "write_mesh_folder", "ENGINES", "MESH_FORMATS"]

ENGINES = ("cpu", "gpu")
MESH_FORMATS = ("obj", "ply", "glb")


def bake(mesh, params, engine: str = "cpu", *, ctx=None, progress=None, wind=None,
         time: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Deformed world positions and normals, each ``(instances, vertices, 3) float32``,
    in the base mesh's vertex order.  ``engine`` is ``"cpu"`` (numpy reference)
    or ``"gpu"`` (transform feedback of the drawing vertex shader).
    ``params``: (n, 16) or (n, 19) (extended instances).
    ``wind``: an :class:`axialdeform.Wind` taken at ``time`` seconds (or None).
    ``progress``: optional object with ``update(instances_done)`` (a tqdm bar)."""
    if engine == "cpu":
        from .wind import apply_wind

        if wind is not None:
            params = apply_wind(wind, mesh.axis, params, time)
        return deform(mesh.axis, mesh.positions, mesh.normals, params, progress=progress)
    if engine != "gpu":
        raise AxialDeformError(f"engine: expected one of {', '.join(ENGINES)}, found {engine!r}")
    from ..gl.context import create_context
    from ..gl.renderer import AxialRenderer

    own = ctx is None
    ctx = create_context() if own else ctx
    try:
        with AxialRenderer(ctx, mesh, params, wind=wind) as r:
            return r.capture(progress=progress, time=time)
    finally:
        if own:
            ctx.release()


def write_npz(path: str | os.PathLike, positions: np.ndarray, normals: np.ndarray) -> None:
    """``positions`` and ``normals`` arrays into one ``.npz``, atomically."""
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, positions=positions.astype(np.float32), normals=normals.astype(np.float32))


def write_mesh_folder(folder: str | os.PathLike, mesh, positions, normals, fmt: str = "obj", progress=None) -> list[Path]:
    """One mesh file per instance (``instance_000000.obj`` …), each written atomically."""
    if fmt not in MESH_FORMATS:
        raise AxialDeformError(f"format: expected one of {', '.join(MESH_FORMATS)}, found {fmt!r}")
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise AxialDeformError(f"{folder}: exists and is not a folder")
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
    return written

"""Baking: every instance's deformed world positions and normals, by the CPU
reference (the GPU capture: :mod:`axialdeform.gl.bake`), to an ``.npz`` or a
folder of mesh files."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .deform import deform
from .errors import ArgumentError, AxialDeformError

__all__ = ["bake_cpu", "instance_name", "write_npz", "write_scene_npz", "write_mesh_folder", "MESH_FORMATS"]

MESH_FORMATS = ("obj", "ply", "glb")


def bake_cpu(mesh, params, *, progress=None, wind=None, time: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Deformed world positions and normals, each ``(instances, vertices, 3) float32``,
    in the base mesh's vertex order, by the numpy reference (:func:`deform`).
    ``params``: (n, 16) or (n, 19) (extended instances); ``wind``: an
    :class:`axialdeform.Wind` taken at ``time`` seconds (or None).
    ``progress``: optional object with ``update(instances_done)``.  The GPU
    engine and the switch between them: :func:`axialdeform.gl.bake.bake`."""
    if wind is not None:
        from .wind import apply_wind

        params = apply_wind(wind, mesh.axis, params, time)
    return deform(mesh.axis, mesh.positions, mesh.normals, params, progress=progress)


def instance_name(i: int, count: int = 0, suffix: str = "") -> str:
    """The name of instance ``i`` of ``count`` wherever instances are files or
    glTF nodes: ``instance_000012`` + ``suffix`` (e.g. ``".obj"``), zero-padded
    to 6 digits or to as many as ``count - 1`` needs, so names sort in order."""
    digits = max(6, len(str(max(int(count) - 1, 0))))
    return f"instance_{int(i):0{digits}d}{suffix}"


def write_npz(path: str | os.PathLike, positions: np.ndarray, normals: np.ndarray) -> None:
    """``positions`` and ``normals`` arrays into one ``.npz``, atomically."""
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, positions=positions.astype(np.float32), normals=normals.astype(np.float32))


def write_scene_npz(path: str | os.PathLike, layers: dict) -> None:
    """Several layers into one ``.npz``, atomically: ``{name: (positions, normals)}``
    becomes arrays ``positions_NAME`` and ``normals_NAME``, each (instances, vertices, 3) float32."""
    arrays = {}
    for name, (positions, normals) in layers.items():
        arrays[f"positions_{name}"] = np.asarray(positions, dtype=np.float32)
        arrays[f"normals_{name}"] = np.asarray(normals, dtype=np.float32)
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)


def write_mesh_folder(folder: str | os.PathLike, mesh, positions, normals, fmt: str = "obj", progress=None) -> list[Path]:
    """One mesh file per instance (``instance_000000.obj`` …), each written atomically."""
    if fmt not in MESH_FORMATS:
        raise ArgumentError(f"format: expected one of {', '.join(MESH_FORMATS)}, found {fmt!r}")
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise AxialDeformError(f"{folder}: exists and is not a folder")
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for i in range(len(positions)):  # one file per instance: file I/O, not maths
        path = folder / instance_name(i, len(positions), f".{fmt}")
        tm = mesh.to_trimesh(positions[i], normals[i])
        with atomic_path(path) as tmp:
            tm.export(str(tmp), file_type=fmt)
        written.append(path)
        if progress is not None:
            progress.update(1)
    return written

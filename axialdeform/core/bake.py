"""Baking: every instance's deformed world positions and normals, by the CPU
reference (or an engine passed in, such as the GPU capture of
:mod:`axialdeform.gl.capture`), to an ``.npz`` or a folder of mesh files."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .deform import deform
from .errors import AxialDeformError, ArgumentError

__all__ = ["bake", "write_npz", "write_mesh_folder", "instance_name", "ENGINES", "MESH_FORMATS"]

#: names of the engines ``axialdeform bake --engine`` offers (``"gpu"``: :func:`axialdeform.gl.capture.bake_gpu`)
ENGINES = ("cpu", "gpu")
MESH_FORMATS = ("obj", "ply", "glb")


def bake(mesh, params, engine="cpu", *, progress=None, **engine_options) -> tuple[np.ndarray, np.ndarray]:
    """Deformed world positions and normals, each ``(instances, vertices, 3) float32``,
    in the base mesh's vertex order.

    engine : ``"cpu"`` or a callable
        ``"cpu"``: the numpy reference (:func:`axialdeform.core.deform.deform`).
        A callable ``engine(mesh, params, progress=..., **engine_options)``
        does the work instead, e.g. the GPU capture
        :func:`axialdeform.gl.capture.bake_gpu` (``ctx=`` is one of its options).
    progress : optional object with ``update(instances_done)`` (a tqdm bar).
    """
    if callable(engine):
        return engine(mesh, params, progress=progress, **engine_options)
    if engine != "cpu":
        hint = " (the GPU engine is axialdeform.gl.capture.bake_gpu: pass it as engine=)" if engine == "gpu" else ""
        raise ArgumentError(f"engine: expected 'cpu' or a callable, found {engine!r}{hint}")
    if engine_options:
        raise ArgumentError(f"engine 'cpu' takes no options, found {', '.join(sorted(engine_options))}")
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

"""Baking: every instance's deformed world positions and normals, by the CPU
reference (the GPU capture: :mod:`axialdeform.gl.bake`), to an ``.npz`` or a
folder of mesh files."""

from __future__ import annotations

import re

import numpy as np

from .deform import deform
from .io.safeio import check_count, require_finite
from .params import check_tree_params
from .wind import apply_wind

__all__ = ['bake_cpu', 'bake_cpu_pieces', 'instance_name', 'part_file_names', 'check_bake_count', 'check_bake_result', 'MESH_FORMATS']

MESH_FORMATS = ("obj", "ply", "glb")


def bake_cpu(mesh, params, *, progress=None, wind=None, time: float = 0.0,
             source: str | None = None, position_ids: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Deformed world positions and normals, each ``(instances, vertices, 3) float32``,
    in the base mesh's vertex order, by the numpy reference (:func:`deform`).
    ``params``: (n, 16) or (n, 19) (extended instances); ``wind``: an
    :class:`axialdeform.Wind` taken at ``time`` seconds (or None).
    ``position_ids``: the wind's phases hash where the instances stand (a generated layer's:
    :func:`~axialdeform.core.wind.position_ids`), not their index.
    ``progress``: optional object with ``update(instances_done)``.  The GPU
    engine and the switch between them: :func:`axialdeform.gl.bake.bake`.

    The count is checked against memory first (:func:`check_bake_count`) and
    a non-finite result (finite parameters so large that float32 overflows)
    raises :class:`AxialDeformError` naming ``source`` (the parameter file),
    the instance, array, vertex and coordinate (:func:`check_bake_result`):
    nothing non-finite is ever returned to be written."""
    check_bake_count(mesh, len(params), "cpu", source)
    if wind is not None:

        params = apply_wind(wind, mesh.tree or mesh.axis, params, time,  # several axes: every axis sways
                            ids="position" if position_ids else "index")
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused just below
        positions, normals = deform(mesh, params, progress=progress)
    check_bake_result(positions, normals, source)
    return positions, normals


def check_bake_count(mesh, count: int, engine: str = "cpu", source: str | None = None) -> None:
    """Refuse ``count`` instances whose baked result cannot fit in memory: two
    ``(n, v, 3)`` float32 arrays (the GPU capture holds a third copy while it
    splits them), checked before anything is allocated."""
    check_count(count, mesh.vertex_count * 12 * (4 if engine == "gpu" else 2.2),
                f"{source + ': ' if source else ''}instances to bake ({mesh.vertex_count} vertices each)")


def check_bake_result(positions, normals, source: str | None = None) -> None:
    """Raise :class:`AxialDeformError` if a baked result holds a NaN or infinity."""
    require_finite(positions, "positions", "xyz", source=source)
    require_finite(normals, "normals", "xyz", source=source)


def instance_name(i: int, count: int = 0, suffix: str = "", part: str | None = None) -> str:
    """The name of instance ``i`` of ``count`` wherever instances are files or
    glTF nodes: ``instance_000012`` + ``suffix`` (e.g. ``".obj"``), zero-padded
    to 6 digits or to as many as ``count - 1`` needs, so names sort in order.
    ``part``: one part of a multi-part mesh in its own file,
    ``instance_000012_PART.ply`` (:func:`part_file_names` makes ``PART``
    safe for a file name)."""
    digits = max(6, len(str(max(int(count) - 1, 0))))
    middle = "" if part is None else f"_{part}"
    return f"instance_{int(i):0{digits}d}{middle}{suffix}"


def part_file_names(parts) -> list[str]:
    """For each :class:`~axialdeform.core.material.Part`, its name as it goes
    into a file name: letters, digits, ``-`` and ``_`` kept, anything else
    ``_``; names that then repeat get ``-1``, ``-2`` … so each is unique."""
    out: list[str] = []
    for p in parts:
        base = re.sub(r"[^A-Za-z0-9_-]", "_", str(p.name)) or "part"
        name, k = base, 0
        while name in out:
            k += 1
            name = f"{base}-{k}"
        out.append(name)
    return out


#: bytes of baked output (positions and normals) made at a time by :func:`bake_cpu_pieces`
BAKE_PIECE_BYTES = 1 << 23


def bake_cpu_pieces(mesh, params, *, progress=None, wind=None, time: float = 0.0, source: str | None = None,
                    piece_bytes: int = BAKE_PIECE_BYTES, position_ids: bool = False):
    """The result of :func:`bake_cpu` in pieces of consecutive instances, a
    generator of ``(positions, normals)``, each ``(m, vertices, 3) float32``
    with ``m * vertices * 24 <= piece_bytes`` (at least one instance):
    concatenated they are exactly ``bake_cpu``'s arrays, but memory holds one
    piece.  Each piece is checked for non-finite numbers as it is made (the
    message numbers the instance in the whole file)."""

    params = check_tree_params(params, mesh.axis_count)
    v = max(mesh.vertex_count, 1)
    step = max(1, int(piece_bytes) // (v * 24))
    for a in range(0, len(params), step):
        block = params[a : a + step]
        if wind is not None:  # the wind's phase follows the instance index (or where it stands)
            block = apply_wind(wind, mesh.tree or mesh.axis, block, time, start=a,
                               ids="position" if position_ids else "index")
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused just below
            positions, normals = deform(mesh, block, progress=progress)
        require_finite(positions, "positions", "xyz", source=source, first=a)
        require_finite(normals, "normals", "xyz", source=source, first=a)
        yield positions, normals



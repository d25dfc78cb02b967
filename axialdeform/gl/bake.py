"""Baking by either engine: the numpy reference (:func:`axialdeform.core.bake.bake_cpu`)
or the GPU (transform feedback of the drawing vertex shader, :meth:`AxialRenderer.capture`)."""

from __future__ import annotations

import numpy as np

from ..core.bake import (
    BAKE_PIECE_BYTES,
    bake_cpu,
    bake_cpu_pieces,
    check_bake_count,
    check_bake_result,
)
from ..core.errors import ArgumentError
from ..core.io.safeio import require_finite
from ..core.options import RenderOptions
from .context import create_context
from .renderer import AxialRenderer

__all__ = ["bake", "bake_pieces", "ENGINES"]

ENGINES = ("cpu", "gpu")


def bake(mesh, params, engine: str = "cpu", *, ctx=None, progress=None, source: str | None = None,
         options: RenderOptions | None = None, **fields) -> tuple[np.ndarray, np.ndarray]:
    """Every instance bent and placed: world positions and normals in the base mesh's vertex order.

    Parameters
    ----------
    mesh : BaseMesh
    params : (n, 16|19|22) float32
        The instances (a K-axis mesh: ``10·(K − 1)`` more numbers each).
    engine : {"cpu", "gpu"}
        The numpy reference, or transform feedback of the drawing vertex shader (in ``ctx``, or in
        a context made and released here).
    ctx : moderngl.Context, optional
    progress : object, optional
        With ``update(instances_done)`` (a tqdm bar).
    source : str, optional
        The parameter file, named in errors.
    options : RenderOptions, optional
        Its ``wind`` (an :class:`axialdeform.Wind`) taken at its ``time`` seconds, and its
        ``position_ids`` (the wind's phases hash where the instances stand: a generated layer's).
    **fields
        Deprecated (still working for one release, with a DeprecationWarning): ``wind=``, ``time=``
        and ``position_ids=`` as keywords.

    Returns
    -------
    positions, normals : (n, v, 3) float32
        Counts that cannot fit in memory and non-finite results are refused, naming ``source``
        (:func:`~axialdeform.core.bake.bake_cpu`).
    """
    opts = RenderOptions.of(options, fields, "bake", ("wind", "time", "position_ids"))
    wind, time, position_ids = opts.wind, opts.time or 0.0, opts.position_ids
    if engine == "cpu":
        return bake_cpu(mesh, params, progress=progress, wind=wind, time=time, source=source, position_ids=position_ids)
    if engine != "gpu":
        raise ArgumentError(f"engine: expected one of {', '.join(ENGINES)}, found {engine!r}")

    check_bake_count(mesh, len(params), "gpu", source)
    own = ctx is None
    ctx = create_context() if own else ctx
    try:
        with AxialRenderer(ctx, mesh, params, options=RenderOptions(wind=wind, position_ids=position_ids)) as r:
            positions, normals = r.capture(progress=progress, time=time, check_finite=False)
    finally:
        if own:
            ctx.release()
    check_bake_result(positions, normals, source)  # named after the file, not just the instance
    return positions, normals


def bake_pieces(mesh, params, engine: str = "cpu", *, ctx=None, progress=None, source: str | None = None,
                piece_bytes: int = BAKE_PIECE_BYTES, options: RenderOptions | None = None, **fields):
    """The result of :func:`bake` in pieces of consecutive instances, a
    generator of ``(positions, normals)``, each ``(m, vertices, 3) float32``
    of at most ``piece_bytes`` together (at least one instance):
    concatenated they are :func:`bake`'s arrays, but memory holds one piece
    (the GPU holds the parameters; each piece is one :meth:`capture` of
    ``start, count``, so the wind's phase follows the instance index).
    Non-finite results are refused as they come, naming ``source`` and the
    instance in the whole file.  ``options`` and ``fields`` as :func:`bake`'s."""
    opts = RenderOptions.of(options, fields, "bake_pieces", ("wind", "time", "position_ids"))
    wind, time, position_ids = opts.wind, opts.time or 0.0, opts.position_ids
    if engine == "cpu":
        yield from bake_cpu_pieces(mesh, params, progress=progress, wind=wind, time=time, source=source,
                                   piece_bytes=piece_bytes, position_ids=position_ids)
        return
    if engine != "gpu":
        raise ArgumentError(f"engine: expected one of {', '.join(ENGINES)}, found {engine!r}")

    step = max(1, int(piece_bytes) // (max(mesh.vertex_count, 1) * 24))
    own = ctx is None
    ctx = create_context() if own else ctx
    try:
        with AxialRenderer(ctx, mesh, params, options=RenderOptions(wind=wind, position_ids=position_ids)) as r:
            for a in range(0, r.count, step):
                m = min(step, r.count - a)
                positions, normals = r.capture(a, m, progress=progress, time=time, check_finite=False)
                require_finite(positions, "positions", "xyz", source=source, first=a)
                require_finite(normals, "normals", "xyz", source=source, first=a)
                yield positions, normals
                del positions, normals
    finally:
        if own:
            ctx.release()

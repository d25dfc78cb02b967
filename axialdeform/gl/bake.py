"""Baking by either engine: the numpy reference (:func:`axialdeform.core.bake.bake_cpu`)
or the GPU (transform feedback of the drawing vertex shader, :meth:`AxialRenderer.capture`)."""

from __future__ import annotations

import numpy as np

from ..core.bake import bake_cpu, check_bake_count, check_bake_result
from ..core.errors import ArgumentError

__all__ = ["bake", "ENGINES"]

ENGINES = ("cpu", "gpu")


def bake(mesh, params, engine: str = "cpu", *, ctx=None, progress=None, wind=None,
         time: float = 0.0, source: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Deformed world positions and normals, each ``(instances, vertices, 3) float32``,
    in the base mesh's vertex order.  ``engine`` is ``"cpu"`` (numpy reference)
    or ``"gpu"`` (transform feedback of the drawing vertex shader; in ``ctx``,
    or in a context made and released here).
    ``params``: (n, 16) or (n, 19) (extended instances).
    ``wind``: an :class:`axialdeform.Wind` taken at ``time`` seconds (or None).
    ``progress``: optional object with ``update(instances_done)`` (a tqdm bar).
    Counts that cannot fit in memory and non-finite results are refused,
    naming ``source`` (the parameter file): see :func:`~axialdeform.core.bake.bake_cpu`."""
    if engine == "cpu":
        return bake_cpu(mesh, params, progress=progress, wind=wind, time=time, source=source)
    if engine != "gpu":
        raise ArgumentError(f"engine: expected one of {', '.join(ENGINES)}, found {engine!r}")
    from .context import create_context
    from .renderer import AxialRenderer

    check_bake_count(mesh, len(params), "gpu", source)
    own = ctx is None
    ctx = create_context() if own else ctx
    try:
        with AxialRenderer(ctx, mesh, params, wind=wind) as r:
            positions, normals = r.capture(progress=progress, time=time, check_finite=False)
    finally:
        if own:
            ctx.release()
    check_bake_result(positions, normals, source)  # named after the file, not just the instance
    return positions, normals

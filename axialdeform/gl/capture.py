"""The GPU bake engine: every instance's world positions and normals as the
drawing vertex shader computes them (transform feedback through
:class:`~axialdeform.gl.renderer.AxialRenderer`)::

    from axialdeform.gl.capture import bake_gpu
    positions, normals = bake_gpu(mesh, params)               # own context
    positions, normals = ad.bake(mesh, params, engine=bake_gpu, ctx=ctx)
"""

from __future__ import annotations

import numpy as np

from .context import create_context
from .renderer import AxialRenderer

__all__ = ["bake_gpu"]


def bake_gpu(mesh, params, ctx=None, progress=None) -> tuple[np.ndarray, np.ndarray]:
    """Deformed world positions and normals, each ``(instances, vertices, 3) float32``,
    in the base mesh's vertex order, captured from the GPU.

    ctx : moderngl.Context or None
        The context to use; ``None`` makes (and releases) one of its own.
    progress : optional object with ``update(instances_done)`` (a tqdm bar).
    """
    own = ctx is None
    ctx = create_context() if own else ctx
    try:
        with AxialRenderer(ctx, mesh, params) as r:
            return r.capture(progress=progress)
    finally:
        if own:
            ctx.release()

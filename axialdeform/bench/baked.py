"""Baked meshes drawn one draw call each: the benchmark's "loaded" method
(every instance a mesh of its own, as a program without the axial shader
draws them)."""

from __future__ import annotations

import contextlib

import moderngl
import numpy as np

from ..core.errors import AxialDeformError
from ..core.options import RenderOptions
from ..gl.buffers import MeshBuffers
from ..gl.context import draw_in_batches
from ..gl.renderer import MODE_INDEX, MODES, AxialRenderer

__all__ = ["BakedMeshes"]


class BakedMeshes:
    """Meshes that are already deformed (``axialdeform bake`` output, or any
    mesh files), each with its own vertex and index buffers and vertex
    array, drawn one draw call each with the shading, uniforms and face
    culling of an un-bent :class:`AxialRenderer` -- the thesis's "load every
    one" method, drawn exactly like the instanced methods.

    Parameters
    ----------
    ctx : moderngl.Context
    like : BaseMesh
        A mesh whose name picks the colour and whose :attr:`BaseMesh.is_volume`
        decides back-face culling (the base mesh the files were baked from).
    mode : str
        One of :data:`MODES`; only the index buffers this mode draws are made.
    """

    def __init__(self, ctx, like, mode: str = "solid", *, cull_back_faces: bool | None = None):
        if mode not in MODE_INDEX:
            raise AxialDeformError(f"render mode: expected one of {', '.join(MODES)}, found {mode!r}")
        self.ctx = ctx
        self.mode = mode
        self._items = []  # (MeshBuffers, vao, index count)
        self._released = False
        self.renderer = AxialRenderer(ctx, like, np.zeros((0, 16), np.float32),
                                      RenderOptions(bend=False, cull_back_faces=cull_back_faces))
        self.cull_back_faces = self.renderer.cull_back_faces

    def __len__(self) -> int:
        return len(self._items)

    def add(self, mesh) -> None:
        """Upload one deformed mesh (world positions and normals as they are)."""
        if self._released:
            raise AxialDeformError("these BakedMeshes were released; create new ones")
        wire = self.mode == "wireframe"
        buffers = MeshBuffers(self.ctx, mesh, indices=("edges",) if wire else ("triangles",))
        try:
            program = self.renderer.program
            vao = self.ctx.vertex_array(program, [buffers.content(program)],
                                        index_buffer=buffers.edges if wire else buffers.triangles,
                                        index_element_size=4)
        except BaseException:
            buffers.release()
            raise
        self._items.append((buffers, vao, buffers.edge_indices if wire else buffers.triangle_indices))

    def render(self, view, projection, look=None) -> None:
        """Draw every mesh into the bound framebuffer (one draw call each)."""

        self.renderer.render(view, projection, self.mode, look=look)  # no instances: sets the uniforms only
        self.ctx.enable(moderngl.DEPTH_TEST)
        wire = self.mode == "wireframe"
        primitive = moderngl.LINES if wire else moderngl.TRIANGLES
        with (contextlib.nullcontext() if wire else self.renderer.culling(view, projection)):
            for _, vao, n in self._items:
                draw_in_batches(self.ctx, lambda count, first, vao=vao: vao.render(primitive, vertices=count, first=first),
                                n, 0, 2 if wire else 3, 1)

    def release(self) -> None:
        """Free every GL object; safe to call twice."""
        if self._released:
            return
        self._released = True
        for buffers, vao, _ in self._items:
            vao.release()
            buffers.release()
        self._items.clear()
        self.renderer.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

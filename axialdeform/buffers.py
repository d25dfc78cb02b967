"""Step 4 of the data flow: GPU buffers.

* :class:`MeshBuffers` — the base mesh once: interleaved position + normal
  (24 bytes a vertex), triangle indices and edge indices (for wireframe).
* :class:`InstanceBuffer` — the 16 numbers of every instance in ONE buffer,
  read with divisor 1 (64 bytes an instance); replacing all of it or a slice
  writes in place while the count is unchanged.

Both hold their ``ctx``; ``release()`` is safe to call twice and nothing is
released from ``__del__``.
"""

from __future__ import annotations

import numpy as np

from .errors import ParamError
from .params import as_params

__all__ = ["MeshBuffers", "InstanceBuffer", "INSTANCE_FORMAT", "INSTANCE_ATTRIBUTES", "RECORD_BYTES"]

#: layout of one instance record in the instanced attribute buffer
INSTANCE_FORMAT = ("4f", "4f", "2f", "3f", "3f")
INSTANCE_ATTRIBUTES = ("i_d12", "i_d34", "i_d5", "i_position", "i_angles")
RECORD_BYTES = 64


def _content(buffer, formats, names, program, per_instance=False):
    """A vertex-array content tuple; attributes the program does not use
    (the linker removed them) become padding so moderngl accepts it."""
    fmt = []
    used = []
    for f, name in zip(formats, names):
        if name in program:
            fmt.append(f)
            used.append(name)
        else:
            fmt.append(f"{int(f[0]) * 4}x")
    return (buffer, " ".join(fmt) + ("/i" if per_instance else ""), *used)


class MeshBuffers:
    """Vertex (position + normal, float32) and index (uint32) buffers of a base mesh."""

    def __init__(self, ctx, mesh):
        self.ctx = ctx
        self.mesh = mesh
        self.vertex_count = mesh.vertex_count
        interleaved = np.hstack([mesh.positions, mesh.normals]).astype("f4")
        self.vbo = ctx.buffer(interleaved.tobytes())
        self.triangles = ctx.buffer(mesh.faces.astype("u4").tobytes())
        self.edges = ctx.buffer(mesh.edges.astype("u4").tobytes())
        self.triangle_indices = int(mesh.faces.size)
        self.edge_indices = int(mesh.edges.size)
        self._released = False

    def content(self, program):
        return _content(self.vbo, ("3f", "3f"), ("in_position", "in_normal"), program)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        for b in (self.vbo, self.triangles, self.edges):
            b.release()


class InstanceBuffer:
    """All instances' 16 numbers in one GPU buffer (float32, 64 bytes each).

    ``capacity`` instances fit without reallocating; ``set`` with a larger
    count grows it (orphaning the old storage), a smaller count keeps it.
    """

    def __init__(self, ctx, params=None, capacity: int | None = None):
        self.ctx = ctx
        values = as_params(np.zeros((0, 16)) if params is None else params)
        self.count = len(values)
        self.capacity = max(int(capacity or 0), self.count, 1)
        self.buffer = ctx.buffer(reserve=self.capacity * RECORD_BYTES)
        self.reallocations = 0
        if self.count:
            self.buffer.write(values.tobytes())
        self._released = False

    def content(self, program):
        return _content(self.buffer, INSTANCE_FORMAT, INSTANCE_ATTRIBUTES, program, per_instance=True)

    def set(self, params) -> None:
        """Replace every instance; reallocates only if the count outgrows the capacity."""
        values = as_params(params)
        if len(values) > self.capacity:
            self.capacity = len(values)
            self.buffer.orphan(self.capacity * RECORD_BYTES)
            self.reallocations += 1
        self.count = len(values)
        if self.count:
            self.buffer.write(values.tobytes())

    def update(self, params, start: int = 0) -> None:
        """Overwrite instances ``start .. start + len(params) - 1`` in place."""
        values = as_params(params)
        start = int(start)
        if start < 0 or start + len(values) > self.count:
            raise ParamError(
                f"update: instances {start}..{start + len(values) - 1} do not fit in the {self.count} instances drawn; "
                "expected 0 <= start and start + len(params) <= count (use set() to change the count)"
            )
        if len(values):
            self.buffer.write(values.tobytes(), offset=start * RECORD_BYTES)

    def read(self) -> np.ndarray:
        """The parameters on the GPU, ``(count, 16) float32``."""
        data = self.buffer.read(size=self.count * RECORD_BYTES)
        return np.frombuffer(data, dtype="f4").reshape(self.count, 16).copy()

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        self.buffer.release()

"""Step 4 of the data flow: GPU buffers.

* :class:`MeshBuffers` — the base mesh once: interleaved position + normal
  (24 bytes a vertex), triangle indices and edge indices (for wireframe).
* :class:`InstanceBuffer` — the 16 numbers of every instance in ONE buffer,
  read with divisor 1 (64 bytes an instance, or 32 with ``quantized=True``:
  uint16 per number plus a per-column ``min``/``step`` table passed as
  uniforms and decoded in the vertex shader, ``AXIAL_QUANTIZED``); replacing
  all of it or a slice writes in place while the count is unchanged.
  Extended instances (19 numbers: ``s tw tp`` too, ``AXIAL_EXTENDED``) take
  76 bytes (float32) or 40 (19 uint16 and 2 bytes of padding).

Both hold their ``ctx``; ``release()`` is safe to call twice and nothing is
released from ``__del__``.
"""

from __future__ import annotations

import numpy as np

from ..core.errors import ArgumentError, ParamError
from ..core.mesh import grid_edge_count, grid_edge_pieces, grid_edges
from ..core.params import as_params, extend_params, is_extended
from ..core.quantize import dequantize_params, quantize_params, quantize_with_table
from ..core.record import EXTENDED_WIDTH, WIDTH, gl_layout
from .context import check_alive, check_released

__all__ = [
    "MeshBuffers", "InstanceBuffer", "INSTANCE_FORMAT", "INSTANCE_ATTRIBUTES", "RECORD_BYTES",
    "QUANTIZED_FORMAT", "QUANTIZED_ATTRIBUTES", "QUANTIZED_RECORD_BYTES",
    "EXTENDED_FORMAT", "EXTENDED_ATTRIBUTES", "EXTENDED_RECORD_BYTES",
    "QUANTIZED_EXTENDED_FORMAT", "QUANTIZED_EXTENDED_ATTRIBUTES", "QUANTIZED_EXTENDED_RECORD_BYTES", "buffer_content", "format_bytes"]

# the layouts of the instanced attribute buffer, generated from the record
# table (core/record.py): float 64 bytes (76 extended); quantized 16 uint16
# read as four integer uvec4 attributes (19 + 2 bytes of padding extended)
INSTANCE_FORMAT, INSTANCE_ATTRIBUTES, RECORD_BYTES = gl_layout(extended=False, quantized=False)
QUANTIZED_FORMAT, QUANTIZED_ATTRIBUTES, QUANTIZED_RECORD_BYTES = gl_layout(extended=False, quantized=True)
EXTENDED_FORMAT, EXTENDED_ATTRIBUTES, EXTENDED_RECORD_BYTES = gl_layout(extended=True, quantized=False)
(QUANTIZED_EXTENDED_FORMAT, QUANTIZED_EXTENDED_ATTRIBUTES,
 QUANTIZED_EXTENDED_RECORD_BYTES) = gl_layout(extended=True, quantized=True)


def as_index(value, name: str) -> int:
    """``value`` as an int if it is a whole number type (int, numpy integer;
    not bool, float, str or None), else :class:`ArgumentError`."""

    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ArgumentError(f"{name}: expected an integer instance index, found {value!r} ({type(value).__name__})")
    return int(value)


def format_bytes(fmt: str) -> int:
    """Bytes of one moderngl attribute format such as ``"4f"`` or ``"4u2"``."""
    count = int(fmt[0])
    size = int(fmt[-1]) if fmt[-1].isdigit() else 4
    return count * size


def buffer_content(buffer, formats, names, program, per_instance=False):
    """A vertex-array content tuple; attributes the program does not use
    (the linker removed them) become padding so moderngl accepts it."""
    fmt = []
    used = []
    for f, name in zip(formats, names):
        if name is None:  # padding of the layout itself
            fmt.append(f)
        elif name in program:
            fmt.append(f)
            used.append(name)
        else:
            fmt.append(f"{format_bytes(f)}x")
    return (buffer, " ".join(fmt) + ("/i" if per_instance else ""), *used)


#: grid rows whose edges one draw of a height map's wireframe covers (GL >= 4.2: :meth:`MeshBuffers.grid_edge_draws`)
GRID_BLOCK_ROWS = 16


def _grid_block_pattern(rows: int, cols: int, block: int) -> np.ndarray:
    """The edges of ``block`` grid rows from vertex 0, then the last row's right
    edges from vertex 0: every block of the grid is the first part of it drawn
    with a base vertex (``r0 · cols``), the last row the second (uint32 pairs)."""
    first = grid_edges(min(rows, block + 1), cols)[: min(rows - 1, block) * (3 * cols - 2)]
    c = np.arange(cols - 1, dtype=np.uint32)
    return np.concatenate([first, np.stack([c, c + 1], axis=1)])


def _edge_buffer(ctx, mesh, grid_block: int | None = None):
    """The mesh's edges as uint32 pairs in a GL buffer: a height map's made
    from its grid piece by piece and not kept (the buffer holds them; memory
    holds one piece, :func:`grid_edge_pieces`) -- or, with ``grid_block``,
    only the pattern of that many rows (:func:`_grid_block_pattern`) -- else
    the mesh's own (found once and kept by the mesh)."""
    grid = getattr(mesh, "grid", None)
    if grid is None:
        return ctx.buffer(np.ascontiguousarray(mesh.edges, dtype="u4"))  # no copies
    if grid_block is not None:
        return ctx.buffer(_grid_block_pattern(*grid, grid_block))
    buffer = ctx.buffer(reserve=8 * grid_edge_count(*grid))
    for first, piece in grid_edge_pieces(*grid):
        buffer.write(piece, offset=8 * first)
    return buffer


class MeshBuffers:
    """Vertex (position + normal, float32) and index (uint32) buffers of a base mesh.

    ``indices`` names the index buffers to build now: ``"triangles"`` and/or
    ``"edges"``.  Triangles left out stay ``None``; edges left out are built
    on first use of :attr:`edges` (a wireframe draw), so solid drawing never
    pays for them."""

    def __init__(self, ctx, mesh, indices=("triangles",)):
        check_alive(ctx, "new MeshBuffers")
        self.ctx = ctx
        self.mesh = mesh
        self.vertex_count = mesh.vertex_count
        self.triangles = self._edges = None
        self._released = False
        # one (n, 6) float32 array handed over as it is (no hstack/astype/tobytes
        # copies: a 4.5 M-triangle terrain would hold ~160 MB more while uploading)
        # several axes: each vertex's axis as a 7th float (in_axis); a LOD level carries its own
        tree = getattr(mesh, "tree", None)
        axis_ids = tree.vertex_code if tree is not None else getattr(mesh, "vertex_axis", None)  # blends: b + 64 b1 + 4096 q
        interleaved = np.empty((mesh.vertex_count, 6 if axis_ids is None else 7), dtype="f4")
        interleaved[:, :3] = mesh.positions
        interleaved[:, 3:6] = mesh.normals
        if axis_ids is not None:
            interleaved[:, 6] = axis_ids
        self._axis_ids = axis_ids is not None
        self.vbo = ctx.buffer(interleaved)
        del interleaved
        if "triangles" in indices:
            self.triangles = ctx.buffer(np.ascontiguousarray(mesh.faces, dtype="u4"))
        grid = getattr(mesh, "grid", None)
        #: a height map's wireframe as blocks of rows drawn with a base vertex from ONE small
        #: index buffer (GL >= 4.2: indirect draws with a base vertex), (rows, cols, rows a block);
        #: None: the whole edge buffer (every other mesh, GL 3.3)
        self.grid_blocks = None if grid is None or ctx.version_code < 420 else (*grid, GRID_BLOCK_ROWS)
        if "edges" in indices:
            self._edges = _edge_buffer(ctx, mesh, self._block_rows)
        self.triangle_indices = int(mesh.faces.size)

    @property
    def edges(self):
        """The edge index buffer (uint32 pairs), built on first use (lazily:
        finding the unique edges of a 10 M-triangle mesh takes seconds)."""
        check_released(self._released, "these MeshBuffers")
        if self._edges is None:
            check_alive(self.ctx, "these MeshBuffers")
            self._edges = _edge_buffer(self.ctx, self.mesh, self._block_rows)
        return self._edges

    @property
    def edge_indices(self) -> int:
        """Number of indices in :attr:`edges` (two per edge)."""
        grid = getattr(self.mesh, "grid", None)
        if grid is not None:
            return 2 * grid_edge_count(*grid)
        return int(self.mesh.edges.size)

    @property
    def _block_rows(self) -> int | None:
        return None if self.grid_blocks is None else self.grid_blocks[2]

    def grid_edge_draws(self, instances: int, base: int = 0) -> list:
        """The indirect commands ``(count, instances, first index, base vertex, base
        instance)`` that draw a height map's edges block by block (:attr:`grid_blocks`),
        in the whole buffer's order."""
        rows, cols, block = self.grid_blocks
        per_row = 3 * cols - 2
        out = [(2 * min(block, rows - 1 - r0) * per_row, instances, 0, r0 * cols, base)
               for r0 in range(0, rows - 1, block)]
        out.append((2 * (cols - 1), instances, 2 * min(rows - 1, block) * per_row, (rows - 1) * cols, base))
        return out

    def content(self, program):
        if self._axis_ids:
            return buffer_content(self.vbo, ("3f", "3f", "1f"), ("in_position", "in_normal", "in_axis"), program)
        return buffer_content(self.vbo, ("3f", "3f"), ("in_position", "in_normal"), program)

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        for b in (self.vbo, self.triangles, self._edges):
            if b is not None:
                b.release()


class InstanceBuffer:
    """All instances' 16 numbers in one GPU buffer (float32, 64 bytes each).

    ``capacity`` instances fit without reallocating; ``set`` with a larger
    count grows it (orphaning the old storage), a smaller count keeps it.

    With ``quantized=True`` each instance is 16 uint16 (32 bytes), the
    quantization of :func:`axialdeform.core.quantize.quantize_params`; ``qmin`` and
    ``qstep`` ((16,) float32) are the per-column table the vertex shader
    needs (uniforms ``u_qmin``/``u_qstep``, four ``vec4`` each).

    ``extended`` (default: whether ``params`` has 19 columns or more) stores the 19
    numbers of extended instances (76 bytes, or 40 quantized: the extra
    ``(3,)`` of the table go to ``u_qmin_extra``/``u_qstep_extra``); 16-number
    parameters written to it get ``s = 1, tw = 0, tp = 0``.  A tinted
    instance's tint (columns 19..21) is not stored here: the renderer keeps it
    in a float32 buffer of its own (``i_tint``, :data:`~axialdeform.core.record.SHADER_INPUTS`).
    """

    def __init__(self, ctx, params=None, capacity: int | None = None, *, quantized: bool = False,
                 extended: bool | None = None):
        check_alive(ctx, "a new InstanceBuffer")
        self.ctx = ctx
        self.quantized = bool(quantized)
        values = as_params(np.zeros((0, WIDTH)) if params is None else params)
        self.extended = is_extended(values) if extended is None else bool(extended)
        self.columns = EXTENDED_WIDTH if self.extended else WIDTH
        if self.extended:
            self.record_bytes = QUANTIZED_EXTENDED_RECORD_BYTES if self.quantized else EXTENDED_RECORD_BYTES
        else:
            self.record_bytes = QUANTIZED_RECORD_BYTES if self.quantized else RECORD_BYTES
        self.qmin = np.zeros(self.columns, dtype=np.float32)
        self.qstep = np.zeros(self.columns, dtype=np.float32)
        values = self._fit(values)
        self.count = len(values)
        self.capacity = max(int(capacity or 0), self.count, 1)
        self.buffer = ctx.buffer(reserve=self.capacity * self.record_bytes)
        self.reallocations = 0
        if self.count:
            self.buffer.write(self._encode_all(values))
        self._released = False

    def _check(self) -> None:
        check_released(self._released, "this InstanceBuffer")
        check_alive(self.ctx, "this InstanceBuffer")

    def _fit(self, values: np.ndarray) -> np.ndarray:
        """``values`` in this buffer's width (16-number ones extended with 1, 0, 0)."""
        if self.extended:
            return extend_params(values)
        if values.shape[1] != WIDTH:
            raise ParamError(
                f"parameters: {values.shape[1]} numbers per instance for a buffer of 16; expected (n, 16), "
                "or a renderer made for extended instances (extended=True)"
            )
        return values

    def _pack_q(self, q: np.ndarray) -> bytes:
        if self.extended:  # two bytes of padding after the 19 uint16
            q = np.concatenate([q, np.zeros((len(q), 1), dtype=q.dtype)], axis=1)
        return q.astype("<u2").tobytes()

    def _encode_all(self, values: np.ndarray) -> bytes:
        if not self.quantized:
            return values.tobytes()
        self.qmin, self.qstep, q = quantize_params(values)
        return self._pack_q(q)

    def _encode_part(self, values: np.ndarray, setter: str = "set()", name: str = "update") -> bytes:
        """Encode with the current table; values outside its range are refused."""
        if not self.quantized:
            return values.tobytes()
        q = quantize_with_table(values, self.qmin, self.qstep, name=name, setter=setter)
        return self._pack_q(q)

    @property
    def formats(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """The attribute formats and names of this buffer's layout."""
        if self.quantized:
            if self.extended:
                return QUANTIZED_EXTENDED_FORMAT, QUANTIZED_EXTENDED_ATTRIBUTES
            return QUANTIZED_FORMAT, QUANTIZED_ATTRIBUTES
        if self.extended:
            return EXTENDED_FORMAT, EXTENDED_ATTRIBUTES
        return INSTANCE_FORMAT, INSTANCE_ATTRIBUTES

    def content(self, program):
        return buffer_content(self.buffer, *self.formats, program, per_instance=True)

    def set(self, params) -> None:
        """Replace every instance; reallocates only if the count outgrows the capacity."""
        self._check()
        values = self._fit(as_params(params))
        if len(values) > self.capacity:
            self.capacity = len(values)
            self.buffer.orphan(self.capacity * self.record_bytes)
            self.reallocations += 1
        self.count = len(values)
        if self.count:
            self.buffer.write(self._encode_all(values))

    def reserve(self, capacity: int) -> None:
        """Room for ``capacity`` instances (grown, orphaning the old storage, only past the capacity); nothing
        is written: a GPU pass writes them and sets :attr:`count` (a generated layer, :mod:`~axialdeform.gl.generated`)."""
        self._check()
        if int(capacity) > self.capacity:
            self.capacity = int(capacity)
            self.buffer.orphan(self.capacity * self.record_bytes)
            self.reallocations += 1

    def update(self, params, start: int = 0, *, setter: str = "set()", name: str = "update") -> None:
        """Overwrite instances ``start .. start + len(params) - 1`` in place.
        ``start`` must be an integer (int or numpy integer).

        name, setter : how error messages name this call and the one that
        replaces every instance (a wrapper such as ``AxialRenderer`` passes its own)."""
        self._check()
        values = self._fit(as_params(params))
        start = as_index(start, f"{name}: start")
        if start < 0 or start + len(values) > self.count:
            raise ParamError(
                f"{name}: instances {start}..{start + len(values) - 1} do not fit in the {self.count} instances drawn; "
                f"expected 0 <= start and start + len(params) <= count (use {setter} to change the count)"
            )
        if len(values):
            self.buffer.write(self._encode_part(values, setter, name), offset=start * self.record_bytes)

    def read(self) -> np.ndarray:
        """The parameters on the GPU, ``(count, 16)`` (extended: ``(count, 19)``)
        float32, decoded if quantized."""
        self._check()
        if self.count == 0:  # moderngl cannot map zero bytes
            return np.zeros((0, self.columns), dtype=np.float32)
        data = self.buffer.read(size=self.count * self.record_bytes)
        w = self.columns
        if self.quantized:
            q = np.frombuffer(data, dtype="<u2").reshape(self.count, self.record_bytes // 2)[:, :w]
            return dequantize_params(self.qmin, self.qstep, q)
        return np.frombuffer(data, dtype="f4").reshape(self.count, w).copy()

    def release(self) -> None:
        if self._released:
            return
        self._released = True
        self.buffer.release()

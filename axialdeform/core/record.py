"""Step 3 of the data flow: the instance record.  ONE table says what an
instance is made of; everything else is generated from it.

An instance is a row of 16 float32 numbers (19 for an *extended* instance)::

    d1u d1v d2u d2v d3u d3v d4u d4v d5u d5v  px py pz  rx ry rz  [s tw tp]

:data:`RECORD` lists its fields (name, columns, unit, how a file quantizes
them); :data:`SHADER_INPUTS` the instanced vertex attributes that carry the
columns to ``glsl/scene.vert`` (name, first column, size, glTF attribute).
From these two tables come

* the column names and slices (:data:`FIELDS`, :data:`OFFSETS`, ...) used by
  the maths, the parameter files and the error messages;
* the named views of a parameter array, :class:`Instances`
  (``params.position`` instead of ``params[:, 10:13]``);
* the GL buffer formats and attribute names (:func:`gl_layout`);
* the glTF ``EXT_mesh_gpu_instancing`` attributes (:data:`GLTF_ATTRIBUTES`);
* the attribute list the web page receives (:func:`page_layout`).

``tests/core/test_record.py`` holds the GLSL declarations in ``glsl/`` and
the page's JavaScript to this table.  Pure numpy: no GL here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "Field", "ShaderInput", "RECORD", "SHADER_INPUTS", "GLTF_ATTRIBUTES", "FIELDS", "EXTENDED_FIELDS",
    "WIDTH", "EXTENDED_WIDTH", "WIDTHS", "OFFSETS", "POSITION", "ANGLES", "EXTRA", "SCALE", "TWIST", "TAPER",
    "IDENTITY_EXTRA", "Instances", "gl_layout", "page_layout", "page_record",
]


@dataclass(frozen=True)
class Field:
    """One named field of the instance record.

    Attributes
    ----------
    name : str
        The attribute name of the view (``params.position``).
    columns : tuple of str
        The file's column names, in order.
    start : int
        Index of the first column in the row.
    unit : str
        What the numbers mean.
    extended : bool
        Only in extended (19-number) instances.
    quantization : str
        How a quantized binary file stores it (every column today: uint16 on
        the column's own range, the table in the file's header).
    shape : tuple of int
        The shape of one instance's value in the named view (``()`` for a
        scalar).
    """

    name: str
    columns: tuple[str, ...]
    start: int
    unit: str
    extended: bool = False
    quantization: str = "uint16 on the column's range"
    shape: tuple[int, ...] = ()

    @property
    def stop(self) -> int:
        return self.start + len(self.columns)

    @property
    def slice(self) -> slice:
        """The columns of this field: ``params[:, field.slice]``."""
        return slice(self.start, self.stop)


#: THE instance record: every field, in row order
RECORD: tuple[Field, ...] = (
    Field("offsets", ("d1u", "d1v", "d2u", "d2v", "d3u", "d3v", "d4u", "d4v", "d5u", "d5v"), 0,
          "model units: control point i moves by (diu, div) across the axis", shape=(5, 2)),
    Field("position", ("px", "py", "pz"), 10, "world units", shape=(3,)),
    Field("rotation", ("rx", "ry", "rz"), 13, "radians about fixed X, then Y, then Z (R = Rz Ry Rx)", shape=(3,)),
    Field("scale", ("s",), 16, "uniform scale factor (> 0)", extended=True),
    Field("twist", ("tw",), 17, "radians of turn over the axis", extended=True),
    Field("taper", ("tp",), 18, "cross-section shrink at the axis end (< 1)", extended=True),
)

#: names of the 16 columns, in file order
FIELDS: tuple[str, ...] = tuple(c for f in RECORD if not f.extended for c in f.columns)
#: names of the 19 columns of an extended instance
EXTENDED_FIELDS: tuple[str, ...] = tuple(c for f in RECORD for c in f.columns)
WIDTH, EXTENDED_WIDTH = len(FIELDS), len(EXTENDED_FIELDS)
WIDTHS = (WIDTH, EXTENDED_WIDTH)

_BY_NAME = {f.name: f for f in RECORD}
OFFSETS = _BY_NAME["offsets"].slice
POSITION = _BY_NAME["position"].slice
ANGLES = _BY_NAME["rotation"].slice
#: the extension columns ``s tw tp`` of a (n, 19) array
EXTRA = slice(WIDTH, EXTENDED_WIDTH)
SCALE, TWIST, TAPER = (_BY_NAME[n].start for n in ("scale", "twist", "taper"))
#: the values of ``s tw tp`` that give exactly the 16-number shape
IDENTITY_EXTRA = (1.0, 0.0, 0.0)


@dataclass(frozen=True)
class ShaderInput:
    """An instanced vertex attribute of ``glsl/scene.vert`` (float layout).

    Attributes
    ----------
    name : str
        The GLSL ``in`` variable.
    start, size : int
        First column and number of columns it carries (``vec{size}``).
    extended : bool
        Only in the extended layout (``#ifdef AXIAL_EXTENDED``).
    gltf : str or None
        The ``EXT_mesh_gpu_instancing`` attribute that carries the same
        columns in an instanced glTF, where it is one of ours.
    """

    name: str
    start: int
    size: int
    extended: bool = False

    @property
    def glsl_type(self) -> str:
        return f"vec{self.size}" if self.size > 1 else "float"


#: the float layout of the instanced buffer: 64 bytes (76 extended), divisor 1
SHADER_INPUTS: tuple[ShaderInput, ...] = (
    ShaderInput("i_d12", 0, 4),
    ShaderInput("i_d34", 4, 4),
    ShaderInput("i_d5", 8, 2),
    ShaderInput("i_position", 10, 3),
    ShaderInput("i_angles", 13, 3),
    ShaderInput("i_extra", 16, 3, extended=True),
)

#: the instanced glTF's attributes (``EXT_mesh_gpu_instancing``) that carry
#: columns as they are: name -> (accessor type, columns); ``TRANSLATION``,
#: ``ROTATION`` (a quaternion of the angles) and ``SCALE`` (``(s, s, s)``)
#: are glTF's own and written by :mod:`axialdeform.core.io.gltf`
GLTF_ATTRIBUTES: dict[str, tuple[str, tuple[int, ...]]] = {
    "_AXIAL_D12": ("VEC4", (0, 1, 2, 3)),
    "_AXIAL_D34": ("VEC4", (4, 5, 6, 7)),
    "_AXIAL_D5": ("VEC2", (8, 9)),
    "_AXIAL_ANGLES": ("VEC3", tuple(range(ANGLES.start, ANGLES.stop))),
}
#: extended instances only: twist and taper (the scale goes to glTF's own SCALE)
GLTF_EXTENDED_ATTRIBUTES: dict[str, tuple[str, tuple[int, ...]]] = {"_AXIAL_TWIST_TAPER": ("VEC2", (TWIST, TAPER))}


def gl_layout(extended: bool, quantized: bool) -> tuple[tuple[str, ...], tuple[str | None, ...], int]:
    """The moderngl attribute formats, names and record bytes of the buffer.

    Float records are :data:`SHADER_INPUTS` (``"4f"`` ...); quantized ones are
    the row's uint16 levels read four at a time as integer ``uvec4``
    attributes ``i_q0, i_q1, ...`` (the last one shorter, padded to 4 bytes).

    Returns
    -------
    formats : tuple of str
    names : tuple of (str or None)
        ``None`` for padding.
    record_bytes : int
    """
    width = EXTENDED_WIDTH if extended else WIDTH
    if not quantized:
        inputs = [a for a in SHADER_INPUTS if extended or not a.extended]
        return tuple(f"{a.size}f" for a in inputs), tuple(a.name for a in inputs), 4 * width
    formats, names = [], []
    for k, start in enumerate(range(0, width, 4)):
        size = min(4, width - start)
        formats.append(f"{size}u2")
        names.append(f"i_q{k}")
    record = 2 * width
    if record % 4:
        formats.append(f"{4 - record % 4}x")
        names.append(None)
        record += 4 - record % 4
    return tuple(formats), tuple(names), record


def page_layout(extended: bool, quantized: bool = False) -> list[list]:
    """``[[name, size, first column], ...]``: the instanced attributes as the
    web page binds them to the file's records (``THREE.InterleavedBufferAttribute``
    over the float32 or uint16 values, one record a row)."""
    if quantized:
        width = EXTENDED_WIDTH if extended else WIDTH
        return [[f"i_q{k}", min(4, width - start), start] for k, start in enumerate(range(0, width, 4))]
    return [[a.name, a.size, a.start] for a in SHADER_INPUTS if extended or not a.extended]


def page_record() -> dict:
    """The record as the page receives it (its config's ``"record"``):
    ``{"16": {"float": layout, "quantized": layout}, "19": {...}}``."""
    return {str(w): {"float": page_layout(w == EXTENDED_WIDTH), "quantized": page_layout(w == EXTENDED_WIDTH, True)}
            for w in WIDTHS}


class Instances(np.ndarray):
    """An ``(n, 16)`` or ``(n, 19)`` float32 parameter array with named views.

    A plain :class:`numpy.ndarray` in every other way (``params[:, 10:13]``
    still works); the views share memory with it, so writing to them
    changes the instances::

        params = ad.random_params(mesh, 100)
        params.position[:, 1] += 0.5        # lift every instance
        params.offsets[:, 4] *= 2.0         # bend the tip (d5) twice as far
        params.rotation                     # (n, 3) radians

    ``offsets`` is ``(n, 5, 2)``; ``position`` and ``rotation`` ``(n, 3)``;
    ``scale``, ``twist`` and ``taper`` ``(n,)`` (extended instances only).
    """

    @classmethod
    def zeros(cls, count: int, *, extended: bool = False) -> "Instances":
        """``count`` instances of zeros: ``(count, 16)`` float32 (``(count, 19)``
        extended, with ``s = 1``: the undeformed shape), to fill through the views."""
        out = np.zeros((int(count), EXTENDED_WIDTH if extended else WIDTH), dtype=np.float32).view(cls)
        if extended:
            out[:, SCALE] = 1.0
        return out

    @classmethod
    def of(cls, values) -> "Instances":
        """``values`` ((n, 16|19) float32) as :class:`Instances`, without a copy."""
        return np.asarray(values).view(cls)

    def __getattr__(self, name):
        f = _BY_NAME.get(name)
        if f is None:
            raise AttributeError(f"{type(self).__name__!s} has no attribute {name!r}")
        if self.ndim != 2 or self.shape[1] not in WIDTHS:
            raise AttributeError(f"{name}: named views need an (n, 16) or (n, 19) array, found shape {self.shape}")
        if f.extended and self.shape[1] != EXTENDED_WIDTH:
            raise AttributeError(f"{name}: only extended (n, 19) instances have it; this array is {self.shape}")
        cols = self[:, f.slice].view(np.ndarray)
        if f.shape == ():
            return cols[:, 0]
        return cols.reshape(len(self), *f.shape)

    def __setattr__(self, name, value):
        if name in _BY_NAME:
            view = getattr(self, name)
            view[...] = value
            return
        super().__setattr__(name, value)

    def __dir__(self):
        names = [f.name for f in RECORD if not f.extended or (self.ndim == 2 and self.shape[-1] == EXTENDED_WIDTH)]
        return sorted(set(super().__dir__()) | set(names))

"""Step 3 of the data flow: the instance record.  ONE table says what an
instance is made of; everything else is generated from it.

An instance is a row of 16 float32 numbers, 19 for an *extended* instance
and 22 for a *tinted* one (the levels of the record, :data:`WIDTHS`)::

    d1u d1v d2u d2v d3u d3v d4u d4v d5u d5v  px py pz  rx ry rz  [s tw tp  [tr tg tb]]

:data:`RECORD` lists its fields (name, columns, unit, level, how a file
quantizes them); :data:`SHADER_INPUTS` the instanced vertex attributes that
carry the columns to ``glsl/scene.vert`` (name, first column, size, level,
buffer).  A file's width says its level (binary files: version = level + 1).
From these two tables come

* the column names and slices (:data:`FIELDS`, :data:`OFFSETS`, ...) used by
  the maths, the parameter files and the error messages;
* the named views of a parameter array, :class:`Instances`
  (``params.position`` instead of ``params[:, 10:13]``);
* the GL buffer formats and attribute names (:func:`gl_layout`);
* the glTF ``EXT_mesh_gpu_instancing`` attributes (:data:`GLTF_ATTRIBUTES`);
* the record's columns in JavaScript (the npm module's ``recordLayout``, js/src/core/adp.js; a test
  compares them with this table).

``tests/core/test_record.py`` holds the GLSL declarations in ``glsl/`` and
the page's JavaScript to this table.  Pure numpy: no GL here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "Field", "ShaderInput", "RECORD", "SHADER_INPUTS", "GLTF_ATTRIBUTES", "FIELDS", "EXTENDED_FIELDS", "WIDTH",
    "EXTENDED_WIDTH", "TINTED_WIDTH", "WIDTHS", "TINT", "IDENTITY_TINT", "level_of", "describe_widths",
    "GLTF_EXTENDED_ATTRIBUTES", "GLTF_TINT_ATTRIBUTE", "GLTF_INSTANCE_TYPES", "OFFSETS", "POSITION", "ANGLES", "EXTRA", "SCALE", "TWIST",
    "TAPER", "IDENTITY_EXTRA", "Instances", "gl_layout", "LEVEL_FIELDS", "RECORD_BUFFER_WIDTH", "LEVEL_NAMES",
    "describe_record", "tint_columns", "tree_width", "tree_widths", "split_record", "join_record", "tree_shape",
    "record_fields", "is_record_width", "MAX_RECORD_AXES", "SlotGroup", "SLOT_COLUMNS", "SLOT_FLOATS", "SLOT_OUTPUTS",
    "SLOT_GROUPS", "CHILD_AXES_A_PASS", "CHILD_SLOT_VECTORS", "slot_varyings", "slot_layout",
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
    level : int
        The first record level that has it: 0 every instance (16 numbers),
        1 extended instances (19), 2 tinted instances (22).
    shape : tuple of int
        The shape of one instance's value in the named view (``()`` for a
        scalar).
    """

    name: str
    columns: tuple[str, ...]
    start: int
    unit: str
    level: int = 0
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
    Field("scale", ("s",), 16, "uniform scale factor (> 0)", level=1),
    Field("twist", ("tw",), 17, "radians of turn over the axis", level=1),
    Field("taper", ("tp",), 18, "cross-section shrink at the axis end (< 1)", level=1),
    Field("tint", ("tr", "tg", "tb"), 19, "linear RGB in 0..1 multiplying the base colour (1 1 1: unchanged)",
          level=2, shape=(3,)),
)

#: the column names of each level, in file order: 16, 19 and 22 names
LEVEL_FIELDS: tuple[tuple[str, ...], ...] = tuple(
    tuple(c for f in RECORD if f.level <= level for c in f.columns) for level in range(max(f.level for f in RECORD) + 1))
#: names of the 16 columns, in file order
FIELDS: tuple[str, ...] = LEVEL_FIELDS[0]
#: names of the 19 columns of an extended instance
EXTENDED_FIELDS: tuple[str, ...] = LEVEL_FIELDS[1]
#: the numbers per instance of each level: (16, 19, 22)
WIDTHS: tuple[int, ...] = tuple(len(names) for names in LEVEL_FIELDS)
WIDTH, EXTENDED_WIDTH, TINTED_WIDTH = WIDTHS


#: what each level's instances are called
LEVEL_NAMES: tuple[str, ...] = ("plain", "extended", "tinted")


def describe_record(width: int) -> str:
    """``"22 numbers an instance (tinted: ... tr tg tb)"``: a width in words."""
    k, level = tree_shape(width)
    added = [c for c in LEVEL_FIELDS[level] if c not in (LEVEL_FIELDS[level - 1] if level else ())]
    axes = f", {k} axes: 10 offsets each" if k > 1 else ""
    return f"{width} numbers an instance ({LEVEL_NAMES[level]}{axes}" + (f": ... {' '.join(added)})" if level else ")")


def level_of(width: int) -> int:
    """The record level of ``width`` numbers per instance (0, 1, 2); ValueError if none."""
    return WIDTHS.index(int(width))


def describe_widths(widths=WIDTHS) -> str:
    """``"16, 19 or 22"``: the widths for an error message."""
    w = [str(x) for x in widths]
    return w[0] if len(w) == 1 else ", ".join(w[:-1]) + " or " + w[-1]

_BY_NAME = {f.name: f for f in RECORD}
OFFSETS = _BY_NAME["offsets"].slice
POSITION = _BY_NAME["position"].slice
ANGLES = _BY_NAME["rotation"].slice
#: the extension columns ``s tw tp`` of a (n, 19) array
EXTRA = slice(WIDTH, EXTENDED_WIDTH)
SCALE, TWIST, TAPER = (_BY_NAME[n].start for n in ("scale", "twist", "taper"))
#: the columns ``tr tg tb`` of a (n, 22) array
TINT = _BY_NAME["tint"].slice
#: the values of ``s tw tp`` that give exactly the 16-number shape
IDENTITY_EXTRA = (1.0, 0.0, 0.0)
#: the tint that leaves the base colour as it is
IDENTITY_TINT = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class ShaderInput:
    """An instanced vertex attribute of ``glsl/scene.vert`` (float layout).

    Attributes
    ----------
    name : str
        The GLSL ``in`` variable.
    start, size : int
        First column and number of columns it carries (``vec{size}``).
    level : int
        The first record level that has it (1: ``#ifdef AXIAL_EXTENDED``,
        2: ``#ifdef AXIAL_TINT``).
    buffer : str
        ``"record"``: read from the instance buffer (float32, or the uint16
        levels of a quantized one); ``"tint"``: a float32 buffer of its own,
        so that :meth:`AxialRenderer.set_tint` re-colours without touching
        the record, whatever the record's encoding.
    """

    name: str
    start: int
    size: int
    level: int = 0
    buffer: str = "record"

    @property
    def extended(self) -> bool:
        return self.level > 0


#: the float layout of the instanced buffer: 64 bytes (76 extended), divisor
#: 1; the tint (tinted instances) in a float32 buffer of its own
SHADER_INPUTS: tuple[ShaderInput, ...] = (
    ShaderInput("i_d12", 0, 4),
    ShaderInput("i_d34", 4, 4),
    ShaderInput("i_d5", 8, 2),
    ShaderInput("i_position", 10, 3),
    ShaderInput("i_angles", 13, 3),
    ShaderInput("i_extra", 16, 3, level=1),
    ShaderInput("i_tint", 19, 3, level=2, buffer="tint"),
)
#: numbers per instance in the instance buffer: the columns its inputs read
RECORD_BUFFER_WIDTH: int = max(a.start + a.size for a in SHADER_INPUTS if a.buffer == "record")


# ------------------------------------------------------------------ the generator's slot (glsl/generate.glsl)
@dataclass(frozen=True)
class SlotGroup:
    """One vector of the generator's slot as it travels between GL passes (a transform-feedback
    output ``g_{index}``, a vertex input ``a_{index}``, a compaction varying ``vs_{index}``/``o_{index}``).

    Attributes
    ----------
    index : int
    start, size : int
        First number of the slot and how many it carries (``vec{size}``, ``float`` for 1).
    level : int
        The record level whose columns it carries; ``len(WIDTHS)`` for ``kept``.
    """

    index: int
    start: int
    size: int
    level: int

    @property
    def glsl_type(self) -> str:
        return "float" if self.size == 1 else f"vec{self.size}"


#: THE generator's slot: what ``axial_generate`` (glsl/generate.glsl) makes of one cell -- the tinted
#: record's columns, then ``kept`` (1: kept, 0: dropped by the ground maps and bands)
SLOT_COLUMNS: tuple[str, ...] = LEVEL_FIELDS[-1] + ("kept",)
#: numbers a slot
SLOT_FLOATS: int = len(SLOT_COLUMNS)
#: ``axial_generate``'s outputs, in slot order: (name, size); the record's are the scene shader's inputs'
#: names without ``i_`` (``d12``, ..., ``tint``), then ``kept``
SLOT_OUTPUTS: tuple[tuple[str, int], ...] = tuple((a.name[2:], a.size) for a in SHADER_INPUTS) + (("kept", 1),)
#: child axes the children's pass writes an instance (10 numbers each): as many as 64 captured
#: components hold (GL's least MAX_TRANSFORM_FEEDBACK_INTERLEAVED_COMPONENTS)
CHILD_AXES_A_PASS: int = 64 // 10
#: its outputs, four numbers each
CHILD_SLOT_VECTORS: int = -(-10 * CHILD_AXES_A_PASS // 4)


def _slot_groups() -> tuple[SlotGroup, ...]:
    bounds = [0, *WIDTHS, SLOT_FLOATS]
    groups = []
    for level, (lo, hi) in enumerate(zip(bounds[:-1], bounds[1:])):
        for start in range(lo, hi, 4):
            groups.append(SlotGroup(len(groups), start, min(4, hi - start), level))
    return tuple(groups)


#: the slot's vectors: each record level's new columns four at a time, then ``kept`` (so a pass that
#: keeps the record's first 16 or 19 numbers takes whole vectors)
SLOT_GROUPS: tuple[SlotGroup, ...] = _slot_groups()
assert sum(size for _, size in SLOT_OUTPUTS) == SLOT_FLOATS, "the generator's outputs are the slot"
assert [a.start for a in SHADER_INPUTS] == [sum(s for _, s in SLOT_OUTPUTS[:k]) for k in range(len(SHADER_INPUTS))]


def slot_varyings(prefix: str, levels=None) -> tuple[str, ...]:
    """The names of the slot's vectors (``g_0``, ...) with ``prefix``, those of ``levels`` only if given."""
    return tuple(f"{prefix}_{g.index}" for g in SLOT_GROUPS if levels is None or g.level in levels)


def slot_layout() -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The moderngl formats and vertex input names of a buffer of slots (``("4f", ...), ("a_0", ...)``)."""
    return tuple(f"{g.size}f" for g in SLOT_GROUPS), slot_varyings("a")

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
#: tinted instances: the tint as the per-instance colour three.js's
#: GLTFLoader already reads (``instanceColor``), so other viewers show it too
GLTF_TINT_ATTRIBUTE: tuple[str, str, tuple[int, ...]] = ("_COLOR_0", "VEC3", tuple(range(TINT.start, TINT.stop)))
#: every instance attribute's accessor type, glTF's own placement included (a child axis j's
#: ``_AXIAL_A{j}_D12/_D34/_D5`` as the first's): what both readers of the extension check
GLTF_INSTANCE_TYPES: dict[str, str] = {
    "TRANSLATION": "VEC3", "ROTATION": "VEC4", "SCALE": "VEC3",
    **{name: kind for name, (kind, _) in {**GLTF_ATTRIBUTES, **GLTF_EXTENDED_ATTRIBUTES}.items()},
    GLTF_TINT_ATTRIBUTE[0]: GLTF_TINT_ATTRIBUTE[1]}


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
        inputs = [a for a in SHADER_INPUTS if a.buffer == "record" and (extended or not a.extended)]
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


def tint_columns(values) -> np.ndarray | None:
    """The ``(n, 3)`` tint columns of tinted instances, else ``None``."""
    values = np.asarray(values)
    if values.ndim != 2 or not is_record_width(values.shape[1]):
        return None
    k, level = tree_shape(values.shape[1])  # several axes: the tint comes after every axis's offsets
    return values[:, 10 * (k - 1) + TINT.start:10 * (k - 1) + TINT.stop] if level == 2 else None


class Instances(np.ndarray):
    """An ``(n, 16|19|22)`` float32 parameter array with named views (a record of K axes too: 10 more numbers
    an axis after the first; then ``offsets`` is every axis's, ``(n, K, 5, 2)``).

    A plain :class:`numpy.ndarray` in every other way (``params[:, 10:13]`` still works); the views
    share memory with it, so writing to them changes the instances::

        params = ad.random_params(mesh, 100)
        params.position[:, 1] += 0.5        # lift every instance
        params.offsets[:, 4] *= 2.0         # bend the tip (d5) twice as far
        params.rotation                     # (n, 3) radians

    Make one with :meth:`zeros` or :meth:`of` (no copy).

    Attributes
    ----------
    offsets : (n, 5, 2) float32
        The five control-point offsets.
    position : (n, 3) float32
    rotation : (n, 3) float32
        Radians about fixed X, then Y, then Z.
    scale, twist, taper : (n,) float32
        Extended instances only.
    tint : (n, 3) float32
        Tinted instances only.
    """

    @classmethod
    def zeros(cls, count: int, *, extended: bool = False, tinted: bool = False) -> Instances:
        """``count`` instances of zeros: ``(count, 16)`` float32 (``(count, 19)``
        extended, with ``s = 1``: the undeformed shape; ``(count, 22)`` tinted,
        with the tint 1 1 1), to fill through the views."""
        level = 2 if tinted else 1 if extended else 0
        out = np.zeros((int(count), WIDTHS[level]), dtype=np.float32).view(cls)
        if level >= 1:
            out[:, SCALE] = 1.0
        if level >= 2:
            out[:, TINT] = 1.0
        return out

    @classmethod
    def of(cls, values) -> Instances:
        """``values`` ((n, 16|19) float32) as :class:`Instances`, without a copy."""
        return np.asarray(values).view(cls)

    def __getattr__(self, name):
        f = _BY_NAME.get(name)
        if f is None:
            raise AttributeError(f"{type(self).__name__!s} has no attribute {name!r}")
        if self.ndim != 2 or not is_record_width(self.shape[1]):
            shapes = describe_widths(tuple(f"(n, {w})" for w in WIDTHS))
            raise AttributeError(f"{name}: named views need an {shapes} array (10 more numbers an axis after the "
                                 f"first), found shape {self.shape}")
        k, level = tree_shape(self.shape[1])
        if level < f.level:
            kind = "extended" if f.level == 1 else "tinted"
            raise AttributeError(f"{name}: only {kind} (n, {WIDTHS[f.level] + 10 * (k - 1)}) instances have it; "
                                 f"this array is {self.shape}")
        if f.name == "offsets":  # every axis's, axis after axis: (n, 5, 2), or (n, K, 5, 2) with K axes
            cols = self[:, :10 * k].view(np.ndarray)
            return cols.reshape(len(self), *f.shape) if k == 1 else cols.reshape(len(self), k, *f.shape)
        cols = self[:, f.start + 10 * (k - 1):f.stop + 10 * (k - 1)].view(np.ndarray)
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
        level = tree_shape(self.shape[-1])[1] if self.ndim == 2 and is_record_width(self.shape[-1]) else -1
        names = [f.name for f in RECORD if level >= f.level]
        return sorted(set(super().__dir__()) | set(names))


# ------------------------------------------------------------------ several axes (core/axes.py)
def tree_width(axes: int, level: int = 0) -> int:
    """Numbers per instance of a K-axis mesh: ``10·K + 6 + 3·level``."""
    return 10 * int(axes) + WIDTHS[level] - 10


def tree_widths(axes: int) -> tuple[int, ...]:
    return tuple(tree_width(axes, level) for level in range(len(WIDTHS)))


def split_record(values, axes: int) -> tuple[np.ndarray, np.ndarray]:
    """A K-axis record as axis 0's standard record ``(n, 16|19|22)`` and the
    child axes' offsets ``(n, K − 1, 5, 2)`` (both float32)."""
    v = np.asarray(values)
    children = v[:, 10:10 * axes].reshape(len(v), axes - 1, 5, 2)
    return np.ascontiguousarray(np.concatenate([v[:, :10], v[:, 10 * axes:]], axis=1)), children


def join_record(standard, children) -> np.ndarray:
    """The inverse of :func:`split_record`: ``(n, 10·K + 6 [+3 [+3]])`` float32."""
    s = np.asarray(standard, dtype=np.float32)
    c = np.asarray(children, dtype=np.float32).reshape(len(s), -1)
    return np.ascontiguousarray(np.concatenate([s[:, :10], c, s[:, 10:]], axis=1))


def tree_shape(width: int) -> tuple[int, int]:
    """``(K, level)`` of ``width`` numbers per instance (``width = 10·K + 6 + 3·level``);
    ValueError if none."""
    k, rest = divmod(int(width) - 6, 10)
    if k < 1 or rest not in (0, 3, 6):
        raise ValueError(f"{width} is not 10·K + 6 (+ 3, + 6) numbers")
    return k, rest // 3


#: the most axes a record may have (core/axes.py's MAX_AXES)
MAX_RECORD_AXES = 64


def is_record_width(width: int) -> bool:
    """Whether ``width`` numbers per instance is a record: ``10·K + 6 + 3·level``,
    1 <= K <= :data:`MAX_RECORD_AXES`, level 0, 1 or 2."""
    try:
        k, _ = tree_shape(width)
    except ValueError:
        return False
    return k <= MAX_RECORD_AXES


def record_fields(width: int) -> tuple[str, ...]:
    """The column names of a record of ``width`` numbers: the level's names for
    one axis; with K axes axis k's offsets are ``a{k}.d1u`` .. ``a{k}.d5v``
    after axis 0's."""
    k, level = tree_shape(width)
    names = LEVEL_FIELDS[level]
    children = tuple(f"a{j}.{c}" for j in range(1, k) for c in names[:10])
    return names[:10] + children + names[10:]

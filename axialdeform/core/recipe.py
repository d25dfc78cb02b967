"""A generated layer's recipe, declared once: every key of a scene file's ``[layer.generate]``.

:data:`RECIPE` is the one table of a recipe's keys: each key's kind (what values it takes, how a file
spells it), its default, whether the JSON form carries it (the page, the notebook widget, the npm
module's generated ``AxialInstancedMesh`` and the glTF generated form) and which of ``glsl/generate.glsl``'s
``AxialRecipe`` numbers it passes into unchanged.  :data:`KINDS` says, once, what each kind expects.

Read from here: :class:`~axialdeform.core.generate.Generate` (its fields, their defaults and their
checks), the scene file's reader (the keys and their shapes), ``recipe_json`` and ``recipe_uniforms``
(the keys carried and passed through), the glTF generated form's reader.  Written from here by
``tools/make_tables.py``: the npm module's ``RECIPE`` and ``RECIPE_KINDS`` (``js/src/core/record.js``, read by
``checkRecipe``, ``recipeUniforms`` and ``checkUniforms``), its ``GenerateRecipe`` type
(``js/src/index.d.ts``), the glTF extension's schema and the table of keys in ``docs/generate.md``.  A new
key is a row here plus its formula (``glsl/generate.glsl`` and ``core/generate.py``).  Pure Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import ParamError

__all__ = ["MAX_COUNT", "ANCHORS", "Kind", "RecipeKey", "KINDS", "RECIPE", "REQUIRED", "recipe_key",
           "accepts", "check_value", "passed_through", "from_numbers",
           "optional_numbers"]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


#: the default of a key a recipe must give
REQUIRED = _Required()
#: the largest whole number a ``count`` key takes (``clump_cells``: a block of at most 256 x 256 cells)
MAX_COUNT = 256


@dataclass(frozen=True)
class Kind:
    """What a kind of key takes.

    Attributes
    ----------
    expected : str
        The words of an error message: ``"generate: KEY: expected <expected>, found ..."``.
    shape : str
        How a file spells it: ``"number"``, ``"whole"`` (an integer), ``"levels"`` (one number or 1..16),
        ``"pair"``, ``"triple"`` (three numbers), ``"quad"`` (four) or ``"word"``.
    words : tuple of str
        A ``"word"`` kind's choices.
    """

    expected: str
    shape: str
    words: tuple = ()


#: the base mesh's points an instance may stand on (a recipe's and ``[layer.scatter]``'s ``anchor``;
#: :func:`~axialdeform.core.mesh.anchor_point`)
ANCHORS = ("bottom", "center", "origin")

#: every kind of key, and what it expects (js/src/core/limits.js tests each kind by the same rule)
KINDS = {
    "positive": Kind("a finite number > 0", "number"),
    "nonnegative": Kind("a finite number >= 0", "number"),
    "below_one": Kind("a number in [0, 1)", "number"),
    "amount": Kind("an amount in [0, 1]", "number"),
    "seed": Kind("an integer 0 .. 4294967295", "whole"),
    "count": Kind(f"a whole number 1 .. {MAX_COUNT}", "whole"),
    "levels": Kind("a finite number >= 0, or one per level of the hierarchy", "levels"),
    "scale": Kind("[lo, hi] with 0 < lo <= hi", "pair"),
    "quartiles": Kind("[q1, q2, q3] with 0 < q1 <= q2 <= q3", "triple"),
    "octiles": Kind("[o1, o3, o5, o7] with 0 < o1 <= o3 <= o5 <= o7", "quad"),
    "span": Kind("[lo, hi] with lo <= hi", "pair"),
    "degrees": Kind("[lo, hi] with lo <= hi in degrees, 0..90", "pair"),
    "share": Kind("[lo, hi] with 0 <= lo <= hi <= 1", "pair"),
    "rgb": Kind("three linear RGB numbers in [0, 1]", "triple"),
    "anchor": Kind("one of " + ", ".join(ANCHORS), "word", ANCHORS),
}


@dataclass(frozen=True)
class RecipeKey:
    """One key of a recipe.

    Attributes
    ----------
    name : str
        The key, as a scene file, the JSON form and :class:`~axialdeform.core.generate.Generate` spell it.
    kind : str
        One of :data:`KINDS`.
    default : object
        Its value when not given; :data:`REQUIRED`: the recipe must give it; None: none (the key is optional
        and takes ``null`` in JSON).
    doc : str
        One line: what it does.
    json : bool
        Whether the recipe's JSON form carries it (else it reaches a reader through the generator's numbers).
    required_json : bool
        Whether the JSON form must carry it (the keys of the form's first version).
    uniform : str or None
        The ``AxialRecipe`` number it goes into unchanged (None: a number computed from it).
    absent : object
        That number's value when the key is None.
    in_file : bool
        Whether a scene file spells it (``choice`` comes from ``weights``).
    """

    name: str
    kind: str
    default: object
    doc: str
    json: bool = False
    required_json: bool = False
    uniform: str | None = None
    absent: object = None
    in_file: bool = True

    @property
    def optional(self) -> bool:
        """Whether None is a value (no scale, no tint, no band)."""
        return self.default is None

    @property
    def uniform_default(self):
        """The ``AxialRecipe`` number when the key is not given or None."""
        return self.absent if self.default is None or self.default is REQUIRED else self.default


#: every key of a recipe, in order (Generate's fields; the JSON form's keys)
RECIPE = (
    RecipeKey("rate", "positive", REQUIRED, "instances per square unit of ground (before the density map)", True, True),
    RecipeKey("tile", "positive", 16.0, "the side of a tile (world units)", True, True),
    RecipeKey("min_distance", "nonnegative", 0.0, "the guaranteed distance between any two instances (< 1/sqrt(rate))",
              True, True),
    RecipeKey("seed", "seed", 0, "the seed of every random number", True, True, uniform="seed"),
    RecipeKey("bend", "levels", 0.1, "offsets in [-bend L, bend L]; a mesh of several axes: one amplitude per level "
              "of its hierarchy, the last for any deeper level", True, True),
    RecipeKey("scale", "scale", None, "a uniform scale drawn in [lo, hi] (19 numbers an instance)", True,
              uniform="scale", absent=(1.0, 1.0)),
    RecipeKey("twist", "nonnegative", 0.0, "a twist drawn in [-twist, twist] radians", True, uniform="twist"),
    RecipeKey("taper", "below_one", 0.0, "a taper drawn in [0, taper]", True, uniform="taper"),
    RecipeKey("tint", "amount", None, "each instance's colour tint_color (1 - tint u): shades of tint_color "
              "(22 numbers)", True, uniform="tint", absent=0.0),
    RecipeKey("tint_color", "rgb", (1.0, 1.0, 1.0), "linear RGB: the brightest tint", True, uniform="tint_color"),
    RecipeKey("altitude", "span", None, "on a height map: kept where the ground's height lies in [lo, hi]"),
    RecipeKey("slope", "degrees", None, "on a height map: kept where the ground's slope lies in [lo, hi] degrees"),
    RecipeKey("choice", "share", (0.0, 1.0), "kept where u20 lies in [lo, hi): this mesh's share of a layer of "
              "several meshes (a scene file's weights)", uniform="choice", in_file=False),
    RecipeKey("anchor", "anchor", "bottom", "the base mesh's point that stands on the ground: its bounding box's "
              "bottom face's centre, its centre, its origin"),
    RecipeKey("lift", "span", None, "an extra height drawn in [lo, hi] world units", uniform="lift", absent=(0.0, 0.0)),
    RecipeKey("align_to_normal", "amount", 0.0, "on a height map: lean toward the ground's normal by this fraction",
              uniform="align"),
    RecipeKey("tint_hue", "amount", 0.0, "how far each colour channel's u goes its own way (0: one u, the tint keeps "
              "tint_color's hue; 1: one u each)", True, uniform="tint_hue"),
    RecipeKey("yaw", "span", (0.0, 2.0 * math.pi), "the turn about up drawn in [lo, hi] radians", True, uniform="yaw"),
    RecipeKey("clump_cells", "count", 1, "clumps: 8 parents to every clump_cells x clump_cells cells, anywhere in them; "
              "each instance picks one (1 and clump_radius 0: no clumps)", True, uniform="clump_cells"),
    RecipeKey("clump_radius", "nonnegative", 0.0, "clumps: each instance uniform in a disc of this radius around its "
              "parent (world units; no min_distance then)", True, uniform="clump_radius"),
    RecipeKey("clump_core", "amount", 0.0, "clumps: the share of each clump's instances that stand in its core (where "
              "u25 < clump_core)", True, uniform="clump_core"),
    RecipeKey("clump_core_radius", "nonnegative", 0.0, "clumps: the core's radius, at most clump_radius (world units): "
              "its instances uniform in a disc of this radius around the parent", True, uniform="clump_core_radius"),
    RecipeKey("scale_quartiles", "quartiles", None, "the scale at u13 = 1/4, 1/2, 3/4: drawn piecewise linear through "
              "[lo, q1, q2, q3, hi] (a learned distribution of sizes; none: uniform in scale's [lo, hi])", True,
              uniform="scale_mid", absent=(-1.0, -1.0, -1.0)),
    RecipeKey("scale_octiles", "octiles", None, "with scale_quartiles, the scale at u13 = 1/8, 3/8, 5/8, 7/8 too: "
              "piecewise linear through nine knots (none: through five)", True, uniform="scale_odd",
              absent=(-1.0, -1.0, -1.0, -1.0)),
)

_BY_NAME = {k.name: k for k in RECIPE}


def recipe_key(name: str) -> RecipeKey:
    """The row of key ``name`` (KeyError when a recipe has no such key)."""
    return _BY_NAME[name]


def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _numbers(v, n: int) -> bool:
    return isinstance(v, (tuple, list)) and len(v) == n and all(_number(x) for x in v)


def accepts(kind: str, v) -> bool:
    """Whether value ``v`` is of kind ``kind`` (its range; None is no value of any kind)."""
    if kind == "positive":
        return _number(v) and v > 0
    if kind == "nonnegative":
        return _number(v) and v >= 0
    if kind == "below_one":
        return _number(v) and 0 <= v < 1
    if kind == "amount":
        return _number(v) and 0 <= v <= 1
    if kind == "seed":
        return isinstance(v, int) and not isinstance(v, bool) and 0 <= v < 2 ** 32
    if kind == "count":
        return isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= MAX_COUNT
    if kind == "levels":
        bends = v if isinstance(v, (tuple, list)) else (v,)
        return 0 < len(bends) and all(_number(b) and b >= 0 for b in bends)
    if kind == "rgb":
        return _numbers(v, 3) and all(0 <= x <= 1 for x in v)
    if kind == "anchor":
        return v in KINDS[kind].words
    if kind in ("quartiles", "octiles"):
        n = 3 if kind == "quartiles" else 4
        return _numbers(v, n) and 0 < v[0] and all(a <= b for a, b in zip(v, v[1:]))
    pair = _numbers(v, 2) and v[0] <= v[1]
    if kind == "scale":
        return pair and v[0] > 0
    if kind == "degrees":
        return pair and 0 <= v[0] and v[1] <= 90
    if kind == "share":
        return pair and 0 <= v[0] and v[1] <= 1
    return pair  # span


def check_value(key: RecipeKey, value):
    """``value`` of ``key`` checked by its kind and normalized (number lists as float tuples; one bend of a
    list as a float); a :class:`ParamError` "generate: KEY: expected ..., found ..." otherwise."""
    if value is None and key.optional:
        return None
    if not accepts(key.kind, value):
        raise ParamError(f"generate: {key.name}: expected {KINDS[key.kind].expected}, found {value!r}")
    shape = KINDS[key.kind].shape
    if shape == "levels" and isinstance(value, (tuple, list)):
        return tuple(float(b) for b in value) if len(value) > 1 else float(value[0])
    if shape in ("pair", "triple", "quad"):
        return tuple(float(x) for x in value)
    return value


def passed_through(recipe) -> dict:
    """The ``AxialRecipe`` numbers the keys of ``recipe`` (a Generate) go into unchanged, JSON-able."""
    out = {}
    for key in RECIPE:
        if key.uniform is None:
            continue
        v = getattr(recipe, key.name)
        v = key.uniform_default if v is None else v
        out[key.uniform] = [float(x) for x in v] if isinstance(v, tuple) else int(v) if key.kind == "seed" else float(v)
    return out


def from_numbers(u: dict) -> dict:
    """The keys the JSON form does not carry but the generator's numbers ``u`` hold unchanged (``choice``,
    ``lift``, ``align_to_normal``), as :class:`~axialdeform.core.generate.Generate` takes them (None where the
    number is its absent value): a generated form read back."""
    out = {}
    for key in RECIPE:
        if key.uniform is not None and not key.json:
            v = u[key.uniform]
            v = tuple(float(x) for x in v) if isinstance(v, list) else float(v)
            out[key.name] = None if key.optional and v == key.uniform_default else v
    return out


def optional_numbers() -> dict:
    """The numbers a generated form may leave out (keys its first version did not carry), at their values
    when the key is not given: what a reader fills in before it checks a file."""
    return {key.uniform: list(v) if isinstance(v, tuple) else v for key in RECIPE
            if key.uniform is not None and not key.required_json for v in (key.uniform_default,)}

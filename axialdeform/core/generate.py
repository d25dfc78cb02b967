"""Generated layers: a layer's instances as a pure function of a recipe, a seed, a tile and an index.

The numpy reference of ``glsl/generate.glsl`` (as :func:`~axialdeform.core.deform.deform` is of
``glsl/axial.glsl``): the GPU makes the same records by transform feedback
(:mod:`axialdeform.gl.generate`), the tests hold it to this module, and the commands that need the
numbers on the CPU (``bake``, ``export``, ``fit``) materialize a layer here.

The world's ground (``up = y``) is cut into square tiles of side ``T`` (``tile``); tile ``(tx, tz)``
covers ``[tx T, (tx + 1) T) x [tz T, (tz + 1) T)``.  A tile is an ``m x m`` grid of cells of side
``c = T / m``, ``m = max(1, round(T sqrt(rate)))`` (so the rate drawn is ``m^2 / T^2``, within a
factor ``(1 ± 1/(T sqrt(rate)))^2`` of ``rate``).  Instance ``i`` (``0 <= i < m^2``) of a tile stands
in cell ``(i mod m, i div m)``, jittered: ``x = (tx m + cx + 1/2 + j (u0 - 1/2)) c`` (and ``z`` with
``u1``), ``j = 1 - min_distance / c``.  Two instances of neighbouring cells are then at least
``c - j c = min_distance`` apart along the axis that separates them -- the guaranteed minimum
distance, in one tile and across tiles alike (the grid is one grid over the whole world).

Randomness: ``u_k`` (``k = 0 .. 21``; room for 32) is 24 bits of the PCG hash of ``glsl/wind.glsl``
(:func:`~axialdeform.core.wind.wind_hash`) chained over the seed, the tile and ``32 i + k``::

    key = H(H(H(uint tx) ^ uint tz) ^ seed);   u_k = (H(key ^ (32 i + k)) >> 8) / 2^24

(integer maths: bit-exact on every GPU and in numpy).  Then, in float32 as the shader computes them:
a turn about up ``ry = yaw_lo + (yaw_hi - yaw_lo) u2`` (``yaw`` default [0, 2 pi]); offsets
``d_q = bend L (2 u_{3+q} - 1)`` for the ten numbers, every control point then shifted by ``-D(t_a)``,
``t_a`` the anchor's place on the axis, so it stays put;
``s = lo + (hi - lo) u13`` (with ``scale_quartiles``: piecewise linear through ``[lo, q1, q2, q3, hi]`` at
``u13 = 0, 1/4, .., 1``; with ``scale_octiles`` too, through nine knots at ``u13 = 0, 1/8, .., 1``),
``tw = twist (2 u14 - 1)``, ``tp = taper u15`` (19 numbers when any of scale, twist, taper is given), the
tint from ``u17 .. u19`` (22 numbers); ``py`` = the ground's height (0: a flat world; a height map: its
triangles) minus the anchor's height times ``s``, plus the lift (``u21``); kept by the height map, the
altitude and slope bands, the density map (``u16``) and the mesh's share (``u20``); a tree's child axes from
hash streams of their own (:func:`children_table`).
docs/generate.md states every formula.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from .axes import anchor_projection
from .bounds import child_reach
from .deform import bernstein
from .errors import ParamError
from .generate_ground import GroundMaps, cos_sin_f32, ground_height, lean_angles
from .mesh import anchor_point
from .recipe import KINDS, RECIPE, REQUIRED, check_value, passed_through
from .record import EXTENDED_WIDTH, SCALE, SLOT_FLOATS, TAPER, TINT, TINTED_WIDTH, TWIST, WIDTH, join_record
from .variation import tint_of
from .wind import wind_hash

__all__ = ["Generate", "tile_size", "tile_hash_key", "uniforms", "generate_tile", "generate_tiles", "tiles_around",
           "tiles_in", "check_extent", "check_extent_slots", "check_reach", "reach_tiles", "generate_extent",
           "anchor_weights", "recipe_uniforms", "GroundMaps",
           "GENERATED_NUMBERS", "GENERATED_FLOATS", "recipe_json", "children_table",
           "child_bound", "tile_spheres", "extent_box", "world_edge", "slot_limit", "check_slots", "MAX_TILE_SLOTS", "MAX_SLOTS",
           "MAX_BEND", "WORLD_CELLS"]

GENERATED_NUMBERS = 25  # u_0 .. u_24 an instance
CLUMP_PARENTS = 8  # parents an s x s block of cells holds (a layer in clumps)
GENERATED_FLOATS = SLOT_FLOATS  # what the GPU pass writes an instance: the 22-number record, then kept (1) or dropped (0)
HASH_STRIDE = 32  # the hash's numbers an instance (room for more fields)

# ---- bounds, checked from the recipe alone before any array is made (docs/generate.md, "Bounds")
#: the most cells a tile may have (``m^2``)
MAX_TILE_SLOTS = 1 << 20
#: the most slots one command makes at once (an extent, or the tiles within reach); the environment
#: variable ``AXIALDEFORM_MAX_SLOTS`` raises (or lowers) it
MAX_SLOTS = 1 << 22
#: the largest bend amplitude, in axis lengths
MAX_BEND = 100.0
#: the world of a recipe ends ``WORLD_CELLS`` cells from the origin along x and z: there float32 positions
#: are still exact to 1/256 of a cell (2^16 c has a float32 spacing of c / 128), so the guaranteed
#: ``min_distance`` holds to within c / 128 on every tile the generator makes; no tile beyond is made
WORLD_CELLS = 1 << 16


def _from_the_table(cls):
    """Generate's fields from :data:`~axialdeform.core.recipe.RECIPE`: one a key, its default; its docstring's
    attributes the keys' lines."""
    cls.__annotations__ = {key.name: "object" for key in RECIPE}
    for key in RECIPE:
        if key.default is not REQUIRED:
            setattr(cls, key.name, key.default)
    cls.__doc__ += "\n    Attributes\n    ----------\n" + "".join(
        f"    {key.name} : {KINDS[key.kind].expected}{' or None' if key.optional else ''}\n        {key.doc[0].upper()}{key.doc[1:]}"
        f"{'' if key.default in (None, REQUIRED) else f' (default {key.default!r})'}.\n" for key in RECIPE)
    return dataclass(frozen=True)(cls)


@_from_the_table
class Generate:
    """A generated layer's recipe (a scene file's ``[layer.generate]``): one field a key of
    :data:`~axialdeform.core.recipe.RECIPE`, checked by its kind, then against each other (the tile's cells,
    ``min_distance`` below the cell side, the largest bend and scale, the lift within the world's edge).
    """

    def __post_init__(self) -> None:
        def bad(field, expected, value):
            raise ParamError(f"generate: {field}: expected {expected}, found {value!r}")

        for key in RECIPE:
            object.__setattr__(self, key.name, check_value(key, getattr(self, key.name)))
        for b in (self.bend if isinstance(self.bend, tuple) else (self.bend,)):
            if b > MAX_BEND:
                bad("bend", f"at most {MAX_BEND:g} (axis lengths)", self.bend)
        cells = self.tile * math.sqrt(self.rate)
        if not cells < 4 * math.sqrt(MAX_TILE_SLOTS) or max(1, round(cells)) ** 2 > MAX_TILE_SLOTS:
            blame = "tile" if self.rate * 32.0 ** 2 <= MAX_TILE_SLOTS else "rate"  # a tile of 32 would hold the rate
            bad(blame, f"a tile of at most {MAX_TILE_SLOTS} cells (rate x tile^2 = {self.rate * self.tile * self.tile:.6g}): "
                "a smaller tile or a lower rate", getattr(self, blame))
        cell = tile_size(self)[1]
        if self.min_distance >= cell:
            bad("min_distance", f"less than the cell side 1/sqrt(rate) = {cell:.6g} (the rate leaves no more room)",
                self.min_distance)
        if self.lift is not None and max(abs(x) for x in self.lift) > world_edge(self):
            bad("lift", f"heights within the world's edge, +-{world_edge(self):.6g} (WORLD_CELLS cells)", self.lift)
        if self.clumped and self.min_distance > 0:
            bad("min_distance", "0 with clumps (clump_cells, clump_radius: instances of a clump stand anywhere in it)",
                self.min_distance)
        if self.clump_radius > world_edge(self):
            bad("clump_radius", f"at most the world's edge, {world_edge(self):.6g}", self.clump_radius)
        if self.clump_core_radius > self.clump_radius:
            bad("clump_core_radius", f"at most clump_radius, {self.clump_radius:.6g} (the core lies within the clump)",
                self.clump_core_radius)
        if self.scale is not None and self.scale[1] > MAX_BEND:
            bad("scale", f"[lo, hi] with hi at most {MAX_BEND:g}", self.scale)
        q, o = self.scale_quartiles, self.scale_octiles
        if q is not None and (self.scale is None or q[0] < self.scale[0] or q[2] > self.scale[1]):
            bad("scale_quartiles", "three numbers within scale's [lo, hi] (and a scale beside them)", q)
        if o is not None and (q is None or not self.scale[0] <= o[0] <= q[0] <= o[1] <= q[1] <= o[2] <= q[2] <= o[3] <= self.scale[1]):
            bad("scale_octiles", "four numbers between scale_quartiles' (and scale's), beside them", o)

    @property
    def extended(self) -> bool:
        """Whether the records have 19 numbers or more (scale, twist, taper or tint given)."""
        return self.scale is not None or self.twist > 0 or self.taper > 0 or self.tint is not None

    @property
    def width(self) -> int:
        return TINTED_WIDTH if self.tint is not None else EXTENDED_WIDTH if self.extended else WIDTH

    def level_bend(self, depth: int) -> float:
        """The bend amplitude of a hierarchy's level ``depth`` (0: axis 0; the last one beyond)."""
        b = self.bend if isinstance(self.bend, tuple) else (self.bend,)
        return b[min(depth, len(b) - 1)]

    @property
    def spread(self) -> float:
        """How far beyond its cell an instance can stand (world units): 0, or in clumps the parent's cells and the
        clump's radius, ``clump_cells c + clump_radius``."""
        return self.clump_cells * tile_size(self)[1] + self.clump_radius if self.clumped else 0.0

    @property
    def clumped(self) -> bool:
        """Whether instances stand in clumps (``clump_cells`` > 1 or ``clump_radius`` > 0)."""
        return self.clump_cells > 1 or self.clump_radius > 0

    @property
    def needs_heights(self) -> bool:
        """Whether the recipe reads the ground's height map (an altitude or slope band)."""
        return self.altitude is not None or self.slope is not None


def tile_size(recipe: Generate) -> tuple[int, float]:
    """(m, c): cells a side of a tile and the cell side, ``m = max(1, round(T sqrt(rate)))``, ``c = T / m``."""
    m = max(1, int(round(recipe.tile * math.sqrt(recipe.rate))))
    return m, recipe.tile / m


def world_edge(recipe: Generate) -> float:
    """The world's edge ``E = WORLD_CELLS c`` (world units): the generator makes the tiles that lie in
    ``[-E, E]^2`` and no other (float32 positions keep the cell grid, and so ``min_distance``, to c/128 there)."""
    return WORLD_CELLS * tile_size(recipe)[1]


def slot_limit() -> int:
    """The most slots one command makes at once: :data:`MAX_SLOTS`, or ``AXIALDEFORM_MAX_SLOTS``."""
    raw = os.environ.get("AXIALDEFORM_MAX_SLOTS")
    if raw is None:
        return MAX_SLOTS
    try:
        value = int(raw)
    except ValueError:
        value = 0
    if value < 1:
        raise ParamError(f"AXIALDEFORM_MAX_SLOTS: expected a whole number >= 1, found {raw!r:.40}")
    return value


def check_slots(recipe: Generate, tiles: int, what: str, axes: int = 1) -> int:
    """The slots ``tiles`` tiles of ``recipe`` hold (``tiles m^2``), or a :class:`ParamError` when that is
    above :func:`slot_limit` (``what``: what asked for them, named in the message) -- checked before any
    array is made.  A mesh of ``axes`` axes (``BaseMesh.axis_count``) counts each: a slot holds every axis's numbers."""
    m = tile_size(recipe)[0]
    slots = int(tiles) * m * m
    limit = slot_limit()
    if slots * axes > limit:
        more = f" x {axes} axes" if axes > 1 else ""
        raise ParamError(f"generate: {what}: {int(tiles)} tiles of {m * m} cells = {slots}{more} slots; expected at "
                         f"most {limit} (a smaller extent or reach, a lower rate, or raise AXIALDEFORM_MAX_SLOTS)")
    return slots


def _u32(x) -> np.ndarray:
    return (np.asarray(x, dtype=np.int64) & 0xFFFFFFFF).astype(np.uint32)


def tile_hash_key(seed: int, tx, tz) -> np.ndarray:
    """The tile's key ``H(H(H(uint tx) ^ uint tz) ^ seed)`` (uint32; tx, tz may be negative)."""
    return wind_hash(wind_hash(wind_hash(_u32(tx)) ^ _u32(tz)) ^ np.uint32(seed))


def uniforms(key, ids, first: int = 0, count: int | None = None) -> np.ndarray:
    """(n, count) float32 in [0, 1): ``u_k`` of instances ``ids`` of the tile with hash ``key``, k from ``first``
    (default u_0 .. u_24, :data:`GENERATED_NUMBERS`; a layer in clumps draws u_25 too)."""
    ids = _u32(ids)
    k = np.arange(first, GENERATED_NUMBERS if count is None else first + count, dtype=np.uint32)
    with np.errstate(over="ignore"):
        x = (ids[:, None] * np.uint32(HASH_STRIDE) + k[None, :]) ^ np.uint32(key)
    return (wind_hash(x) >> np.uint32(8)).astype(np.float32) * np.float32(1.0 / 16777216.0)


def generate_tile(recipe: Generate, mesh, tx: int, tz: int, maps: GroundMaps | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Every cell's instance of tile (tx, tz): ``(params, kept)`` -- ``(m^2, 16, 19 or 22) float32`` records
    in cell order and the ``(m^2,)`` bool of those kept (over the height map, in the bands, by the density)."""
    m, c = tile_size(recipe)
    n = m * m
    ids = np.arange(n, dtype=np.int64)
    key = tile_hash_key(recipe.seed, tx, tz)
    u = uniforms(key, ids)
    f32 = np.float32
    j = f32(1.0 - recipe.min_distance / c)
    cell = f32(c)
    cx = (np.int64(tx) * m + ids % m).astype(f32)
    cz = (np.int64(tz) * m + ids // m).astype(f32)
    out = np.zeros((n, recipe.width), f32)
    out[:, 10] = (cx + f32(0.5) + j * (u[:, 0] - f32(0.5))) * cell
    out[:, 12] = (cz + f32(0.5) + j * (u[:, 1] - f32(0.5))) * cell
    if recipe.clumped:  # one of the 8 parents of its s x s cells, anywhere in them; the instance in a disc around it
        s_c = f32(recipe.clump_cells)
        px = np.floor((cx + f32(0.5)) / s_c).astype(f32)
        pz = np.floor((cz + f32(0.5)) / s_c).astype(f32)
        pkey = tile_hash_key(recipe.seed ^ 0x9E3779B9, px.astype(np.int64), pz.astype(np.int64))
        q = np.minimum(np.floor(u[:, 24] * f32(CLUMP_PARENTS)), f32(CLUMP_PARENTS - 1)).astype(np.uint32)
        ids_q = q[:, None] * np.uint32(HASH_STRIDE) + np.arange(2, dtype=np.uint32)
        pu = (wind_hash(ids_q ^ pkey[:, None]) >> np.uint32(8)).astype(f32) * f32(1.0 / 16777216.0)
        span = s_c * cell
        cs = cos_sin_f32(f32(2.0 * math.pi) * u[:, 23])
        core = uniforms(key, ids, 25, 1)[:, 0] < f32(recipe.clump_core)  # u25: in the core
        rho = np.where(core, f32(recipe.clump_core_radius), f32(recipe.clump_radius)) * np.sqrt(u[:, 22])
        out[:, 10] = (px + pu[:, 0]) * span + rho * cs[0]
        out[:, 12] = (pz + pu[:, 1]) * span + rho * cs[1]
    out[:, 14] = f32(recipe.yaw[0]) + (f32(recipe.yaw[1]) - f32(recipe.yaw[0])) * u[:, 2]
    amp = f32(recipe.level_bend(0) * mesh.axis.length)
    d = (amp * (f32(2.0) * u[:, 3:13] - f32(1.0))).reshape(n, 5, 2)
    w = anchor_weights(mesh, recipe.anchor)
    at = w[0] * d[:, 0] + w[1] * d[:, 1] + w[2] * d[:, 2] + w[3] * d[:, 3] + w[4] * d[:, 4]  # D(t_a), float32
    out[:, 0:10] = (d - at[:, None, :]).reshape(n, 10)  # every control point shifted: D(t_a) = 0
    s = np.ones(n, f32)
    if recipe.extended:
        lo, hi = recipe.scale if recipe.scale is not None else (1.0, 1.0)
        s = f32(lo) + (f32(hi) - f32(lo)) * u[:, 13]
        if recipe.scale_quartiles is not None:  # piecewise linear through the knots at u13 = 0, 1/4 (1/8), .., 1
            q, o = recipe.scale_quartiles, recipe.scale_octiles
            knots = np.array([lo, *q, hi] if o is None else [lo, o[0], q[0], o[1], q[1], o[2], q[2], o[3], hi], f32)
            spans = f32(len(knots) - 1)
            v = u[:, 13] * spans
            k = np.minimum(np.floor(v), spans - f32(1.0))
            a, b = knots[k.astype(np.int64)], knots[k.astype(np.int64) + 1]
            s = a + (b - a) * (v - k)
        out[:, SCALE] = s
        out[:, TWIST] = f32(recipe.twist) * (f32(2.0) * u[:, 14] - f32(1.0))
        out[:, TAPER] = f32(recipe.taper) * u[:, 15]
    if recipe.tint is not None:
        out[:, TINT] = tint_of(u[:, 17:20], recipe.tint, recipe.tint_color, recipe.tint_hue, f32)
    g = maps if maps is not None else GroundMaps()
    rec = recipe_uniforms(recipe, mesh, g)
    h = np.zeros(n, f32)
    t2 = np.zeros(n, f32)
    kept = np.ones(n, bool)
    xz = out[:, [10, 12]]
    grad = np.zeros((n, 2), f32)
    if g.heights is not None:
        h, t2, kept, grad = ground_height(g, xz)
    alt, band = np.asarray(rec["altitude"], f32), np.asarray(rec["slope_tan2"], f32)
    choice = np.asarray(rec["choice"], f32)
    kept &= (h >= alt[0]) & (h <= alt[1]) & (t2 >= band[0]) & (t2 <= band[1])
    kept &= (u[:, 20] >= choice[0]) & (u[:, 20] < choice[1])
    if g.density is not None:
        c = np.floor((xz - g.d_lo) * g.d_inv).astype(np.int64)
        size = np.array([g.density.shape[1], g.density.shape[0]])
        c = np.mod(c, size) if g.d_wrap else np.clip(c, 0, size - 1)
        kept &= u[:, 16] < g.density[c[:, 1], c[:, 0]]
    lift = np.asarray(rec["lift"], f32)
    ay = np.full(n, f32(rec["anchor_y"]), f32)
    if recipe.align_to_normal > 0 and g.heights is not None:
        out[:, 13:16], ay = lean_angles(rec, out[:, 14], grad)
    out[:, 11] = h - ay * s + (lift[0] + (lift[1] - lift[0]) * u[:, 21])
    if getattr(mesh, "tree", None) is not None:
        out = join_record(out, _children(recipe, mesh, tile_hash_key(recipe.seed, tx, tz), ids))
    return out, kept


def children_table(recipe: Generate, mesh) -> np.ndarray:
    """``(K - 1, 26)`` float32 of a mesh of several axes: child axis j's amplitude ``bend[level] L_j``, then
    its 5 x 5 joint projection (:func:`~axialdeform.core.axes.anchor_projection`), row after row."""
    tree = mesh.tree
    amp = [recipe.level_bend(int(d)) * a.length for d, a in zip(tree.depth[1:], tree.axes[1:])]
    proj = anchor_projection(np.asarray(tree.anchors[1:], dtype=np.float64)).reshape(-1, 25)
    return np.column_stack([amp, proj]).astype(np.float32)


def _children(recipe: Generate, mesh, key, ids) -> np.ndarray:
    """``(n, K - 1, 5, 2)`` float32: the child axes' offsets (axial_generate_child of glsl/generate.glsl)."""
    f32 = np.float32
    table = children_table(recipe, mesh)
    n, k = len(ids), len(table)
    out = np.zeros((n, k, 5, 2), f32)
    base = _u32(ids)[:, None] * np.uint32(HASH_STRIDE) + np.arange(10, dtype=np.uint32)[None, :]
    for j in range(1, k + 1):  # a loop over the axes, not the instances
        with np.errstate(over="ignore"):
            kj = wind_hash(np.uint32(key) + np.uint32(j))
        u = (wind_hash(base ^ kj) >> np.uint32(8)).astype(f32) * f32(1.0 / 16777216.0)
        raw = (table[j - 1, 0] * (f32(2.0) * u - f32(1.0))).reshape(n, 5, 2)
        proj = table[j - 1, 1:].reshape(5, 5)
        for a in range(5):
            acc = np.zeros((n, 2), f32)
            for b in range(5):
                acc = acc + proj[a, b] * raw[:, b]
            out[:, j - 1, a] = acc
    return out


def anchor_weights(mesh, anchor: str = "bottom") -> np.ndarray:
    """(5,) float32: the Bernstein weights ``B4_k(t_a)`` of the base mesh's anchor on its axis: ``t_a`` of
    scatter's ``bottom`` anchor, the centre of its bounding box's lowest face (what stands on the ground:
    a blade's root, a lying stone's middle).  Shifting every control point by ``-D(t_a)`` keeps that
    point where it is put."""
    t = mesh.axis.parameter(anchor_point(mesh, anchor, 1)[None, :])[0]
    return bernstein(np.array(t)).astype(np.float32)


def recipe_uniforms(recipe: Generate, mesh, maps: GroundMaps | None = None) -> dict:
    """The numbers ``glsl/generate.glsl``'s ``AxialRecipe`` takes for ``recipe`` and its base mesh (float64;
    the GPU rounds them to float32 as the numpy reference does): ``seed``, ``m``, ``cell``, ``jitter``,
    ``bend`` (times L), ``scale`` (lo, hi), ``twist``, ``taper``, ``anchor_y``, ``anchor_w`` (4) and
    ``anchor_w4``, the lift, the tint, the ground maps' placement (``has_heights``, ``h_lo``, ``h_inv``, ``h_size``,
    ``has_density``, ``d_lo``, ``d_inv``, ``d_size``, ``d_wrap``) and the bands (``altitude``,
    ``slope_tan2``: tan^2 of the slope's bounds) -- what the desktop generator and the page's are given
    (JSON-able; the maps' pixels travel beside them)."""
    m, cell = tile_size(recipe)
    w = anchor_weights(mesh, recipe.anchor)
    g = maps if maps is not None else GroundMaps()
    fl = lambda a: [float(x) for x in a]  # noqa: E731
    alt = recipe.altitude if recipe.altitude is not None else (-3.0e38, 3.0e38)
    slope = [math.tan(math.radians(a)) ** 2 for a in recipe.slope] if recipe.slope is not None else [0.0, 3.0e38]
    return {**passed_through(recipe), "m": int(m), "cell": float(cell), "jitter": 1.0 - recipe.min_distance / cell,
            "bend": float(recipe.level_bend(0) * mesh.axis.length), "anchor_y": float(anchor_point(mesh, recipe.anchor, 1)[1]),
            "anchor_w": [float(x) for x in w[:4]], "anchor_w4": float(w[4]),
            "has_heights": g.heights is not None, "h_lo": fl(g.h_lo), "h_inv": fl(g.h_inv),
            "h_size": [0, 0] if g.heights is None else [int(g.heights.shape[1]), int(g.heights.shape[0])],
            "has_density": g.density is not None, "d_lo": fl(g.d_lo), "d_inv": fl(g.d_inv),
            "d_size": [0, 0] if g.density is None else [int(g.density.shape[1]), int(g.density.shape[0])],
            "d_wrap": bool(g.d_wrap), "altitude": fl(alt), "slope_tan2": [min(x, 3.0e38) for x in slope],
            "anchor_xz": fl(anchor_point(mesh, recipe.anchor, 1)[[0, 2]])}


def recipe_json(recipe: Generate, reach: float) -> dict:
    """The recipe as the page, the notebook widget and the glTF generated form carry it (JSON): the keys
    :data:`~axialdeform.core.recipe.RECIPE` marks ``json``, as a scene file's ``[layer.generate]`` spells them,
    and the ``reach``."""
    out = {}
    for key in RECIPE:
        if key.json:
            v = getattr(recipe, key.name)
            out[key.name] = list(v) if isinstance(v, tuple) else v
    return {**out, "reach": float(reach)}


def generate_tiles(recipe: Generate, mesh, tiles, maps: GroundMaps | None = None) -> np.ndarray:
    """The kept instances of every tile in ``tiles`` ((k, 2) ints), tile after tile: (n, 16, 19 or 22) float32
    (10 more an instance for every child axis of a mesh of several axes)."""
    parts = []
    for tx, tz in np.asarray(tiles, dtype=np.int64).reshape(-1, 2):
        p, kept = generate_tile(recipe, mesh, int(tx), int(tz), maps)
        parts.append(p[kept])
    tree = getattr(mesh, "tree", None)
    width = recipe.width + (0 if tree is None else 10 * (tree.count - 1))
    return np.concatenate(parts) if parts else np.zeros((0, width), np.float32)


def _world_tiles(recipe: Generate) -> tuple[int, int]:
    """The first and last tile index (along x and z alike) that lies wholly within the world's edge."""
    T, E = float(recipe.tile), world_edge(recipe)
    return math.ceil(-E / T), math.floor(E / T) - 1


def tiles_around(recipe: Generate, x: float, z: float, reach: float) -> np.ndarray:
    """(k, 2) ints: the tiles any point of which lies within ``reach`` of (x, z), nearest first -- those
    within the world's edge (:func:`world_edge`); ParamError when they hold more slots than
    :func:`slot_limit`."""
    x, z, reach = float(x), float(z), float(reach)
    if not (math.isfinite(x) and math.isfinite(z) and math.isfinite(reach) and reach >= 0):
        raise ParamError(f"generate: expected a finite point and reach >= 0, found ({x!r}, {z!r}) and {reach!r}")
    T = recipe.tile
    first, last = _world_tiles(recipe)
    span = lambda v: (max(first, math.floor(max(v - reach, -2.0 ** 62) / T)),  # noqa: E731
                      min(last, math.floor(min(v + reach, 2.0 ** 62) / T)))
    (lo_x, hi_x), (lo_z, hi_z) = span(x), span(z)
    if hi_x < lo_x or hi_z < lo_z:
        return np.zeros((0, 2), np.int64)
    check_slots(recipe, (hi_x - lo_x + 1) * (hi_z - lo_z + 1), "reach")
    tx, tz = np.meshgrid(np.arange(lo_x, hi_x + 1), np.arange(lo_z, hi_z + 1), indexing="ij")
    tiles = np.stack([tx.ravel(), tz.ravel()], 1)
    # the nearest point of each tile to (x, z)
    nx = np.clip(x, tiles[:, 0] * T, (tiles[:, 0] + 1) * T)
    nz = np.clip(z, tiles[:, 1] * T, (tiles[:, 1] + 1) * T)
    dist = np.hypot(nx - x, nz - z)
    keep = dist <= reach
    order = np.argsort(dist[keep], kind="stable")
    return tiles[keep][order]


def reach_tiles(recipe: Generate, reach: float) -> int:
    """The most tiles :func:`tiles_around` can return for ``reach``: ``(ceil(2 reach / T) + 1)^2`` (a
    generated mesh's capacity in tiles, in the page and the npm module alike)."""
    k = math.ceil(2.0 * float(reach) / recipe.tile) + 1
    return k * k


def check_reach(recipe: Generate, reach: float, axes: int = 1) -> int:
    """The slots the tiles within ``reach`` may hold, or a ParamError naming ``reach`` when it is not finite
    and > 0, reaches past the world (2 E), or asks for more slots than :func:`slot_limit`."""
    reach = float(reach)
    E = world_edge(recipe)
    if not (math.isfinite(reach) and 0 < reach <= 2 * E):
        raise ParamError(f"generate: reach: expected a distance > 0 and at most the world's width {2 * E:.6g}, "
                         f"found {reach!r}")
    return check_slots(recipe, reach_tiles(recipe, reach), "reach", axes)


def check_extent(recipe: Generate, extent) -> tuple:
    """``extent`` (x0, z0, x1, z1) as floats, or a ParamError naming ``extent`` when it is not finite,
    empty, or reaches beyond the world's edge (:func:`world_edge`)."""
    try:
        x0, z0, x1, z1 = (float(v) for v in extent)
    except (TypeError, ValueError):
        raise ParamError(f"generate: extent: expected [x0, z0, x1, z1], found {extent!r:.80}") from None
    E = world_edge(recipe)
    if not all(math.isfinite(v) for v in (x0, z0, x1, z1)) or not (x1 > x0 and z1 > z0):
        raise ParamError(f"generate: extent: expected finite [x0, z0, x1, z1] with x1 > x0 and z1 > z0, "
                         f"found {[x0, z0, x1, z1]}")
    if max(abs(x0), abs(z0), abs(x1), abs(z1)) > E:
        raise ParamError(f"generate: extent: expected the ground within the world's edge, +-{E:.6g} "
                         f"(WORLD_CELLS = {WORLD_CELLS} cells of {tile_size(recipe)[1]:.6g}), found {[x0, z0, x1, z1]}")
    return x0, z0, x1, z1


def _extent_span(recipe: Generate, extent) -> tuple[int, int, int, int]:
    """``(lo_x, hi_x, lo_z, hi_z)``: the tile indices within the world whose instances can stand in ``extent``
    (checked): the tiles that meet it grown by :attr:`Generate.spread` (in clumps an instance stands up to that
    far beyond its tile: without those tiles a layer would thin out along its extent's edges)."""
    x0, z0, x1, z1 = check_extent(recipe, extent)
    g = recipe.spread
    x0, z0, x1, z1 = x0 - g, z0 - g, x1 + g, z1 + g
    T = recipe.tile
    first, last = _world_tiles(recipe)
    return (max(first, math.floor(x0 / T)), min(last, math.floor(x1 / T)),
            max(first, math.floor(z0 / T)), min(last, math.floor(z1 / T)))


def check_extent_slots(recipe: Generate, extent, axes: int = 1) -> int:
    """The slots the tiles meeting ``extent`` hold (each of ``axes`` axes), or a ParamError naming ``extent``
    when that is above :func:`slot_limit` -- counted, no tile made."""
    lo_x, hi_x, lo_z, hi_z = _extent_span(recipe, extent)
    return check_slots(recipe, max(0, hi_x - lo_x + 1) * max(0, hi_z - lo_z + 1), "the extent", axes)


def tiles_in(recipe: Generate, extent, axes: int = 1) -> np.ndarray:
    """(k, 2) ints: the tiles whose instances can stand in the ground ``extent`` (x0, z0, x1, z1) within the
    world's edge (those that meet it; in clumps those within :attr:`Generate.spread` of it too); a
    ParamError naming ``extent`` when they hold more slots (of ``axes`` axes each) than :func:`slot_limit`."""
    check_extent_slots(recipe, extent, axes)
    lo_x, hi_x, lo_z, hi_z = _extent_span(recipe, extent)
    if hi_x < lo_x or hi_z < lo_z:
        return np.zeros((0, 2), np.int64)
    tx, tz = np.meshgrid(np.arange(lo_x, hi_x + 1), np.arange(lo_z, hi_z + 1), indexing="ij")
    return np.stack([tx.ravel(), tz.ravel()], 1)


def generate_extent(recipe: Generate, mesh, extent, maps: GroundMaps | None = None) -> np.ndarray:
    """The instances standing in the ground ``extent`` (x0, z0, x1, z1; x0 <= px < x1, z0 <= pz < z1):
    the tiles that meet it, materialized (what ``render``, ``bake``, ``export`` and ``fit`` draw and write)."""
    x0, z0, x1, z1 = check_extent(recipe, extent)
    axes = mesh.axis_count
    p = generate_tiles(recipe, mesh, tiles_in(recipe, extent, axes), maps)
    px, pz = p[:, 10 * axes], p[:, 10 * axes + 2]  # the position follows every axis's offsets
    inside = (px >= x0) & (px < x1) & (pz >= z0) & (pz < z1)
    return p[inside]


def child_bound(recipe: Generate, mesh) -> float:
    """How far a generated tree's child axes can move a vertex (model units; 0 for one axis): child axis
    ``j``'s offsets are ``P_j raw``, ``|raw_b| <= amp_j`` per component, so ``|d_a| <= sqrt 2 amp_j
    sum_b |P_ab|``; summed along each chain (:func:`~axialdeform.core.bounds.child_reach`)."""
    tree = getattr(mesh, "tree", None)
    if tree is None or tree.count < 2:
        return 0.0
    table = children_table(recipe, mesh).astype(np.float64)
    most = np.abs(table[:, 0])[:, None] * np.abs(table[:, 1:].reshape(-1, 5, 5)).sum(axis=2)  # (K - 1, 5)
    worst = np.repeat(most[None, :, :, None], 2, axis=3)  # each component at its bound: |d_a| = sqrt 2 most
    return float(child_reach(tree, worst)[0])


def _reach(recipe: Generate, mesh, maps: GroundMaps | None) -> tuple[float, float, float]:
    """``(y_lo, y_hi, r)``: the heights an instance's position can take and how far its vertices lie from it."""
    g = maps if maps is not None else GroundMaps()
    s_hi = max(recipe.scale) if recipe.scale is not None else 1.0
    s_lo = min(recipe.scale) if recipe.scale is not None else 1.0
    far = float(np.sqrt((np.asarray(mesh.positions, np.float64) ** 2).sum(axis=1)).max())
    local = far + 2.0 * math.sqrt(2.0) * recipe.level_bend(0) * mesh.axis.length + child_bound(recipe, mesh)
    h_lo, h_hi = (0.0, 0.0) if g.heights is None else (float(g.heights.min()), float(g.heights.max()))
    lift = recipe.lift or (0.0, 0.0)
    ay = float(anchor_point(mesh, recipe.anchor, 1)[1])
    ys = [h - ay * s + f for h in (h_lo, h_hi) for s in (s_lo, s_hi) for f in lift]
    return min(ys), max(ys), s_hi * local


def tile_spheres(recipe: Generate, mesh, tiles, maps: GroundMaps | None = None) -> np.ndarray:
    """``(k, 4)`` float64 ``x, y, z, r``: a sphere holding every instance tile ``tiles[k]`` can make, found
    from the recipe alone (no instance made): what a view frames, shadows and stands a ground under when
    the instances live on the GPU.  An instance's vertices lie within ``s (|v| + 2 sqrt 2 bend L + the
    child axes' bound)`` of its position (``|v|``: the base mesh's farthest vertex from its origin;
    ``d_q - D(t_a)``: at most twice ``bend L`` a component); its position lies in its tile, at the ground's
    height range (the height map's lowest and highest; 0 flat) minus the anchor's height times ``s``, plus the lift;
    in clumps up to ``Generate.spread`` beyond its tile."""
    tiles = np.asarray(tiles, dtype=np.float64).reshape(-1, 2)
    T = float(recipe.tile)
    y_lo, y_hi, local = _reach(recipe, mesh, maps)
    radius = math.hypot(T / math.sqrt(2.0) + recipe.spread, (y_hi - y_lo) / 2.0) + local
    out = np.empty((len(tiles), 4))
    out[:, 0], out[:, 2] = (tiles[:, 0] + 0.5) * T, (tiles[:, 1] + 0.5) * T
    out[:, 1], out[:, 3] = (y_lo + y_hi) / 2.0, radius
    return out


def extent_box(recipe: Generate, mesh, extent, maps: GroundMaps | None = None) -> np.ndarray:
    """``(8, 3)`` float64: the corners of the box a generated layer shows over the ground ``extent`` (x0, z0,
    x1, z1), from the recipe alone -- what frames a layer whose instances are made on the GPU (the page's,
    the viewer's) or not at all yet.  Across: the extent widened by half the unbent base mesh's farthest
    vertex from its up axis (instances turn about it; one standing at the edge is half outside on average);
    along up: the heights its positions stand at (:func:`tile_spheres`'s) plus the mesh's lowest and highest
    vertex; both at the recipe's mean scale.  Like the instances' outline it stands for, it is a frame, not a
    bound: a bent or large instance at the very edge may reach a little past it."""
    x0, z0, x1, z1 = (float(v) for v in extent)
    y_lo, y_hi, _ = _reach(recipe, mesh, maps)
    scale = float(np.mean(recipe.scale)) if recipe.scale is not None else 1.0
    v = np.asarray(mesh.positions, np.float64)
    across = 0.5 * scale * float(np.hypot(v[:, 0], v[:, 2]).max()) + recipe.spread
    down, up = scale * float(v[:, 1].min()), scale * float(v[:, 1].max())
    xs, ys, zs = np.meshgrid([x0 - across, x1 + across], [min(y_lo + down, y_lo), max(y_hi + up, y_hi)],
                             [z0 - across, z1 + across], indexing="ij")
    return np.column_stack([xs.ravel(), ys.ravel(), zs.ravel()])

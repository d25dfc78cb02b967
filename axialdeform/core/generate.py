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

Randomness: ``u_k`` (``k = 0 .. 15``; room for 32) is 24 bits of the PCG hash of ``glsl/wind.glsl``
(:func:`~axialdeform.core.wind.wind_hash`) chained over the seed, the tile and ``32 i + k``::

    key = H(H(H(uint tx) ^ uint tz) ^ seed);   u_k = (H(key ^ (32 i + k)) >> 8) / 2^24

(integer maths: bit-exact on every GPU and in numpy).  Then, in float32 as the shader computes them:
a turn about up ``ry = 2 pi u2``; offsets ``d_q = bend L (2 u_{3+q} - 1)`` for the ten numbers, every
control point then shifted by ``-D(t_a)``, ``t_a`` the anchor's place on the axis (the centre of the
base mesh's lowest bounding-box face: a blade's root, a lying stone's middle), so it stays put;
``s = lo + (hi - lo) u13``, ``tw = twist (2 u14 - 1)``, ``tp = taper u15`` (19 numbers when any of
scale, twist, taper is given); ``py`` = the ground's height (0: a flat world) minus the base mesh's
lowest point times ``s`` (the shape stands on the ground).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .deform import bernstein
from .errors import ParamError
from .record import EXTENDED_WIDTH, WIDTH
from .scatter import anchor_point
from .wind import wind_hash

__all__ = ["Generate", "tile_size", "tile_hash_key", "uniforms", "generate_tile", "generate_tiles", "tiles_around",
           "tiles_in", "generate_extent", "lowest_point", "anchor_weights", "recipe_uniforms", "GENERATED_NUMBERS"]

GENERATED_NUMBERS = 16  # u_0 .. u_15 an instance
HASH_STRIDE = 32  # the hash's numbers an instance (room for more fields)


@dataclass(frozen=True)
class Generate:
    """A generated layer's recipe (a scene file's ``[layer.generate]``).

    Attributes
    ----------
    rate : float
        Instances per square unit of ground (before the density map), > 0.
    tile : float
        The side of a tile (world units), > 0.
    min_distance : float
        The guaranteed distance between any two instances, 0 <= min_distance < 1 / sqrt(rate).
    seed : int
        0 .. 2^32 - 1.
    bend : float
        Offsets in [-bend L, bend L] (L: the base mesh's axis length), >= 0.
    scale : (2,) float or None
        A uniform scale drawn in [lo, hi] (> 0); None: 1.
    twist, taper : float
        Twist in [-twist, twist] radians, taper in [0, taper] (< 1).
    """

    rate: float
    tile: float = 16.0
    min_distance: float = 0.0
    seed: int = 0
    bend: float = 0.1
    scale: tuple | None = None
    twist: float = 0.0
    taper: float = 0.0

    def __post_init__(self) -> None:
        def bad(field, expected, value):
            raise ParamError(f"generate: {field}: expected {expected}, found {value!r}")

        for name in ("rate", "tile"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0):
                bad(name, "a finite number > 0", v)
        if not (isinstance(self.seed, int) and not isinstance(self.seed, bool) and 0 <= self.seed < 2**32):
            bad("seed", "an integer 0 .. 4294967295", self.seed)
        for name in ("min_distance", "bend", "twist", "taper"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0):
                bad(name, "a finite number >= 0", v)
        if self.taper >= 1:
            bad("taper", "a number in [0, 1)", self.taper)
        cell = tile_size(self)[1]
        if self.min_distance >= cell:
            bad("min_distance", f"less than the cell side 1/sqrt(rate) = {cell:.6g} (the rate leaves no more room)",
                self.min_distance)
        if self.scale is not None:
            s = self.scale
            if not (isinstance(s, (tuple, list)) and len(s) == 2 and all(isinstance(x, (int, float)) and
                                                                     not isinstance(x, bool) and math.isfinite(x) and x > 0
                                                                     for x in s) and s[0] <= s[1]):
                bad("scale", "[lo, hi] with 0 < lo <= hi", s)
            object.__setattr__(self, "scale", (float(s[0]), float(s[1])))

    @property
    def extended(self) -> bool:
        """Whether the records have 19 numbers (scale, twist or taper given)."""
        return self.scale is not None or self.twist > 0 or self.taper > 0

    @property
    def width(self) -> int:
        return EXTENDED_WIDTH if self.extended else WIDTH


def tile_size(recipe: Generate) -> tuple[int, float]:
    """(m, c): cells a side of a tile and the cell side, ``m = max(1, round(T sqrt(rate)))``, ``c = T / m``."""
    m = max(1, int(round(recipe.tile * math.sqrt(recipe.rate))))
    return m, recipe.tile / m


def _u32(x) -> np.ndarray:
    return (np.asarray(x, dtype=np.int64) & 0xFFFFFFFF).astype(np.uint32)


def tile_hash_key(seed: int, tx, tz) -> np.ndarray:
    """The tile's key ``H(H(H(uint tx) ^ uint tz) ^ seed)`` (uint32; tx, tz may be negative)."""
    return wind_hash(wind_hash(wind_hash(_u32(tx)) ^ _u32(tz)) ^ np.uint32(seed))


def uniforms(key, ids) -> np.ndarray:
    """(n, 16) float32 in [0, 1): ``u_k`` of instances ``ids`` of the tile with hash ``key``."""
    ids = _u32(ids)
    with np.errstate(over="ignore"):
        x = (ids[:, None] * np.uint32(HASH_STRIDE) + np.arange(GENERATED_NUMBERS, dtype=np.uint32)[None, :]) ^ np.uint32(key)
    return (wind_hash(x) >> np.uint32(8)).astype(np.float32) * np.float32(1.0 / 16777216.0)


def generate_tile(recipe: Generate, mesh, tx: int, tz: int) -> tuple[np.ndarray, np.ndarray]:
    """Every cell's instance of tile (tx, tz): ``(params, kept)`` -- ``(m^2, 16 or 19) float32`` records
    in cell order and the ``(m^2,)`` bool of those kept (all of them: a density map is not built yet)."""
    m, c = tile_size(recipe)
    n = m * m
    ids = np.arange(n, dtype=np.int64)
    u = uniforms(tile_hash_key(recipe.seed, tx, tz), ids)
    f32 = np.float32
    j = f32(1.0 - recipe.min_distance / c)
    cell = f32(c)
    cx = (np.int64(tx) * m + ids % m).astype(f32)
    cz = (np.int64(tz) * m + ids // m).astype(f32)
    out = np.zeros((n, recipe.width), f32)
    out[:, 10] = (cx + f32(0.5) + j * (u[:, 0] - f32(0.5))) * cell
    out[:, 12] = (cz + f32(0.5) + j * (u[:, 1] - f32(0.5))) * cell
    out[:, 14] = f32(2.0 * math.pi) * u[:, 2]
    amp = f32(recipe.bend * mesh.axis.length)
    d = (amp * (f32(2.0) * u[:, 3:13] - f32(1.0))).reshape(n, 5, 2)
    w = anchor_weights(mesh)
    at = w[0] * d[:, 0] + w[1] * d[:, 1] + w[2] * d[:, 2] + w[3] * d[:, 3] + w[4] * d[:, 4]  # D(t_a), float32
    out[:, 0:10] = (d - at[:, None, :]).reshape(n, 10)  # every control point shifted: D(t_a) = 0
    s = np.ones(n, f32)
    if recipe.extended:
        lo, hi = recipe.scale if recipe.scale is not None else (1.0, 1.0)
        s = f32(lo) + (f32(hi) - f32(lo)) * u[:, 13]
        out[:, 16] = s
        out[:, 17] = f32(recipe.twist) * (f32(2.0) * u[:, 14] - f32(1.0))
        out[:, 18] = f32(recipe.taper) * u[:, 15]
    out[:, 11] = -f32(lowest_point(mesh)) * s
    kept = np.ones(n, bool)
    return out, kept


def anchor_weights(mesh) -> np.ndarray:
    """(5,) float32: the Bernstein weights ``B4_k(t_a)`` of the base mesh's anchor on its axis: ``t_a`` of
    scatter's ``bottom`` anchor, the centre of its bounding box's lowest face (what stands on the ground:
    a blade's root, a lying stone's middle).  Shifting every control point by ``-D(t_a)`` keeps that
    point where it is put."""
    t = mesh.axis.parameter(anchor_point(mesh, "bottom", 1)[None, :])[0]
    return bernstein(np.array(t)).astype(np.float32)


def recipe_uniforms(recipe: Generate, mesh) -> dict:
    """The numbers ``glsl/generate.glsl``'s ``AxialRecipe`` takes for ``recipe`` and its base mesh (float64;
    the GPU rounds them to float32 as the numpy reference does): ``seed``, ``m``, ``cell``, ``jitter``,
    ``bend`` (times L), ``scale`` (lo, hi), ``twist``, ``taper``, ``lowest``, ``anchor_w`` (4) and
    ``anchor_w4`` -- what the desktop generator and the page's are given (JSON-able)."""
    m, cell = tile_size(recipe)
    lo, hi = recipe.scale if recipe.scale is not None else (1.0, 1.0)
    w = anchor_weights(mesh)
    return {"seed": int(recipe.seed), "m": int(m), "cell": float(cell), "jitter": 1.0 - recipe.min_distance / cell,
            "bend": float(recipe.bend * mesh.axis.length), "scale": [float(lo), float(hi)], "twist": float(recipe.twist),
            "taper": float(recipe.taper), "lowest": lowest_point(mesh), "anchor_w": [float(x) for x in w[:4]],
            "anchor_w4": float(w[4])}


def lowest_point(mesh) -> float:
    """The base mesh's lowest y (its bottom stands on the ground)."""
    return float(np.asarray(mesh.positions)[:, 1].min())


def generate_tiles(recipe: Generate, mesh, tiles) -> np.ndarray:
    """The kept instances of every tile in ``tiles`` ((k, 2) ints), tile after tile: (n, 16 or 19) float32."""
    parts = []
    for tx, tz in np.asarray(tiles, dtype=np.int64).reshape(-1, 2):
        p, kept = generate_tile(recipe, mesh, int(tx), int(tz))
        parts.append(p[kept])
    return np.concatenate(parts) if parts else np.zeros((0, recipe.width), np.float32)


def tiles_around(recipe: Generate, x: float, z: float, reach: float) -> np.ndarray:
    """(k, 2) ints: the tiles any point of which lies within ``reach`` of (x, z), nearest first."""
    T = recipe.tile
    lo_x, hi_x = math.floor((x - reach) / T), math.floor((x + reach) / T)
    lo_z, hi_z = math.floor((z - reach) / T), math.floor((z + reach) / T)
    tx, tz = np.meshgrid(np.arange(lo_x, hi_x + 1), np.arange(lo_z, hi_z + 1), indexing="ij")
    tiles = np.stack([tx.ravel(), tz.ravel()], 1)
    # the nearest point of each tile to (x, z)
    nx = np.clip(x, tiles[:, 0] * T, (tiles[:, 0] + 1) * T)
    nz = np.clip(z, tiles[:, 1] * T, (tiles[:, 1] + 1) * T)
    dist = np.hypot(nx - x, nz - z)
    keep = dist <= reach
    order = np.argsort(dist[keep], kind="stable")
    return tiles[keep][order]


def tiles_in(recipe: Generate, extent) -> np.ndarray:
    """(k, 2) ints: the tiles that meet the ground ``extent`` (x0, z0, x1, z1)."""
    x0, z0, x1, z1 = (float(v) for v in extent)
    T = recipe.tile
    tx, tz = np.meshgrid(np.arange(math.floor(x0 / T), math.floor(x1 / T) + 1),
                         np.arange(math.floor(z0 / T), math.floor(z1 / T) + 1), indexing="ij")
    return np.stack([tx.ravel(), tz.ravel()], 1)


def generate_extent(recipe: Generate, mesh, extent) -> np.ndarray:
    """The instances standing in the ground ``extent`` (x0, z0, x1, z1; x0 <= px < x1, z0 <= pz < z1):
    the tiles that meet it, materialized (what ``render``, ``bake``, ``export`` and ``fit`` draw and write)."""
    x0, z0, x1, z1 = (float(v) for v in extent)
    p = generate_tiles(recipe, mesh, tiles_in(recipe, extent))
    inside = (p[:, 10] >= x0) & (p[:, 10] < x1) & (p[:, 12] >= z0) & (p[:, 12] < z1)
    return p[inside]


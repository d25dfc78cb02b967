"""The glTF generated form (docs/gltf/AXIALDEFORM_bend, ``generate``): a scene's generated layer written as
its recipe -- the generator's numbers and the ground maps -- on an instancing node that also holds a small
plain fallback (the instances of the tile at the extent's centre), so a viewer without the extension
still shows some of the layer and one with it makes the tiles around its camera
(axialdeform-three's ``AxialGLTFPlugin``)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..errors import GltfError, ParamError
from ..generate import (
    Generate,
    GroundMaps,
    check_reach,
    children_table,
    generate_tiles,
    recipe_json,
    recipe_uniforms,
    tile_size,
    tiles_around,
    world_edge,
)
from ..mesh import anchor_point
from ..recipe import ANCHORS, KINDS, RECIPE, accepts, from_numbers, optional_numbers, recipe_key
from .glb import FLOAT

__all__ = ["generated_form", "check_generated", "FALLBACK_TILES", "GeneratedNode", "check_generated_form",
           "read_generated_glb", "MAX_MAP_TEXELS"]

#: the most numbers a ground map or child-axis table of the generated form may hold (4096^2; js/src/core/limits.js)
MAX_MAP_TEXELS = 1 << 24

#: the most tiles the fallback looks through for instances (nearest the extent's centre first)
FALLBACK_TILES = 9


def check_generated(scene, layers) -> None:
    """Refuse a ``generated`` export of a scene without a generated layer."""
    if not any(getattr(layer, "generate", None) is not None for layer in layers):
        raise GltfError(f"{scene.path}: --generated writes a scene's generated layers ([layer.generate]) as their "
                        "recipe; this scene has none (expected --instanced or --baked)")


def generated_form(b, layer) -> tuple[np.ndarray, dict]:
    """A generated layer's fallback instances ((n, 16, 19 or 22) float32: the first tile near its extent's
    centre that keeps any) and the ``generate`` member of its node's ``AXIALDEFORM_bend``: the recipe, the
    generator's numbers (:func:`~axialdeform.core.generate.recipe_uniforms`) and each ground map (and a tree's
    child-axis table) as a FLOAT SCALAR accessor of rows x cols numbers, row after row."""
    gen = layer.generate
    recipe, maps = gen.generate, gen.maps
    x0, z0, x1, z1 = gen.extent
    fallback = np.zeros((0, recipe.width), np.float32)
    for tile in tiles_around(recipe, (x0 + x1) / 2, (z0 + z1) / 2, gen.reach)[:FALLBACK_TILES]:
        fallback = generate_tiles(recipe, layer.mesh, [tile], maps)
        if len(fallback):
            break
    if not len(fallback):
        raise GltfError(f"layer {layer.name}: the {FALLBACK_TILES} tiles nearest its extent's centre keep no "
                        "instance; a generated node needs a fallback of at least one (move the extent)")
    spec = {"recipe": recipe_json(recipe, gen.reach), "uniforms": recipe_uniforms(recipe, layer.mesh, maps)}
    tree = getattr(layer.mesh, "tree", None)  # several axes: each child axis's amplitude and joint projection
    for key in ("heights", "density", "children"):
        grid = (children_table(recipe, layer.mesh) if tree is not None else None) if key == "children" else (
            getattr(maps, key, None) if maps is not None else None)
        if grid is not None:
            data = np.ascontiguousarray(grid, "<f4").ravel()
            spec[key] = {"accessor": b.accessor(b.view(data), FLOAT, len(data), "SCALAR", name=f"{layer.name}_{key}"),
                         "cols": int(grid.shape[1]), "rows": int(grid.shape[0])}
    return fallback, {"generate": spec}


# ---------------------------------------------------------------------------------------------- reading
@dataclass(frozen=True, eq=False)
class GeneratedNode:
    """A node in the generated form, read back (:func:`read_generated_glb`).

    mesh : BaseMesh
        The base mesh with its axis (and axes) as the node records them.
    generate : Generate
        The recipe (its bands, lift, leaning, anchor and share recovered from the generator's numbers).
    reach : float
        The distance around a point within which a viewer makes tiles.
    uniforms : dict
        The generator's numbers the node holds (checked against the recipe).
    maps : GroundMaps
        The height and density maps the node holds (None where it has none)."""

    mesh: object
    generate: Generate
    reach: float
    uniforms: dict
    maps: GroundMaps


_NO_BAND = 3.0e38
_F32_MAX = 3.4028234663852886e38


def _whole(x):
    """``x`` as an int when it is a whole number as JSON gives it (``16`` or ``16.0``: JavaScript's
    ``Number.isInteger`` says yes to both), else None."""
    if isinstance(x, bool):
        return None
    if isinstance(x, int):
        return x
    if isinstance(x, float) and math.isfinite(x) and x.is_integer():
        return int(x)
    return None


def _close(a, b) -> bool:
    return isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a) and abs(a - b) <= 1e-6 * max(1.0, abs(b))


def _pair(v, test=lambda x: isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)) -> bool:
    return isinstance(v, list) and len(v) == 2 and all(test(x) for x in v)


def check_generated_form(spec, axis_length: float, axes: int, map_shapes: dict, where: str) -> tuple[Generate, float, dict]:
    """The generated form's ``generate`` object held to the same rules as the npm plugin's (js/src/core/limits.js,
    ``checkUniforms``): the recipe by :class:`Generate` and its bounds, the slots within reach, and every one of
    the generator's numbers -- what follows from the recipe equal to it, the rest finite and in range, a map's
    size its accessor's.  Returns ``(recipe, reach, numbers)``: the recipe's own keys only, and the generator's
    numbers with those the form's first version lacked at their defaults; a GltfError naming the field."""
    if not isinstance(spec, dict):
        raise GltfError(f"{where}: generate: expected an object (recipe, uniforms)")
    r = spec.get("recipe")
    keys = tuple(key.name for key in RECIPE if key.json)
    if not isinstance(r, dict) or any(k not in keys + ("reach", "extent") for k in r):
        raise GltfError(f"{where}: generate recipe: expected an object of {', '.join(keys + ('reach',))}, found {str(r)[:80]}")
    kw = {k: r[k] for k in keys if k in r}  # null is a value (refused where the field needs one), as in JS
    for k, v in kw.items():
        if isinstance(v, list):
            kw[k] = tuple(v)
        elif KINDS[recipe_key(k).kind].shape == "whole" and _whole(v) is not None:  # 4 or 4.0: JSON's whole numbers
            kw[k] = _whole(v)
    try:
        gen = Generate(**kw)
        reach = r.get("reach", 3.0 * gen.tile)
        if not (isinstance(reach, (int, float)) and not isinstance(reach, bool) and math.isfinite(reach) and reach > 0):
            raise ParamError(f"generate: reach: expected a finite number > 0, found {reach!r}")
        check_reach(gen, reach, axes)  # its range and its slots, each of a tree's axes counted
    except (ParamError, TypeError) as exc:
        raise GltfError(f"{where}: generate recipe: {str(exc).removeprefix('generate: ')}") from None
    u = spec.get("uniforms")
    u = {**optional_numbers(), **u} if isinstance(u, dict) else u  # what the form's first version lacks: its default
    if not isinstance(u, dict):
        raise GltfError(f"{where}: generate uniforms: expected generate.glsl's numbers (seed, m, cell, ...), found {str(u)[:80]}")

    def off(key, expected):
        raise GltfError(f"{where}: generate uniforms: {key}: expected {expected}, found {str(u.get(key))[:80]}")

    m, cell = tile_size(gen)
    E = world_edge(gen)
    bends = gen.bend if isinstance(gen.bend, tuple) else (gen.bend,)
    num = lambda x: isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)  # noqa: E731
    for key in RECIPE:  # the numbers a key goes into unchanged: its value, or (not in the JSON form) its kind's range
        if key.uniform is None:
            continue
        have = u.get(key.uniform)
        if key.json:
            want = getattr(gen, key.name)
            want = key.uniform_default if want is None else want
            same = (_whole(have) == want if KINDS[key.kind].shape == "whole" else
                    isinstance(have, list) and len(have) == len(want) and all(_close(x, y) for x, y in zip(have, want))
                    if isinstance(want, tuple) else _close(have, want))
            if not same:
                off(key.uniform, f"the recipe's {key.name} {list(want) if isinstance(want, tuple) else want}")
        elif not accepts(key.kind, tuple(have) if isinstance(have, list) else have):
            off(key.uniform, KINDS[key.kind].expected)
    if _whole(u.get("m")) != m:
        off("m", f"the recipe's {m} cells a side")
    if not _close(u.get("cell"), cell):
        off("cell", f"the recipe's cell side {cell}")
    if not _close(u.get("jitter"), 1.0 - gen.min_distance / cell):
        off("jitter", f"1 - min_distance / cell = {1.0 - gen.min_distance / cell}")
    if not (num(u.get("bend")) and abs(u["bend"]) <= bends[0] * axis_length * (1 + 1e-6) + 1e-30):
        off("bend", f"the recipe's bend times the axis length, {bends[0] * axis_length}")
    if not num(u.get("anchor_y")):
        off("anchor_y", "a finite number")
    w = u.get("anchor_w")
    if not (isinstance(w, list) and len(w) == 4 and all(num(x) and 0 <= x <= 1 for x in w)):
        off("anchor_w", "four weights in [0, 1]")
    if not (num(u.get("anchor_w4")) and 0 <= u["anchor_w4"] <= 1):
        off("anchor_w4", "a weight in [0, 1]")
    if not _pair(u.get("anchor_xz")):
        off("anchor_xz", "two finite numbers")
    for has, key, size, lo, inv in (("has_heights", "heights", "h_size", "h_lo", "h_inv"),
                                     ("has_density", "density", "d_size", "d_lo", "d_inv")):
        if not isinstance(u.get(has), bool):
            off(has, "true or false")
        shape = map_shapes.get(key)
        if u[has] != (shape is not None):
            off(has, f"true: the node has a {key} map" if shape else f"false: the node has no {key} map")
        sz = u.get(size)
        if not (_pair(sz, lambda x: _whole(x) is not None) and
                ([_whole(x) for x in sz] == [shape[0], shape[1]] if shape else [_whole(x) for x in sz] == [0, 0])):
            off(size, f"the {key} map's [cols, rows] = [{shape[0]}, {shape[1]}]" if shape else "[0, 0]: no map")
        if not _pair(u.get(lo), lambda x: num(x) and abs(x) <= 2 * E):
            off(lo, f"two numbers within the world, +-{2 * E:.6g}")
        if not _pair(u.get(inv), lambda x: num(x) and 0 < x <= _F32_MAX):
            off(inv, "two float32 numbers > 0")
    if not isinstance(u.get("d_wrap"), bool):
        off("d_wrap", "true or false")
    if not (_pair(u.get("altitude"), lambda x: num(x) and abs(x) <= _NO_BAND) and u["altitude"][0] <= u["altitude"][1]):
        off("altitude", "[lo, hi] with lo <= hi")
    if not (_pair(u.get("slope_tan2"), lambda x: num(x) and 0 <= x <= _NO_BAND) and u["slope_tan2"][0] <= u["slope_tan2"][1]):
        off("slope_tan2", "[lo, hi] with 0 <= lo <= hi")
    if max(abs(x) for x in u["lift"]) > E:
        off("lift", f"[lo, hi] within the world's edge +-{E:.6g}")
    return gen, float(reach), u


def read_generated_glb(path, node: str | None = None) -> GeneratedNode:
    """A generated layer's node of a GLB written by ``export --generated`` (or any file in the generated
    form), read as its recipe: :class:`GeneratedNode` (the mesh, the recipe, the reach, the generator's
    numbers and the ground maps), every field checked as the npm plugin checks it before anything is made.
    A GltfError naming the node and the field when the node is not in the generated form or is off."""
    from pathlib import Path

    from .glb import load_glb, read_accessor
    from .gltf_read import BEND_EXTENSION, INSTANCING

    where = str(Path(path))
    gltf = load_glb(path)
    blob = gltf.binary_blob() or b""
    nodes = [nd for nd in gltf.nodes if (nd.extensions or {}).get(INSTANCING) and nd.mesh is not None and
             isinstance((nd.extensions or {}).get(BEND_EXTENSION), dict) and "generate" in nd.extensions[BEND_EXTENSION]]
    if node is not None:
        nodes = [nd for nd in nodes if nd.name == node]
    if len(nodes) != 1:
        raise GltfError(f"{where}: expected one generated node{f' {node!r}' if node else ''} ({BEND_EXTENSION} generate), "
                        f"found {len(nodes)}" + (" (name one with node=)" if len(nodes) > 1 else ""))
    nd = nodes[0]
    mesh, _fallback = _read_fallback(path, nd.name)
    spec = nd.extensions[BEND_EXTENSION]["generate"]
    at = f"{where}: node {nd.name or '0'} {BEND_EXTENSION}"
    grids = {}
    for key in ("heights", "density", "children"):
        m = spec.get(key) if isinstance(spec, dict) else None
        if m is None:
            continue
        if isinstance(m, dict):
            m = {**m, **{k: _whole(m.get(k)) for k in ("cols", "rows")}}
        if not (isinstance(m, dict) and all(isinstance(m.get(k), int) and m[k] > 0 for k in ("cols", "rows"))
                and m["cols"] * m["rows"] <= MAX_MAP_TEXELS):
            raise GltfError(f"{at}: generate {key}: expected {{accessor, cols, rows}} of at most {MAX_MAP_TEXELS} numbers, "
                            f"found {str(m)[:80]}")
        data = read_accessor(gltf, blob, m.get("accessor"), f"generate {key}", at)
        if data.size != m["cols"] * m["rows"]:
            raise GltfError(f"{at}: generate {key}: expected a FLOAT SCALAR accessor of {m['cols']} x {m['rows']}")
        grids[key] = data.reshape(m["rows"], m["cols"]).astype(np.float32)
    shapes = {k: (g.shape[1], g.shape[0]) for k, g in grids.items() if k != "children"}
    gen, reach, u = check_generated_form(spec, float(mesh.axis.length), mesh.axis_count, shapes, at)
    f32 = np.float32
    maps = GroundMaps(heights=grids.get("heights"), h_lo=np.array(u["h_lo"], f32), h_inv=np.array(u["h_inv"], f32),
                      density=grids.get("density"), d_lo=np.array(u["d_lo"], f32), d_inv=np.array(u["d_inv"], f32),
                      d_wrap=bool(u["d_wrap"]))
    alt = None if u["altitude"] == [-_NO_BAND, _NO_BAND] else tuple(u["altitude"])
    slope = None if u["slope_tan2"] == [0.0, _NO_BAND] else tuple(
        math.degrees(math.atan(math.sqrt(min(x, 1e300)))) for x in u["slope_tan2"])
    tol = 1e-6 * float(mesh.axis.length)
    want = np.array([u["anchor_xz"][0], u["anchor_y"], u["anchor_xz"][1]], np.float64)
    anchor = next((a for a in ANCHORS if np.all(np.abs(anchor_point(mesh, a, 1) - want) <= tol)),
                  None)
    if anchor is None:
        raise GltfError(f"{at}: generate uniforms: anchor_y, anchor_xz: expected the base mesh's bottom, center or origin")
    gen = dataclasses.replace(gen, altitude=alt, slope=slope, anchor=anchor, **from_numbers(u))
    return GeneratedNode(mesh, gen, reach, u, maps)


def _read_fallback(path, name):
    from .gltf_read import read_instanced_glb

    return read_instanced_glb(path, node=name, fallback=True)

"""Scene files (TOML, ``tomllib``; ``tomli`` on Python 3.10): the parser.
The format is described in :mod:`axialdeform.core.scene`; errors are
:class:`SceneError` naming the file, the line and the key.

:func:`parse_scene` reads and checks a file and its includes into a :class:`SceneRecipe`: every
key, type and number checked, every file it names found, the light, camera and wind made; no mesh,
surface or parameter file is read and nothing is scattered here -- :func:`axialdeform.core.scene.load_scene`
builds the scene from the recipe, and names the file, line and key of what fails there through
each recipe's :meth:`SceneSource.wrap`."""

from __future__ import annotations

import math
import os
import re
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..axes import AXES_RULES
from ..camera import CameraSpec
from ..errors import AxialDeformError, ParamError, SceneError
from ..look import Look
from ..recipe import KINDS, RECIPE
from ..scatter import ANCHORS, Placement
from ..variation import Variation
from ..wind import Wind
from . import safeio
from .mesh import BUNDLED_MESHES, mesh_source_path
from .safeio import read_regular

__all__ = ["parse_scene", "SceneRecipe", "LayerRecipe", "ScatterRecipe", "GenerateRecipe", "TerrainRecipe", "SceneSource",
           "MAX_INCLUDE_DEPTH", "MAX_INCLUDED_FILES"]


_TOP = {"up", "include", "terrain", "camera", "light", "wind", "layer", "background"}


_TERRAIN = {"mesh", "heightmap", "height_scale", "extent", "color", "resample"}


_CAMERA = {"elevation", "azimuth", "fov", "eye", "target"}


_LIGHT = {"direction", "ambient", "color", "sky", "ground"}


_WIND = {"direction", "strength", "gustiness", "frequency", "wavelength"}


_LAYER = {"name", "mesh", "parts", "axis", "axes", "color", "params", "scatter", "generate", "wind"}


# a recipe's keys (core/recipe.py's table) and the layer's own: where it is made, how far, its maps, its meshes' shares
_GENERATE = {key.name for key in RECIPE if key.in_file} | {"extent", "reach", "density", "weights"}


_SCATTER = {"count", "min_distance", "density", "align_to_normal", "anchor", "scale", "bend", "droop", "seed",
            "allow_fewer", "lift", "surface"}


class SceneSource:
    """A scene file's text, to find the line of a key for messages."""

    def __init__(self, path: Path, text: str, sources: list | None = None) -> None:
        self.path, self.lines = path, text.splitlines()
        #: every file the scene reads (this one, its includes, meshes, parameters, images): shared with includes
        self.sources = [] if sources is None else sources
        self.sources.append(path)

    def line(self, key: str, table: str | None = None, nth: int = 0) -> int:
        """1-based line of ``key = ...`` inside ``[table]`` (the ``nth`` ``[[table]]``), or of the table."""
        start = 0
        if table is not None:
            head = re.compile(r"^\s*\[\[?\s*" + re.escape(table) + r"\s*\]\]?\s*(#.*)?$")
            hits = [i for i, ln in enumerate(self.lines) if head.match(ln)]
            if len(hits) > nth:
                start = hits[nth]
        pat = re.compile(r"^\s*(\[\[?\s*([\w-]+\.)*)?[\"']?" + re.escape(key.split(".")[-1]) + r"[\"']?\s*(=|\]|\.)")
        for i in range(start, len(self.lines)):
            if pat.match(self.lines[i]):
                return i + 1
        return start + 1

    def error(self, message: str, key: str, table: str | None = None, nth: int = 0) -> SceneError:
        return SceneError(f"{self.path}:{self.line(key, table, nth)}: key '{key}': {message}")

    def wrap(self, key: str, table: str | None = None, nth: int = 0):
        """Context: re-raise a library error from building as a SceneError with file, line and key."""
        return _wrap(self, key, table, nth)


@dataclass
class TerrainRecipe:
    """``[terrain]``: a mesh or a height map (``kind``), checked, not read."""

    src: SceneSource
    kind: str  # "mesh" or "heightmap"
    file: Path
    height_scale: float = 1.0
    extent: list | None = None
    resample: bool = False  # a height map larger than the pixel bound read at a lower resolution


@dataclass
class ScatterRecipe:
    """``[layer.scatter]``: :func:`axialdeform.scatter`'s arguments, checked -- its value objects, built here."""

    count: int
    variation: Variation  # bend, droop, scale
    placement: Placement  # min_distance, align_to_normal, anchor, density (a Path); the scene's up is set when drawn
    surface: Path | None  # its own surface (None: the scene's terrain)
    lift: tuple = (0.0, 0.0)
    seed: int = 0
    allow_fewer: bool = False


@dataclass
class GenerateRecipe:
    """``[layer.generate]``: the generator's recipe (:class:`~axialdeform.core.generate.Generate`), the
    ground ``extent`` (x0, z0, x1, z1) that the commands materialize, and the ``reach`` (world units)
    around the camera's target within which ``view`` makes tiles as it moves (default: 3 tiles)."""

    generate: object
    extent: tuple
    reach: float = 0.0
    density: Path | None = None  # the density map's image (the scene builds the ground maps)
    maps: object = None  # GroundMaps: the terrain's heights and the density map (made by the scene)
    mask: Path | None = None  # the painted mask beside the scene file, when there is one (core.brush)


@dataclass
class LayerRecipe:
    """One ``[[layer]]``, checked: what to load and how to make its instances."""

    src: SceneSource
    nth: int
    name: str
    mesh: str | Path  # a bundled name or a file
    frame: object = "auto"
    axes: object = None  # None, "parts", a file or an inline list
    color: tuple | None = None
    wind: bool = False
    params: Path | None = None
    scatter: ScatterRecipe | None = None
    parts: tuple | None = None  # keep only these parts of the mesh file
    generate: GenerateRecipe | None = None


@dataclass
class SceneRecipe:
    """A scene file and its includes, parsed and checked (:func:`parse_scene`)."""

    path: Path
    up: str = "y"
    camera: CameraSpec = field(default_factory=CameraSpec)
    look: Look | None = None
    wind: Wind | None = None
    terrain: TerrainRecipe | None = None
    terrain_color: tuple | None = None
    layers: list = field(default_factory=list)
    #: every file the scene reads (the scene file, includes, meshes, parameters, images)
    sources: list = field(default_factory=list)
    #: the scene files read so far (resolved): a file included again is not read again
    included: set = field(default_factory=set)


#: the deepest chain of includes a scene file may have (a -> b -> c ... is 3)
MAX_INCLUDE_DEPTH = 32
#: the most scene files one scene may read, itself and every include (each is read once)
MAX_INCLUDED_FILES = 256


def _load_toml(path: Path, sources: list | None = None):
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover - Python 3.10
        import tomli as tomllib

    if not os.path.lexists(path):
        raise SceneError(f"{path}: no such scene file")
    # a regular file only (a FIFO or /dev/zero is refused without blocking), of a size
    # whose parse fits in memory (tomllib's objects take up to ~10x the text)
    data = read_regular(path, max(safeio.memory_available() // 12, 1 << 20), "a scene file (.toml)", SceneError)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError(f"{path}: could not read the scene file ({exc})") from None
    del data
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None
    except RecursionError:  # arrays or tables nested hundreds deep: tomllib recurses
        raise SceneError(f"{path}: not a scene file: values nested too deep to read") from None
    return data, SceneSource(path, text, sources)


def _check_keys(src: SceneSource, table: dict, allowed: set, where: str, name: str | None, nth: int = 0) -> None:
    for key in table:
        if key not in allowed:
            raise src.error(f"unknown key in {where}; expected one of {', '.join(sorted(allowed))}", key, name, nth)


def _numbers(src, value, key, table, nth, count: tuple, *, positive=False):
    vals = [value] if isinstance(value, (int, float)) and not isinstance(value, bool) else value
    if (not isinstance(vals, list) or len(vals) not in count
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in vals)
            or (positive and not all(v > 0 for v in vals))):
        n = " or ".join(str(c) for c in count)
        raise src.error(f"expected {n} finite {'positive ' if positive else ''}number(s), found {value!r}", key, table, nth)
    return [float(v) for v in vals]


def _path(src: SceneSource, value, key, table, nth) -> Path:
    if not isinstance(value, str) or not value:
        raise src.error(f"expected a file name (a string), found {value!r}", key, table, nth)
    path = Path(value)
    return path if path.is_absolute() else src.path.parent / path


def _existing(src, value, key, table, nth) -> Path:
    path = _path(src, value, key, table, nth)
    if not path.exists():
        raise src.error(f"no such file {path}", key, table, nth)
    src.sources.append(path)
    return path


def _wrap(src, key, table, nth):
    """Context: re-raise a library error from loading as a SceneError with file, line and key."""

    class _Ctx:
        def __enter__(self):
            return self

        def __exit__(self, typ, exc, tb):
            if exc is not None and isinstance(exc, AxialDeformError) and not isinstance(exc, SceneError):
                raise src.error(str(exc), key, table, nth) from None
            return False

    return _Ctx()


def parse_scene(path: str | os.PathLike) -> SceneRecipe:
    """Read and check a scene file and its includes (see the module docstring): a
    :class:`SceneRecipe` that :func:`axialdeform.core.scene.load_scene` builds."""
    path = Path(path)
    data, src = _load_toml(path)
    scene = SceneRecipe(path=path)
    _check_keys(src, data, _TOP, "the scene", None)
    up = data.get("up", "y")
    if up not in ("x", "y", "z"):
        raise src.error(f"expected one of x, y, z, found {up!r}", "up", None, 0)
    scene.up = up
    for key, allowed in (("terrain", _TERRAIN), ("camera", _CAMERA), ("light", _LIGHT), ("wind", _WIND)):
        if key in data and not isinstance(data[key], dict):
            raise src.error("expected a table", key, None, 0)
        _check_keys(src, data.get(key, {}), allowed, f"[{key}]", key)
    _read_view(src, data, scene)
    scene.terrain = _read_terrain(src, data.get("terrain"), scene)
    if "wind" in data:

        w = data["wind"]
        kwargs = {k: (tuple(_numbers(src, v, k, "wind", 0, (3,))) if k == "direction" else
                      _numbers(src, v, k, "wind", 0, (1,))[0]) for k, v in w.items()}
        with _wrap(src, next(iter(w), "wind"), "wind", 0):
            scene.wind = Wind(**kwargs)
    scene.included.add(path.resolve())
    _read_layers(src, data, scene, stack=(path.resolve(),))
    scene.sources = list(dict.fromkeys(src.sources))
    return scene


def _read_view(src, data, scene) -> None:
    cam = data.get("camera", {})
    out = {}
    for key in ("elevation", "azimuth", "fov"):
        if key in cam:
            out[key] = _numbers(src, cam[key], key, "camera", 0, (1,))[0]
    for key in ("eye", "target"):
        if key in cam:
            out[key] = tuple(_numbers(src, cam[key], key, "camera", 0, (3,)))
    if ("eye" in out) != ("target" in out):
        raise src.error("eye and target go together; expected both or neither", "eye" if "eye" in out else "target",
                        "camera", 0)
    scene.camera = CameraSpec(**out)
    light = data.get("light", {})
    lo = {}
    if "direction" in light:
        lo["light_dir"] = tuple(_numbers(src, light["direction"], "direction", "light", 0, (3,)))
    if "ambient" in light:
        lo["ambient"] = _numbers(src, light["ambient"], "ambient", "light", 0, (1,))[0]
    for key, name in (("color", "light_color"), ("sky", "sky_color"), ("ground", "ground_color")):
        if key in light:  # the fields of axialdeform.Look
            lo[name] = tuple(_numbers(src, light[key], key, "light", 0, (3,)))
    if "background" in data:
        lo["background"] = tuple(_numbers(src, data["background"], "background", None, 0, (3,)))
    with _wrap(src, next(iter(light), "light"), "light", 0):
        scene.look = Look(**lo)


def _read_terrain(src, terrain, scene) -> TerrainRecipe | None:
    """``[terrain]`` checked (its colour set on the recipe); None without one."""
    if not terrain:
        return None

    if ("mesh" in terrain) == ("heightmap" in terrain):
        raise src.error("expected exactly one of 'mesh' or 'heightmap'", next(iter(terrain), "terrain"), "terrain", 0)
    key = "mesh" if "mesh" in terrain else "heightmap"
    file = _existing(src, terrain[key], key, "terrain", 0)
    hs = _numbers(src, terrain.get("height_scale", 1.0), "height_scale", "terrain", 0, (1,))[0]
    extent = terrain.get("extent")
    if extent is not None:
        extent = _numbers(src, extent, "extent", "terrain", 0, (1, 2), positive=True)
    if "color" in terrain:
        scene.terrain_color = tuple(_numbers(src, terrain["color"], "color", "terrain", 0, (3,)))
    resample = terrain.get("resample", False)
    if not isinstance(resample, bool):
        raise src.error(f"expected true or false, found {resample!r:.40}", "resample", "terrain", 0)
    return TerrainRecipe(src, key, file, hs, extent, resample)


def _read_layers(src, data, scene, stack) -> None:
    includes = data.get("include", [])
    if isinstance(includes, str):
        includes = [includes]
    if not isinstance(includes, list):
        raise src.error(f"expected a list of scene files, found {includes!r}", "include", None, 0)
    for item in includes:
        inc = _existing(src, item, "include", None, 0)
        if inc.resolve() in stack:
            chain = " -> ".join(str(p) for p in (*stack, inc.resolve()))
            raise src.error(f"include cycle: {chain}", "include", None, 0)
        if len(stack) >= MAX_INCLUDE_DEPTH:
            raise src.error(f"includes nested {len(stack)} deep; expected at most {MAX_INCLUDE_DEPTH} (a -> b -> ...)",
                            "include", None, 0)
        if inc.resolve() in scene.included:  # included before (a diamond, not a cycle): its layers are in
            continue
        if len(scene.included) >= MAX_INCLUDED_FILES:
            raise src.error(f"the scene reads more than {MAX_INCLUDED_FILES} scene files; expected at most "
                            f"{MAX_INCLUDED_FILES} (itself and its includes)", "include", None, 0)
        scene.included.add(inc.resolve())
        sub, sub_src = _load_toml(inc, src.sources)
        _check_keys(sub_src, sub, _TOP, "the scene", None)
        _read_layers(sub_src, sub, scene, (*stack, inc.resolve()))
    layers = data.get("layer", [])
    if not isinstance(layers, list):
        raise src.error("expected [[layer]] tables", "layer", None, 0)
    for nth, layer in enumerate(layers):  # every key first: no loading before the file is known good
        if not isinstance(layer, dict):
            raise src.error("expected [[layer]] tables", "layer", None, 0)
        _check_keys(src, layer, _LAYER, f"layer {nth + 1}", "layer", nth)
        if isinstance(layer.get("scatter"), dict):
            _check_keys(src, layer["scatter"], _SCATTER, f"layer {nth + 1} scatter", "layer", nth)
        if isinstance(layer.get("generate"), dict):
            _check_keys(src, layer["generate"], _GENERATE, f"layer {nth + 1} generate", "layer", nth)
    for nth, layer in enumerate(layers):
        name = layer.get("name", f"layer{len(scene.layers) + 1}")
        if any(done.name == name for done in scene.layers):
            raise src.error(f"a second layer named {name!r}; expected unique layer names", "name", "layer", nth)
        if isinstance(layer.get("mesh"), list):  # several meshes in one generated layer, by weights
            scene.layers.extend(_mixed_layers(src, layer, nth, scene, name))
            continue
        if isinstance(layer.get("generate"), dict) and "weights" in layer["generate"]:
            raise src.error("weights pick among several meshes; expected mesh = [...] beside them", "weights", "layer", nth)
        scene.layers.append(_read_layer(src, layer, nth, scene, name))


def _mixed_layers(src, layer, nth, scene, name) -> list:
    """``mesh = [a, b, ...]`` with ``[layer.generate] weights = [...]``: one generated layer a mesh (named
    NAME-1, NAME-2, ...), all on the recipe's one grid; each keeps the instances whose ``u20`` falls in its
    share of [0, 1) (docs/generate.md), so together they are the recipe's instances, each one mesh."""
    meshes = layer["mesh"]
    gen = layer.get("generate")
    if not isinstance(gen, dict):
        raise src.error("several meshes in one layer need a [layer.generate] recipe (their weights)", "mesh", "layer", nth)
    if not (meshes and all(isinstance(m, str) for m in meshes)) or len(meshes) > 16:
        raise src.error(f"expected 1 to 16 mesh names, found {meshes!r:.80}", "mesh", "layer", nth)
    weights = _numbers(src, gen.get("weights", [1.0] * len(meshes)), "weights", "layer", nth, (len(meshes),),
                       positive=True)
    weights = np.asarray(weights, np.float64) / np.max(weights)  # 1e308 twice is two halves, not inf / inf
    edges = np.concatenate([[0.0], np.cumsum(weights) / np.sum(weights)])
    edges[-1] = 1.0
    out = []
    for k, mesh in enumerate(meshes):
        sub_name = f"{name}-{k + 1}"
        if any(done.name == sub_name for done in scene.layers):
            raise src.error(f"a second layer named {sub_name!r}; expected unique layer names", "name", "layer", nth)
        sub = _read_layer(src, {**layer, "mesh": mesh, "generate": {x: v for x, v in gen.items() if x != "weights"}},
                          nth, scene, sub_name)
        sub.name = sub_name
        sub.generate = replace(sub.generate, generate=replace(sub.generate.generate, choice=(float(edges[k]),
                                                                                          float(edges[k + 1]))))
        out.append(sub)
    return out


def _read_layer(src, layer, nth, scene, default_name) -> LayerRecipe:
    _check_keys(src, layer, _LAYER, f"layer {nth + 1}", "layer", nth)
    if "mesh" not in layer:
        raise src.error("every layer needs a mesh (a file or 'stone' / 'leaf')", "layer", "layer", nth)
    name = layer.get("name", default_name)
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise src.error(f"expected a name of letters, digits, _ . -, found {name!r}", "name", "layer", nth)
    mesh_value = layer["mesh"]
    # the axis frame (docs/method.md): "auto" | "x" | "y" | "z" | "oriented" | three rows of three numbers
    frame = layer.get("axis", "auto")
    if not isinstance(frame, str):  # [[e_a], [e_u], [e_v]] or nine numbers
        flat = [x for row in frame for x in row] if isinstance(frame, list) and all(
            isinstance(row, list) for row in frame) and len(frame) == 3 else frame
        frame = np.reshape(_numbers(src, flat, "axis", "layer", nth, (9,)), (3, 3))

    if isinstance(mesh_value, str) and mesh_value in BUNDLED_MESHES:
        mesh = mesh_value
        src.sources.append(mesh_source_path(mesh_value))
    else:
        mesh = _existing(src, mesh_value, "mesh", "layer", nth)
    axes = None
    if "axes" in layer:  # several axes: a rule ("skeleton", "parts", "auto"), a TOML file of [[axis]] tables, or tables
        axes = layer["axes"]
        if isinstance(axes, str) and axes not in AXES_RULES:
            axes = _existing(src, axes, "axes", "layer", nth)
        elif not (axes in AXES_RULES or isinstance(axes, list)):
            raise src.error(f"expected 'skeleton', 'parts', 'auto', a file name or an array of {{part, parent, axis}} tables, "
                            f"found {axes!r}", "axes", "layer", nth)
    color = tuple(_numbers(src, layer["color"], "color", "layer", nth, (3,))) if "color" in layer else None
    wind = layer.get("wind", False)
    if not isinstance(wind, bool):
        raise src.error(f"expected true or false, found {wind!r}", "wind", "layer", nth)
    if sum(k in layer for k in ("params", "scatter", "generate")) != 1:
        raise src.error("expected exactly one of 'params' (a parameter file), a [layer.scatter] recipe or a "
                        "[layer.generate] recipe", "mesh", "layer", nth)
    parts = layer.get("parts")
    if parts is not None and not (isinstance(parts, list) and parts and all(isinstance(p, str) for p in parts)):
        raise src.error(f"expected an array of part names (the mesh file's), found {parts!r:.80}", "parts", "layer", nth)
    recipe = LayerRecipe(src, nth, name, mesh, frame, axes, color, wind)
    recipe.parts = None if parts is None else tuple(parts)
    if "params" in layer:
        recipe.params = _existing(src, layer["params"], "params", "layer", nth)
    elif "generate" in layer:
        recipe.generate = _generate_layer(src, layer["generate"], nth, scene)
    else:
        recipe.scatter = _scatter_layer(src, layer["scatter"], nth, scene)
    return recipe


def _generate_layer(src, recipe, nth, scene) -> GenerateRecipe:
    """``[layer.generate]``, checked: every key's type here, the recipe's own rules by Generate.  Without an
    ``extent`` on a height-map terrain the layer covers the terrain (its extent set when the scene is built)."""
    from ..generate import Generate, check_extent, check_extent_slots, check_reach

    if not isinstance(recipe, dict):
        raise src.error("expected a table [layer.generate]", "generate", "layer", nth)
    _check_keys(src, recipe, _GENERATE, f"layer {nth + 1} generate", "layer", nth)
    if "rate" not in recipe:
        raise src.error("a generate recipe needs a rate (instances per square unit of ground)", "generate", "layer", nth)
    covers = "extent" not in recipe and scene.terrain is not None and scene.terrain.kind == "heightmap"
    if "extent" not in recipe and not covers:
        raise src.error("a generate recipe needs an extent [x0, z0, x1, z1]: the ground the commands make (on a "
                        "height-map terrain it covers the terrain)", "generate", "layer", nth)
    kwargs = {key.name: _recipe_value(src, key, recipe[key.name], nth) for key in RECIPE if key.in_file and key.name in recipe}
    density = _existing(src, recipe["density"], "density", "layer", nth) if "density" in recipe else None
    extent = None if covers else tuple(float(x) for x in _numbers(src, recipe["extent"], "extent", "layer", nth, (4,)))
    reach = float(_numbers(src, recipe["reach"], "reach", "layer", nth, (1,), positive=True)[0]) if "reach" in recipe else None
    try:
        gen = Generate(**kwargs)
        extent = None if covers else check_extent(gen, extent)
        reach = reach if reach is not None else 3.0 * gen.tile
        check_reach(gen, reach)
        if not covers:
            check_extent_slots(gen, extent)  # counted, not made (a tree's axes counted when the scene is built)
    except ParamError as exc:  # "generate: FIELD: what was expected": the field's own line
        _, field, said = (str(exc).split(": ", 2) + ["", ""])[:3]
        field = {"the extent": "extent", "the tiles within reach": "reach"}.get(field, field)
        if field not in recipe:
            raise src.error(str(exc), "generate", "layer", nth) from None
        raise src.error(said, field, "layer", nth) from None
    return GenerateRecipe(gen, extent, reach, density)


def _recipe_value(src, key, value, nth):
    """A recipe key's value as its kind spells it in a file (core/recipe.py): its type here, its range by Generate."""
    shape = KINDS[key.kind].shape
    if shape == "word":
        return value
    if shape == "whole":
        if not isinstance(value, int) or isinstance(value, bool):
            raise src.error(f"expected a whole number, found {value!r}", key.name, "layer", nth)
        return value
    counts = {"number": (1,), "levels": tuple(range(1, 17)), "pair": (2,), "triple": (3,), "quad": (4,)}[shape]
    numbers = _numbers(src, value, key.name, "layer", nth, counts, positive=key.kind in ("scale", "quartiles", "octiles"))
    return numbers[0] if shape == "number" or (shape == "levels" and len(numbers) == 1) else tuple(numbers)


def _scatter_layer(src, recipe, nth, scene) -> ScatterRecipe:
    if not isinstance(recipe, dict):
        raise src.error("expected a table [layer.scatter]", "scatter", "layer", nth)
    _check_keys(src, recipe, _SCATTER, f"layer {nth + 1} scatter", "layer", nth)
    if "count" not in recipe:
        raise src.error("a scatter recipe needs a count", "scatter", "layer", nth)
    count = recipe["count"]
    if not isinstance(count, int) or isinstance(count, bool) or count < 0:
        raise src.error(f"expected a whole number >= 0, found {count!r}", "count", "layer", nth)
    kwargs = {}
    for key in ("min_distance", "align_to_normal", "bend", "droop"):
        if key in recipe:
            if key == "bend" and isinstance(recipe[key], list):  # several axes: an amplitude per level
                kwargs[key] = tuple(_numbers(src, recipe[key], key, "layer", nth, tuple(range(1, 9))))
            else:
                kwargs[key] = _numbers(src, recipe[key], key, "layer", nth, (1,))[0]
    if "scale" in recipe:
        kwargs["scale"] = tuple(_numbers(src, recipe["scale"], "scale", "layer", nth, (1, 2), positive=True) * 2)[:2]
    for key, kind, what in (("anchor", str, "a string"), ("seed", int, "a whole number"),
                            ("allow_fewer", bool, "true or false")):
        if key in recipe:
            if not isinstance(recipe[key], kind) or (kind is int and isinstance(recipe[key], bool)):
                raise src.error(f"expected {what}, found {recipe[key]!r}", key, "layer", nth)
            kwargs[key] = recipe[key]

    if kwargs.get("anchor", "bottom") not in ANCHORS:
        raise src.error(f"expected one of {', '.join(ANCHORS)}, found {kwargs['anchor']!r}", "anchor", "layer", nth)
    if "density" in recipe:
        kwargs["density"] = _existing(src, recipe["density"], "density", "layer", nth)
    surface = _existing(src, recipe["surface"], "surface", "layer", nth) if "surface" in recipe else None
    if surface is None and scene.terrain is None:
        raise src.error("a scatter recipe needs a [terrain] in the scene or a 'surface' key", "scatter", "layer", nth)
    lift = _numbers(src, recipe.get("lift", [0.0, 0.0]), "lift", "layer", nth, (1, 2))
    # the value objects scatter takes, built here (each field's check names this file, line and key)
    values = {}
    for kind in (Variation, Placement):
        own = {k: kwargs[k] for k in kind.__dataclass_fields__ if k in kwargs}
        with src.wrap(next(iter(own), "scatter"), "layer", nth):
            values[kind] = kind(**own)
    return ScatterRecipe(count, values[Variation], values[Placement], surface, (lift[0], lift[-1]),
                         seed=kwargs.get("seed", 0), allow_fewer=kwargs.get("allow_fewer", False))

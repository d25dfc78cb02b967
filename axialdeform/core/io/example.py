"""Examples to learn scenery from (``axialdeform learn``, docs/learn.md) and the scene file a learned layer is
written as.

:func:`read_example` reads what users have:

* a **CSV table** of objects (a survey): a header row, columns ``x`` and ``z`` (world units on the terrain),
  optional ``size`` (any unit) and ``kind`` (a word: one layer a kind); other columns are ignored;
* a **parameter file** (``.adp``, ``.txt``): each instance's position, its scale (19 numbers and more) as
  its size, its turn about up;
* a **glTF scene**: in a ``.glb``, the instances of every ``EXT_mesh_gpu_instancing`` node (this library's
  export, with ``AXIALDEFORM_bend``, or any other's) and every other node that has a mesh (as editors
  export a hand-placed patch), each with its world matrix; a text ``.gltf``: one object a node that has a
  mesh (trimesh's scene graph). Each object's place, its scale (the mean of the three) and its turn, and its
  kind from its node's name less a trailing number (``Pine.003``: ``Pine``; one kind: no kinds); a node that
  is the ground they stand on is none of them (:mod:`~axialdeform.core.io.example_gltf`).

The window (the ground the example covers) is given, or the objects' bounding box grown by half a mean
spacing on each side (a glTF's own ground: its footprint, grown to hold every object).
:func:`write_learned_scene` writes a scene file: the terrain's table and one generated layer a learned kind,
each with its density map (a 16-bit PNG) beside the file, every file atomically.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from pathlib import Path

import numpy as np
from PIL import Image

from ..errors import AxialDeformError, ExampleError
from ..generate_ground import GroundMaps
from ..ground_features import FEATURES, GroundFeatures
from ..learn import Example, layer_recipe, learn_layers
from ..marks import standard_records, turn_and_up
from ..record import ANGLES, POSITION, SCALE, is_record_width
from ..scene import load_scene
from ..surface import load_density, load_surface
from ..transforms import rotation_matrices
from .atomic import atomic_path, atomic_write_text
from .example_gltf import glb_objects, gltf_objects
from .glb import INSTANCING
from .mesh import load_mesh, with_axes
from .params import read_params
from .safeio import open_regular
from .scene import parse_scene

__all__ = ["read_example", "write_learned_scene", "read_terrain", "learn_layer", "write_learned", "learned_paths", "layer_mesh",
           "MAX_EXAMPLE_BYTES"]

#: a learned layer's keys of its objects (a scene file layer's): what ``learn --layer`` carries over from the example's layer
MESH_KEYS = ("mesh", "axis", "axes", "parts", "color", "wind")
#: ... and the keys of its recipe that say how its objects stand (``[layer.scatter]``'s or ``[layer.generate]``'s):
#: the learned recipe's too, as its mesh is the layer's
STAND_KEYS = ("anchor", "lift")
#: the largest example file read (bytes)
MAX_EXAMPLE_BYTES = 1 << 30


def _window(xz: np.ndarray, window, name: str) -> tuple:
    if window is not None:
        x0, z0, x1, z1 = (float(v) for v in window)
        if not (x1 > x0 and z1 > z0) or not all(math.isfinite(v) for v in (x0, z0, x1, z1)):
            raise ExampleError(f"{name}: window: expected [x0, z0, x1, z1] with x1 > x0 and z1 > z0, found {list(window)}")
        out = (xz[:, 0] < x0) | (xz[:, 0] > x1) | (xz[:, 1] < z0) | (xz[:, 1] > z1)
        if out.any():
            i = int(np.argmax(out))
            raise ExampleError(f"{name}: object {i + 1} at ({xz[i, 0]:g}, {xz[i, 1]:g}): expected inside the window "
                               f"[{x0:g}, {z0:g}, {x1:g}, {z1:g}]")
        return x0, z0, x1, z1
    lo, hi = xz.min(axis=0), xz.max(axis=0)
    span = hi - lo
    if len(xz) < 3 or not (span > 0).all():
        raise ExampleError(f"{name}: expected at least 3 objects spread over x and z to find the ground they cover "
                           "(or give a window)")
    pad = 0.5 * math.sqrt(span[0] * span[1] / len(xz))
    return float(lo[0] - pad), float(lo[1] - pad), float(hi[0] + pad), float(hi[1] + pad)


def _number(text: str, name: str, row: int, column: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not math.isfinite(v):
        raise ExampleError(f"{name}: row {row}: column '{column}': expected a finite number, found {text!r:.40}")
    return v


def _read_csv(path: Path) -> dict:
    name = str(path)
    with open_regular(path, "a CSV table", ExampleError) as (fh, size):
        if size > MAX_EXAMPLE_BYTES:
            raise ExampleError(f"{name}: a file of {size} bytes; expected at most {MAX_EXAMPLE_BYTES}")
        try:
            text = fh.read().decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise ExampleError(f"{name}: not UTF-8 text at byte {exc.start}; expected a CSV table") from None
    try:
        rows = list(csv.reader(io.StringIO(text)))
    except csv.Error as exc:
        raise ExampleError(f"{name}: not a CSV table ({exc})") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if not rows:
        raise ExampleError(f"{name}: empty; expected a header row with columns x and z, then one row an object")
    header = [c.strip().lower() for c in rows[0]]
    missing = [c for c in ("x", "z") if c not in header]
    if missing:
        raise ExampleError(f"{name}: header: expected columns x and z (and optional size, kind), found {rows[0]!r:.80}")
    col = {c: header.index(c) for c in ("x", "z", "size", "kind") if c in header}
    xz, size, kind = [], [], []
    for n, r in enumerate(rows[1:], start=2):
        if len(r) < len(header):
            raise ExampleError(f"{name}: row {n}: expected {len(header)} columns as the header, found {len(r)}")
        xz.append((_number(r[col["x"]], name, n, "x"), _number(r[col["z"]], name, n, "z")))
        if "size" in col:
            s = _number(r[col["size"]], name, n, "size")
            if s <= 0:
                raise ExampleError(f"{name}: row {n}: column 'size': expected a number > 0, found {r[col['size']]!r:.40}")
            size.append(s)
        if "kind" in col:
            k = r[col["kind"]].strip()
            if not k:
                raise ExampleError(f"{name}: row {n}: column 'kind': expected a word, found nothing")
            kind.append(k)
    if not xz:
        raise ExampleError(f"{name}: no rows after the header; expected one row an object")
    return {"xz": np.array(xz, np.float64), "size": np.array(size) if size else None,
            "kind": np.array(kind, dtype=object) if kind else None}


def _read_records(params: np.ndarray, name: str) -> dict:
    """Each record's place, its scale as its size, its turn about up (axis 0's standard record: a tree's child
    axes' offsets stand before its position), and the records themselves."""
    params = np.asarray(params, np.float64)
    if params.ndim != 2 or not is_record_width(params.shape[1]):
        raise ExampleError(f"{name}: expected records of 10 K + 6 (+ 3, + 6) numbers an object, found an array of shape "
                           f"{params.shape}")
    rec = standard_records(params)
    size = rec[:, SCALE] if rec.shape[1] > SCALE else None
    yaw, up = turn_and_up(rotation_matrices(rec[:, ANGLES]))
    return {"xz": rec[:, POSITION][:, [0, 2]], "size": size, "yaw": yaw, "up": up, "records": params}


def _fitted(data: dict, mesh, name: str) -> dict:
    """The records of placed objects each its own bent copy of ``mesh`` (the library's baked export, an editor's
    bent duplicates): fitted (``core/fit.py``, the 19 numbers) to their world vertices; their places, sizes and
    turns are the fitted ones."""
    from ..fit import fit_params

    shapes, names = data["vertices"], data["names"]
    for k, v in enumerate(shapes):
        if v is None:
            raise ExampleError(f"{name}: object {k + 1} (node {names[k]}): an instance of {INSTANCING}; fit expects one "
                               "node an object, each its own bent copy of the mesh")
        if len(v) not in (mesh.vertex_count, mesh.source_count):
            raise ExampleError(f"{name}: object {k + 1} (node {names[k]}): {len(v)} vertices; expected the mesh's "
                               f"{mesh.vertex_count} in its order, to fit it")
    res = fit_params(mesh, shapes, extended=True)
    if res.exceeds.any():
        k = res.worst
        raise ExampleError(f"{name}: object {k + 1} (node {names[k]}): expected a bent copy of the mesh, found one its "
                           f"best fit misses by {res.max[k]:.3g} axis lengths at a vertex (at most {res.max_residual:g})")
    return {**_read_records(res.params, name), "kind": data.get("kind"), "ground": data.get("ground")}


def read_example(source, window=None, *, layer: str | None = None, fit=None, bounds=None) -> Example:
    """An :class:`~axialdeform.core.learn.Example` from a CSV table, a parameter file, a glTF scene, a scene
    file's layer (``layer``: its name; the layer's instances as drawn), or an (n, 16+) parameter array.

    window : (x0, z0, x1, z1) or None
        The ground the example covers (None: the objects' bounding box grown by half a mean spacing).
    fit : BaseMesh or None
        A ``.glb`` of one node an object, each its own bent copy of this mesh (the same vertices in the same
        order: the library's baked export, an editor's bent duplicates): each object's record is fitted to its
        vertices (``core/fit.py``), so its bend, scale, twist and taper are learned too.
    bounds : (x0, z0, x1, z1) or None
        The terrain's ground: the default window is cut to it.
    """
    if fit is not None and not (isinstance(source, (str, os.PathLike)) and Path(source).suffix.lower() == ".glb"):
        name = str(source) if isinstance(source, (str, os.PathLike)) else "<params>"  # refused before it is read
        raise ExampleError(f"{name}: fit: expected a .glb of placed objects, one node an object, to fit")
    if not isinstance(source, (str, os.PathLike)):
        data, name = _read_records(source, "<params>"), "<params>"
    else:
        path, name = Path(source), str(source)
        suffix = path.suffix.lower()
        if suffix == ".csv":
            data = _read_csv(path)
        elif suffix == ".glb":
            data = glb_objects(path, vertices=fit is not None)
            if fit is not None:
                data = _fitted(data, fit, name)
        elif suffix == ".gltf":
            data = gltf_objects(path)
        elif suffix == ".toml":
            scene = load_scene(path)
            names = [lay.name for lay in scene.layers]
            if layer not in names:
                raise ExampleError(f"{name}: layer: expected one of {', '.join(names) or 'none'} (--layer NAME), found {layer!r}")
            data = _read_records(scene.layers[names.index(layer)].params, name)
        else:
            data = _read_records(read_params(path, allow_mesh_mismatch=True), name)
    xz = data["xz"]
    if len(xz) == 0:
        raise ExampleError(f"{name}: no objects; expected at least one")
    if not np.isfinite(xz).all():
        raise ExampleError(f"{name}: a position is not finite")
    w = _window(xz, window, name)
    if window is None and data.get("ground") is not None:  # a glTF's own ground: where its objects could stand
        g = data["ground"]
        w = (min(g[0], xz[:, 0].min()), min(g[1], xz[:, 1].min()), max(g[2], xz[:, 0].max()), max(g[3], xz[:, 1].max()))
    if window is None and bounds is not None:  # the grown box (or the glTF's ground), on the terrain
        w = (max(w[0], bounds[0]), max(w[1], bounds[1]), min(w[2], bounds[2]), min(w[3], bounds[3]))
    return Example(xz, w, data.get("size"), data.get("kind"), data.get("yaw"), name, data.get("records"), data.get("up"))


def _toml(v) -> str:
    if isinstance(v, str):
        return json.dumps(v)  # a TOML basic string is a JSON string
    if isinstance(v, dict):  # an inline table (an axes list's entries)
        return "{" + ", ".join(f"{json.dumps(str(k))} = {_toml(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(float(v)) if isinstance(v, float) else str(v)


def _write_density(path: Path, grey: np.ndarray) -> None:
    with atomic_path(path, suffix=".png") as tmp:
        Image.fromarray(np.round(np.clip(grey, 0, 1) * 65535).astype(np.uint16)).save(tmp, format="PNG")


def write_learned_scene(path, terrain: dict | None, layers: list, header: str = "") -> list[Path]:
    """A scene file at ``path``: ``up = "y"``, a ``[terrain]`` table of ``terrain``'s keys (paths as given), and a
    generated layer a dict of ``layers`` (``name``, ``mesh``, ``generate``: the recipe's keys, ``density``: a
    (rows, cols) grey map written as ``PATH-NAME-density.png`` beside it).  Every file written atomically, the
    density maps first; returns the paths written."""
    path = Path(path)
    written = []
    lines = [f"# {line}" for line in header.splitlines()] + ["", 'up = "y"', ""]
    if terrain:
        lines.append("[terrain]")
        lines += [f"{k} = {_toml(v)}" for k, v in terrain.items()]
        lines.append("")
    for lay in layers:
        density = path.with_name(f"{path.stem}-{lay['name']}-density.png")
        _write_density(density, lay["density"])
        written.append(density)
        lines += ["[[layer]]", f"name = {_toml(lay['name'])}"]
        lines += [f"{k} = {_toml(lay[k])}" for k in MESH_KEYS if k in lay]
        lines += [f"# {c}" for c in lay.get("comments", ())]
        lines.append("[layer.generate]")
        lines += [f"{k} = {_toml(v)}" for k, v in lay["generate"].items()]
        lines += [f"density = {_toml(density.name)}", ""]
    atomic_write_text(path, "\n".join(lines))
    written.append(path)
    return written


def read_terrain(scene_file, mask=None) -> tuple[dict, object, object]:
    """The height-map terrain of a scene file: its ``[terrain]`` keys (the height map's path absolute), its
    :class:`~axialdeform.core.generate_ground.GroundMaps` and its
    :class:`~axialdeform.core.ground_features.GroundFeatures` (with ``mask``, an image path of the water over
    the same ground, the distance to it)."""
    recipe = parse_scene(scene_file)
    t = recipe.terrain
    if t is None or t.kind != "heightmap":
        raise ExampleError(f"{scene_file}: terrain: expected a [terrain] with a heightmap (the ground's features "
                           f"come from its heights), found {'none' if t is None else 'a mesh'}")
    with t.src.wrap(t.kind, "terrain", 0):
        surface = load_surface(t.file, up="y", height_scale=t.height_scale, extent=t.extent, resample=t.resample)
    table = {"heightmap": str(Path(t.file).resolve()), "height_scale": float(t.height_scale)}
    if t.extent is not None:
        table["extent"] = [float(e) for e in t.extent]
    if recipe.terrain_color is not None:
        table["color"] = [float(c) for c in recipe.terrain_color]
    if t.resample:
        table["resample"] = True
    maps = GroundMaps.of(surface)
    return table, maps, GroundFeatures.of(maps, None if mask is None else load_density(mask))


def learn_layer(example, terrain=None, *, window=None, layer: str | None = None, mask=None, features=None,
                seed: int = 0, errors: str = "clumps") -> list:
    """Learn generated layers from an example of objects standing on a ground: one
    :class:`~axialdeform.core.learn.LearnedLayer` a kind (docs/learn.md).

    Parameters
    ----------
    example : str, PathLike, (n, 16+) array or Example
        What :func:`read_example` reads (a CSV table, a parameter file, a glTF scene, a scene file with
        ``layer``), or an :class:`~axialdeform.core.learn.Example` (:func:`read_example`'s own, e.g. with ``fit``:
        a glTF of baked objects, each fitted to a base mesh).
    terrain : str, PathLike or None
        A scene file with a height-map terrain the example stands on (None: flat ground, no features).
    window : (x0, z0, x1, z1) or None
        The ground the example covers (None: the objects' bounding box grown by half a mean spacing, cut to
        the terrain).
    layer : str or None
        The layer of a scene-file example.
    mask : str, PathLike or None
        A grey image of the water over the terrain (white = water): the feature ``water``.
    features : sequence of str or None
        The ground's features the intensity may depend on (default all:
        :data:`~axialdeform.core.ground_features.FEATURES`; ``water`` needs ``mask``).
    seed : int
        The seed of the simulations of Diggle's test.
    errors : {"clumps", "poisson"}
        Which standard errors decide the ground's terms of an example in clumps: the cluster process's (the
        default: a dependence stays only where the clumps' own variation does not explain it, so it transfers
        to another terrain), or Poisson's with Akaike's criterion (a term stays while it lowers the AIC: every
        dependence the example shows stays, also one its clumps make: its own ground reproduced more closely).
        See :func:`~axialdeform.core.learn.learn_layers`.

    Returns
    -------
    list of LearnedLayer
    """
    ground = read_terrain(terrain, mask)[2] if terrain is not None else None
    bounds = ground.bounds if ground is not None else None
    ex = example if isinstance(example, Example) else read_example(example, window, layer=layer, bounds=bounds)
    for f in features or ():
        if f not in FEATURES or (ground is not None and f not in ground.names):
            raise ExampleError(f"features: {f!r}: expected some of {', '.join(ground.names if ground else FEATURES)}"
                               f"{' (water needs a mask)' if f == 'water' else ''}")
    return learn_layers(ex, ground, list(features) if features else None, seed, errors)


def _layer_names(learned: list) -> list[str]:
    """Each kind as a layer's name (and file name): letters, digits, - and _; the kind's index added where two
    kinds would read the same."""
    names = ["".join(c if c.isalnum() or c in "-_" else "_" for c in str(lay.kind or "learned")) for lay in learned]
    return [n if names.count(n) == 1 else f"{n}-{k}" for k, n in enumerate(names)]


def learned_paths(out, learned: list) -> list[Path]:
    """The files :func:`write_learned` writes for ``learned`` at ``out``: a density map a layer, then ``out``."""
    out = Path(out)
    return [out.with_name(f"{out.stem}-{name}-density.png") for name in _layer_names(learned)] + [out]


def _mesh_keys(mesh) -> dict:
    """A learned layer's mesh as a scene file's layer keys: ``mesh`` (a bundled name or a file) and, from a
    dict of them, ``axis``, ``axes``, ``parts``, ``color`` and ``wind`` (:data:`MESH_KEYS`), and its recipe's
    ``anchor`` and ``lift`` (:data:`STAND_KEYS`)."""
    keys = dict(mesh) if isinstance(mesh, dict) else {"mesh": mesh}
    odd = sorted(set(keys) - set(MESH_KEYS) - set(STAND_KEYS))
    if "mesh" not in keys or odd:
        raise ExampleError(f"mesh: expected a bundled name, a file or a layer's keys of its objects "
                           f"({', '.join(MESH_KEYS + STAND_KEYS)}), found {sorted(keys)}")
    return {k: str(v) if isinstance(v, Path) else v for k, v in keys.items()}


def _layer_mesh(keys: dict):
    """The BaseMesh a learned layer's mesh keys load (as the scene loads its layer): the offsets of an example's
    records become the recipe's ``bend`` in its axes' lengths (the example taken to be of that mesh)."""
    try:
        mesh = load_mesh(keys["mesh"], textures=False)
        if keys.get("parts") is not None:
            mesh = mesh.with_parts(tuple(keys["parts"]))
        mesh = mesh.with_axis(keys.get("axis", "auto"))
        return with_axes(mesh, keys["axes"], keys.get("axis", "auto")) if keys.get("axes") is not None else mesh
    except AxialDeformError as exc:
        raise ExampleError(f"mesh: {keys['mesh']}: expected a mesh to turn the example's bend into axis lengths ({exc})") from None


def layer_mesh(scene_file, layer: str) -> dict:
    """The keys of the objects of the layer ``layer`` of a scene file (``mesh``; ``axis``, ``axes``, ``parts``,
    ``color``, ``wind`` where it has them; files as absolute paths) and how they stand (its recipe's ``anchor``,
    and its ``lift`` where it has one): a layer learned from it grows the same objects, standing as they do
    (``learn --layer`` without ``--mesh``)."""
    recipe = parse_scene(scene_file)
    named = [lay for lay in recipe.layers if lay.name == layer]
    if not named:
        raise ExampleError(f"{scene_file}: layer: expected one of {', '.join(lay.name for lay in recipe.layers) or 'none'} "
                           f"(--layer NAME), found {layer!r}")
    lay = named[0]
    keys = {"mesh": lay.mesh if isinstance(lay.mesh, str) else str(Path(lay.mesh).resolve())}
    if not (isinstance(lay.frame, str) and lay.frame == "auto"):
        keys["axis"] = lay.frame if isinstance(lay.frame, str) else np.asarray(lay.frame, np.float64).tolist()
    if lay.axes is not None:
        keys["axes"] = str(Path(lay.axes).resolve()) if isinstance(lay.axes, Path) else lay.axes
    if lay.parts is not None:
        keys["parts"] = list(lay.parts)
    if lay.color is not None:
        keys["color"] = [float(c) for c in lay.color]
    if lay.wind:
        keys["wind"] = True
    stand = lay.scatter.placement if lay.scatter is not None else lay.generate.generate if lay.generate is not None else None
    if stand is not None:
        keys["anchor"] = stand.anchor
    lift = lay.scatter.lift if lay.scatter is not None else getattr(stand, "lift", None)
    if lift is not None and any(float(v) != 0.0 for v in lift):
        keys["lift"] = [float(v) for v in lift]
    return keys


def write_learned(out, learned: list, terrain, *, mesh="tree", mask=None, seed: int = 0, extent=None,
                  size: float | None = None) -> list[Path]:
    """The scene file ``out`` of ``learned`` (:func:`learn_layer`) over ``terrain`` (a scene file: the example's
    own, or another one, ``mask`` its water), one generated layer a kind with ``mesh`` (a bundled name, a file,
    or a layer's mesh keys, :func:`layer_mesh`'s); on flat ground (``terrain`` None) over ``extent`` (default:
    the example's window); ``size``: the scale of an object of the example's median size (None: the records'
    own median scale where the example is made of records with scales, else 1).  Returns the paths written."""
    if size is not None and not (math.isfinite(size) and size > 0):
        raise ExampleError(f"size: expected a number > 0, found {size!r}")

    table, ground = None, None
    if terrain is not None:
        table, _maps, ground = read_terrain(terrain, mask)
        extent = ground.bounds
    elif extent is None:
        extent = learned[0].window
    for lay in learned:
        missing = [f for f in lay.intensity.names if ground is None or f not in ground.names]
        if missing:
            raise ExampleError(f"{terrain or 'flat ground'}: expected the feature {missing[0]} the layer "
                               f"{lay.kind or 'learned'} depends on{' (give its mask)' if missing[0] == 'water' else ''}")
    layers, names, mesh = [], _layer_names(learned), _mesh_keys(mesh)
    base = _layer_mesh(mesh) if any(lay.marks.bend is not None for lay in learned) else None
    for k, lay in enumerate(learned):
        keys, density = layer_recipe(lay, ground, extent, mesh=base)
        keys["seed"] = seed + k
        median = size if size is not None else lay.marks.record_scale or 1.0
        if "scale" in keys:
            keys["scale"] = [median * v for v in keys["scale"]]
            for key in ("scale_quartiles", "scale_octiles"):
                if key in keys:
                    keys[key] = [median * v for v in keys[key]]
        elif median != 1.0:
            keys["scale"] = [median, median]
        if terrain is None:
            keys["extent"] = list(extent)
        keys.update({k: v for k, v in mesh.items() if k in STAND_KEYS})
        notes = lay.describe(6).split("; ", 1)
        objects = {k: v for k, v in mesh.items() if k in MESH_KEYS}
        layers.append({"name": names[k], **objects, "generate": keys, "density": density, "comments": notes})
    return write_learned_scene(out, table, layers, "a scene learned by axialdeform learn (docs/learn.md)")

"""Helpers shared by the sub-command modules: argument types, loading, progress bars."""

from __future__ import annotations

import argparse
import math
import os
import sys

from tqdm import tqdm

from ..core.axis import FRAME_NAMES
from ..core.errors import ArgumentError, ParamError, ParamFileError
from ..core.io.mesh import load_mesh, mesh_source_path
from ..core.io.params import read_params
from ..core.io.safeio import check_output_path
from ..core.lod import check_lod_error
from ..core.params import check_drawable, range_warning
from ..core.variation import Variation
from ..core.wind import Wind

AXES = ("x", "y", "z")


def angle_range(text: str) -> tuple[float, float]:
    """``MIN,MAX`` radians (one number ``A`` means ``-A,A``)."""
    try:
        parts = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected MIN,MAX in radians, found {text!r}") from None
    if len(parts) == 1:
        return (-abs(parts[0]), abs(parts[0]))
    if len(parts) != 2 or not all(math.isfinite(x) for x in parts):
        raise argparse.ArgumentTypeError(f"expected MIN,MAX in radians, found {text!r}")
    return (parts[0], parts[1])


def view_args(args, auto, up: str):
    """``(eye, target, fov, camera)``: ``--eye``, ``--target`` and ``--fov`` where given, else those of the
    automatic framing ``camera = auto(fov)`` (a callable of the fov, returning a
    :class:`~axialdeform.core.camera.Camera`), checked: the fov in (0, 180) degrees, two different points, a
    view not along the ``up`` axis."""
    import numpy as np

    from ..core.camera import FOVY, UP_VECTORS

    fov = FOVY if args.fov is None else float(args.fov)
    if not 0.0 < fov < 180.0:
        raise ArgumentError(f"--fov: expected degrees between 0 and 180, found {args.fov:g}")
    cam = auto(fov)
    eye = np.asarray(args.eye if args.eye is not None else cam.eye, dtype=np.float64)
    target = np.asarray(args.target if args.target is not None else cam.target, dtype=np.float64)
    forward = target - eye
    if not np.linalg.norm(forward) > 0:
        raise ArgumentError(f"--eye / --target: expected two different points, found both {tuple(map(float, eye))}")
    if np.linalg.norm(np.cross(forward, UP_VECTORS[up])) <= 1e-9 * np.linalg.norm(forward):
        raise ArgumentError(f"--eye / --target: the view direction {tuple(map(float, forward))} is parallel to the up "
                               f"axis {up}; expected a direction that is not straight up or down (or use --up)")
    return eye, target, fov, cam


def vec3(text: str) -> tuple[float, float, float]:
    """``X,Y,Z`` (three finite numbers)."""
    try:
        parts = [float(x) for x in text.split(",")]
    except ValueError:
        parts = []
    if len(parts) != 3 or not all(math.isfinite(x) for x in parts):
        raise argparse.ArgumentTypeError(f"expected X,Y,Z (three numbers), found {text!r}")
    return (parts[0], parts[1], parts[2])


def fraction(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a fraction of L, found {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a finite fraction of L >= 0, found {text!r}")
    return value


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, found {text!r}")
    return value


def axis_frame(text: str):
    """``--axis``: auto, x, y, z, oriented, or nine numbers ``a,b,c,...`` (the
    frame's rows e_a, e_u, e_v), checked when the mesh is loaded."""
    if text in FRAME_NAMES:
        return text
    try:
        numbers = [float(x) for x in text.replace(";", ",").split(",")]
    except ValueError:
        numbers = []
    if len(numbers) != 9 or not all(math.isfinite(x) for x in numbers):
        raise argparse.ArgumentTypeError(f"expected one of {', '.join(FRAME_NAMES)} or nine numbers "
                                         f"(the rows e_a, e_u, e_v of an orthogonal frame), found {text!r}")
    return tuple(tuple(numbers[3 * r: 3 * r + 3]) for r in range(3))


def add_axis(p) -> None:
    """``--axis FRAME`` on a command that loads a mesh (``docs/method.md``, "A chosen axis frame")."""
    p.add_argument("--axis", type=axis_frame, default="auto", metavar="FRAME",
                   help="the mesh's axis frame: auto (longest extent, default), x, y, z, oriented (minimum-volume "
                        "oriented box, for a model lying diagonally) or nine numbers, the rows e_a,e_u,e_v")
    p.add_argument("--axes", metavar="skeleton|parts|auto|FILE.toml",
                   help="several axes in a hierarchy (a tree): 'skeleton' (from the model's own shape: a branch an "
                        "axis), 'parts' (one axis per part), 'auto' (parts when the parts are the limbs, else skeleton) "
                        "or a TOML file of [[axis]] part/parent/axis tables; --axis is then the frame of each axis "
                        "naming none (default: one axis)")
    p.add_argument("--parts", type=part_list, metavar="A,B,...",
                   help="keep only these parts of the mesh file (its scenery left out) for everything: the axes, "
                        "bounds, framing, spacing, export; give it again wherever the parameters are used "
                        "(default: every part)")


def part_list(text: str) -> tuple[str, ...]:
    """``--parts A,B,...``: the part names as the file spells them (a comma inside a name: not supported)."""
    names = tuple(n for n in text.split(",") if n)
    if not names:
        raise argparse.ArgumentTypeError(f"expected part names separated by commas, found {text!r}")
    return names


def add_overwrite(p, detail: str = "") -> None:
    """``--overwrite``: the one rule for an output that exists (every command that writes takes it)."""
    p.add_argument("--overwrite", action="store_true",
                   help="replace an output that exists" + detail + " (default: refuse; a file an input names is "
                        "never replaced)")


def load_base(args, source, *, textures: bool = True):
    """The base mesh ``source`` with the parts ``--parts``, the frame ``--axis`` and the axes ``--axes`` chose."""
    return load_mesh(source, textures=textures, axis=getattr(args, "axis", "auto"), axes=getattr(args, "axes", None),
                     parts=getattr(args, "parts", None))


def add_mesh_and_params(p) -> None:
    """The MESH and PARAMS positional arguments of the commands that read both (and ``--axis``)."""
    p.add_argument("mesh", help="base mesh file, or 'stone' / 'leaf' / 'leafcard' / 'tree', or a scene file (.toml, then no PARAMS)")
    p.add_argument("params", nargs="?", help="parameter file (.adp binary, .txt/.csv/.dat text); required unless MESH is a scene file")
    add_axis(p)


def add_mesh_mismatch(p) -> None:
    p.add_argument("--ignore-mesh-mismatch", action="store_true",
                   help="use PARAMS even if made for another mesh (default: refuse)")


def mesh_file(source):
    """The file a mesh argument names (a bundled name: the package's file), or None."""

    return None if source is None else mesh_source_path(source)


def load(args, what: str = "output", allow_folder: bool = False):
    """``(mesh, params)`` from ``args.mesh`` and ``args.params``, after checking
    that ``args.output`` is neither one of them nor a device, FIFO or socket
    (:func:`~axialdeform.core.io.safeio.check_output_path`); warns once when the
    parameters go past the float32-safe ranges."""

    check_output_path(args.output, (mesh_file(args.mesh), args.params), what, allow_folder=allow_folder)
    if args.params is not None and not os.path.lexists(args.params):  # said before the mesh is loaded
        raise ParamFileError(f"{args.params}: no such parameter file")
    mesh = load_base(args, args.mesh)
    # the files the mesh names too (its material library, textures, buffers): never replaced
    check_output_path(args.output, mesh.sources, what, allow_folder=allow_folder)
    params = read_params(args.params, mesh, allow_mesh_mismatch=args.ignore_mesh_mismatch)
    if args.command in ("render", "view", "web", "bake", "export"):  # a picture, or vertices and a glTF others draw:
        check_drawable(params, str(args.params))  # every number must survive the projection (one line, no warning first)
    # the inputs' own errors first; then an output that exists is replaced only with --overwrite
    check_output_path(args.output, (), what, allow_folder=allow_folder, overwrite=args.overwrite)
    warn_ranges(args, mesh, params)
    return mesh, params


def warn(args, message: str) -> None:
    """One warning line on stderr."""
    print(f"axialdeform {args.command}: warning: {message}", file=sys.stderr)


def warn_ranges(args, mesh, params) -> None:
    """Warn (once) when a parameter file goes past the float32-safe ranges."""

    message = range_warning(mesh, params, args.params)
    if message:
        warn(args, message)


def progress_bar(total: int, desc: str, unit: str = "inst", small: int = 2000):
    """A tqdm bar on stderr (hidden for small jobs when stderr is not a terminal)."""

    return tqdm(total=total, desc=desc, unit=unit, disable=total < small and not sys.stderr.isatty(), file=sys.stderr)


def scale_range(text: str) -> tuple[float, float]:
    """``--scale MIN:MAX`` (or one number S for S:S) as ``(lo, hi)``; anything but
    finite 0 < MIN <= MAX is a ParamError naming the argument and the range."""

    parts = text.replace(",", ":").split(":")
    try:
        lo, hi = (float(parts[0]), float(parts[-1])) if len(parts) in (1, 2) else (math.nan, math.nan)
    except ValueError:
        lo = hi = math.nan
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
        raise ParamError(f"--scale: expected MIN:MAX with 0 < MIN <= MAX (s must be > 0), found {text!r}")
    return lo, hi


def extension_args(args) -> dict:
    """``--scale MIN:MAX``, ``--twist MAX``, ``--taper MAX`` as random_params keywords;
    a bad value is a ParamError naming the argument and the expected range."""

    out = {}
    if getattr(args, "scale", None) is not None:
        out["scale"] = scale_range(args.scale)
    if getattr(args, "twist", None) is not None:
        if not math.isfinite(args.twist):
            raise ParamError(f"--twist: expected a finite number of radians, found {args.twist!r}")
        out["twist"] = args.twist
    if getattr(args, "taper", None) is not None:
        if not (math.isfinite(args.taper) and args.taper < 1):
            raise ParamError(f"--taper: expected a number < 1 (tp < 1: the tip keeps a size > 0), found {args.taper!r}")
        out["taper"] = args.taper
    if getattr(args, "tint", None) is not None:
        if not (math.isfinite(args.tint) and 0 <= args.tint <= 1):
            raise ParamError(f"--tint: expected a variation amount between 0 and 1, found {args.tint!r}")
        out["tint"] = args.tint
    if getattr(args, "tint_color", None) is not None:
        if "tint" not in out:
            raise ParamError("--tint-color: only meaningful with --tint AMOUNT (tinted instances)")
        try:
            color = tuple(float(x) for x in args.tint_color.split(","))
        except ValueError:
            color = ()
        if len(color) != 3 or not all(math.isfinite(c) and 0 <= c <= 1 for c in color):
            raise ParamError(f"--tint-color: expected R,G,B linear RGB numbers in 0..1, found {args.tint_color!r}")
        out["tint_color"] = color
    if getattr(args, "tint_hue", None) is not None:
        if "tint" not in out:
            raise ParamError("--tint-hue: only meaningful with --tint AMOUNT (tinted instances)")
        if not (math.isfinite(args.tint_hue) and 0 <= args.tint_hue <= 1):
            raise ParamError(f"--tint-hue: expected an amount between 0 and 1, found {args.tint_hue!r}")
        out["tint_hue"] = args.tint_hue
    return out


#: the CLI's flags of each Variation field, with their help; the defaults are Variation()'s
_VARIATION_HELP = {
    "bend": ("B[,B...]", "offset amplitude as a fraction of the axis length L; a mesh of several axes takes one a level "
                         "of its hierarchy (trunk,branches,twigs; the last for deeper levels) (default: {})"),
    "yaw": ("MIN,MAX", "radians about the up axis (default: 0,2pi)"),
    "tilt": ("MIN,MAX", "radians about the other two axes (default: {0[0]:g},{0[1]:g})"),
    "scale": ("MIN:MAX", "extended instances: uniform scale s drawn in MIN..MAX, 0 < MIN <= MAX (default: none, 16 numbers)"),
    "twist": ("MAX", "extended instances: twist tw drawn in -MAX..MAX radians over the axis (default: none)"),
    "taper": ("MAX", "extended instances: taper tp drawn between 0 and MAX < 1 (default: none)"),
    "tint": ("AMOUNT", "tinted instances (22 numbers): each one's colour is --tint-color times 1 - AMOUNT*u, u drawn "
                       "in 0..1 (shades of --tint-color); AMOUNT in 0..1 (default: none)"),
    "droop": ("F", "a sag toward the world's down by F of an axis's length at its far end, beside the isotropic --bend: "
                   "every child axis (leaf, frond) clamped at its joint; one axis (blade, leaf card) from its base "
                   "(default: {})"),
}


def bend_levels(text: str):
    """``--bend B`` or ``B,B,...`` (one amplitude per level of a hierarchy)."""
    try:
        values = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected B or B,B,... (fractions of L), found {text!r}") from None
    return values[0] if len(values) == 1 else values


def add_variation_args(parser, names=tuple(_VARIATION_HELP)) -> None:
    """The flags of the :class:`~axialdeform.core.variation.Variation` fields ``names``, with its defaults."""
    default = Variation()
    types = {"bend": bend_levels, "yaw": angle_range, "tilt": angle_range, "scale": str, "twist": float,
             "taper": float, "tint": float, "droop": float}
    for name in names:
        metavar, text = _VARIATION_HELP[name]
        value = getattr(default, name)
        parser.add_argument(f"--{name}", type=types[name], default=None if name == "scale" else value,
                            metavar=metavar, help=text.format(value))
        if name == "tint":
            parser.add_argument("--tint-color", metavar="R,G,B", default=None, help=(
                "with --tint: the brightest tint, linear RGB in 0..1 (default: 1,1,1, the mesh's own colours)"))
            parser.add_argument("--tint-hue", type=float, metavar="H", default=None, help=(
                "with --tint: how far each channel's u goes its own way, 0..1 (default: 0, one u: the tint "
                "keeps --tint-color's hue; 1: the hue varies too)"))


def variation_args(args) -> dict:
    """The :class:`Variation` fields the command line gave (those its parser has), checked with
    the flags' names in the messages."""
    out = {name: getattr(args, name) for name in ("bend", "yaw", "tilt", "droop") if hasattr(args, name)}
    try:
        Variation(**out)
    except ParamError as exc:
        raise ParamError(f"--{exc}") from None
    return {**out, **extension_args(args)}


def add_wind_args(parser) -> None:
    parser.add_argument("--wind", metavar="STRENGTH[,GUST[,FREQ[,WAVELENGTH]]]", default=None, help=(
        "wind (docs/wind.md): tip displacement as a fraction of L, gustiness, gusts per second, "
        "distance between gust fronts, 0 for none (default: no wind)"))
    parser.add_argument("--wind-dir", metavar="X,Y,Z", default="1,0,0", help="wind direction, world (default: %(default)s)")
    parser.add_argument("--time", type=float, default=None, help="seconds: the moment the wind is taken at, with --wind (default: 0)")


def wind_arg(args):
    if args.wind is None:
        if args.time is not None:
            raise ParamError("--time: only meaningful with --wind (the wind is the only thing that moves with time)")
        return None
    if args.time is None:
        args.time = 0.0
    elif not math.isfinite(args.time):
        raise ParamError(f"--time: expected a finite number of seconds, found {args.time!r}")
    try:
        direction = tuple(float(x) for x in args.wind_dir.split(","))
    except ValueError:
        direction = ()
    if len(direction) != 3:
        raise ParamError(f"--wind-dir: expected X,Y,Z (three numbers), found {args.wind_dir!r}")
    try:
        return Wind.parse(args.wind, direction=direction)
    except ParamError as exc:
        raise ParamError(str(exc).replace("wind direction", "--wind-dir")) from None


# ---------------------------------------------------------------- culling and LOD
def add_cull_arguments(p) -> None:
    """``--no-cull``, ``--lod``, ``--lod-error PX`` (render and view)."""
    p.add_argument("--no-cull", action="store_true", help="draw every instance (no per-instance frustum culling; "
                   "the picture is the same, only slower) (default: culling on)")
    p.add_argument("--lod", action="store_true", help="levels of detail: far instances use simplified meshes "
                   "(changes pixels, within --lod-error) (default: off)")
    p.add_argument("--lod-error", type=float, default=None, metavar="PX",
                   help="allowed screen-space error of a level in pixels, > 0 (default 1; implies --lod)")


def cull_options(args) -> dict:
    """AxialRenderer keyword arguments from :func:`add_cull_arguments`'s options."""

    lod = bool(args.lod or args.lod_error is not None)
    return {"culling": not args.no_cull, "lod": lod,
            "lod_error": check_lod_error(1.0 if args.lod_error is None else args.lod_error)}


def format_stats(stats: dict, frame_s: float | None = None) -> str:
    """One line of :attr:`AxialRenderer.stats` (and a frame time)."""
    levels = stats.get("levels", [])
    text = (f"instances: {stats['submitted']} submitted, {stats['visible']} drawn"
            f" (culling {'on' if stats.get('culling') else 'off'}{', indirect draws' if stats.get('indirect') else ''})")
    if stats.get("lod"):
        text += ", LOD levels " + " / ".join(str(k) for k in levels)
    text += f"; vertices processed: {stats['vertices']}"
    if frame_s is not None:
        text += f"; frame {frame_s * 1000:.1f} ms"
    return text


# ---------------------------------------------------------------- bounded time for huge jobs
#: The CLI's per-frame budget of drawn primitives (``--max-triangles``):
#: instances x triangles of the drawn parts, summed over layers and panels,
#: wireframe weighted by :func:`mode_weight`.  A frame of 10**8 triangles of
#: a 1 M-face mesh costs about 25 s of CPU on llvmpipe (2 cores); 5 * 10**7
#: keeps a default ``render`` near 17 s of CPU (docs/reliability.md,
#: "Bounded time for huge jobs").  A policy of the command line only: the
#: Python API (``AxialRenderer`` and the rest) draws whatever it is given.
MAX_TRIANGLES = 50_000_000

#: edges a wireframe draws per triangle (a closed mesh has exactly 1.5)
WIRE_EDGES_PER_TRIANGLE = 1.5

#: The CLI's maximum of mesh files ``bake -o FOLDER`` writes (``--max-files``);
#: ``bake -o OUT.npz`` has no such limit (it is written in pieces).
MAX_BAKE_FILES = 10_000

#: The CLI's maximum of instances ``export --baked`` writes, one glTF mesh and
#: node each (``--max-meshes``); ``--instanced`` (one mesh) and scene files
#: (one mesh a layer) have no such limit.
MAX_EXPORT_MESHES = 10_000


#: The CLI's budget of triangles one baked output holds (``bake``, ``export
#: --baked``; ``--max-triangles``): instances x triangles of the mesh, summed
#: over layers.  Baking is writing: 2 * 10**7 triangles are a 0.5 GB glTF or
#: 1 GB of OBJ text, about 7 s (glTF) to 22 s (OBJ) of CPU here for a
#: 1 M-face mesh -- past it a bake is more likely a mistake than a wish
#: (docs/reliability.md).  The Python API bakes whatever it is given.
MAX_BAKED_TRIANGLES = 20_000_000


def add_max_baked(p) -> None:
    """``--max-triangles N`` of the commands that write baked geometry."""
    p.add_argument("--max-triangles", type=positive_int, default=MAX_BAKED_TRIANGLES, metavar="N", help=(
        "refuse to bake more than N triangles: instances x triangles of the mesh, summed over layers "
        "(default: %(default)s: a 0.5 GB glTF, 1 GB of OBJ text)"))


def check_baked_triangles(args, items, hint: str) -> None:
    """Refuse a baked output of more than ``--max-triangles`` triangles, before
    any work; ``items`` : (what, instances, triangles a mesh) a layer."""
    total = sum(int(n) * int(t) for _, n, t in items)
    if total > args.max_triangles:
        what = ", ".join(f"{w} ({n} x {t} triangles)" for w, n, t in items)
        raise ArgumentError(f"{what}: {total} triangles to bake, over the limit of {args.max_triangles}; expected "
                            f"fewer instances, or raise the limit with --max-triangles N{hint}")


def add_max_triangles(p) -> None:
    """``--max-triangles N`` (every command that rasterises)."""
    p.add_argument("--max-triangles", type=positive_int, default=MAX_TRIANGLES, metavar="N", help=(
        "refuse a frame of more than N triangles: instances x triangles of the drawn parts, summed over "
        "layers; wireframe counts 1.5 edges a triangle, plus the triangles of the hidden-line pass unless "
        "--fast (default: %(default)s: about 12 s of CPU a frame on llvmpipe)"))


def mode_weight(mode: str, fast: bool = False) -> float:
    """Primitives drawn per triangle of the mesh in ``mode``: 1 (solid, flat);
    wireframe: 1.5 edges, plus 1 for the hidden-line depth pass unless ``fast``.
    Level of detail is not counted: any instance may be near (level 0)."""
    if mode == "wireframe":
        return WIRE_EDGES_PER_TRIANGLE + (0.0 if fast else 1.0)
    return 1.0


def drawn_triangles(mesh, parts=None) -> int:
    """Triangles of ``mesh`` drawn with ``--part`` names ``parts`` (None: all)."""
    if not parts:
        return int(len(mesh.faces))
    return int(sum(mesh.part(name).count for name in dict.fromkeys(parts)))


def check_triangles(items, modes, limit: int, fast: bool = False, frames: int = 1) -> int:
    """Refuse a frame over the CLI's triangle budget, before anything is drawn.

    ``items`` : iterable of ``(label, instances, triangles)`` (one a layer;
    a terrain is 1 instance), ``modes`` : a mode or the modes drawn side by
    side (``demo``), ``limit`` : ``--max-triangles``; ``frames`` : frames a
    job draws with no window to close (``view --headless --frames N``,
    ``render --stats``: 2), each counted; 0: an interactive window its user
    watches and closes, not capped.  Returns the weighted primitives
    drawn; over ``limit`` an :class:`ArgumentError` names the file(s), the
    counts, the product, the limit and how to raise it.
    """

    if int(frames) == 0:
        return 0
    modes = (modes,) if isinstance(modes, str) else tuple(modes)
    weight = sum(mode_weight(m, fast) for m in modes)
    items = [(label, int(n), int(t)) for label, n, t in items]
    triangles = sum(n * t for _, n, t in items)
    frames = max(int(frames), 1)
    work = int(math.ceil(triangles * weight)) * frames
    if work <= limit:
        return work
    parts = "; ".join(f"{label}: {n} instances x {t} triangles" for label, n, t in items if n * t)
    if weight == 1:
        total = f"{triangles} triangles a frame ({modes[0]})"
    else:
        what = f"{WIRE_EDGES_PER_TRIANGLE:g} edges a triangle" + ("" if fast else " + the hidden-line pass")
        total = f"{triangles} triangles a frame, x {weight:g} for {' + '.join(modes)} (wireframe: {what})"
    if frames > 1:
        total += f", x {frames} frames"
    if weight != 1 or frames > 1:
        total += f" = {work}"
    fits = [t for _, n, t in items if n * t]
    most = (f"at most {int(limit // (fits[0] * weight * frames))} instances of this mesh"
            if len(fits) == 1 else "fewer instances or smaller meshes")
    raise ArgumentError(
        f"{parts} = {total}, over the limit of {limit}; expected {most}, "
        f"or raise the limit with --max-triangles N (about 25 s of CPU per 10^8 triangles on llvmpipe)")

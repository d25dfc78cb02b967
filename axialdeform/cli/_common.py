"""Helpers shared by the sub-command modules: argument types, loading, progress bars."""

from __future__ import annotations

import argparse
import math
import sys

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


def add_mesh_and_params(p) -> None:
    """The MESH and PARAMS positional arguments of the commands that read both."""
    p.add_argument("mesh", help="base mesh file, or 'stone' / 'leaf'")
    p.add_argument("params", help="parameter file (.adp binary, .txt/.csv/.dat text)")


def add_mesh_mismatch(p) -> None:
    p.add_argument("--ignore-mesh-mismatch", action="store_true",
                   help="use PARAMS even if made for another mesh (default: refuse)")


def mesh_file(source):
    """The file a mesh argument names (a bundled name: the package's file), or None."""
    from ..core.mesh import mesh_source_path

    return None if source is None else mesh_source_path(source)


def load(args, what: str = "output", allow_folder: bool = False):
    """``(mesh, params)`` from ``args.mesh`` and ``args.params``, after checking
    that ``args.output`` is neither one of them nor a device, FIFO or socket
    (:func:`~axialdeform.core.safeio.check_output_path`); warns once when the
    parameters go past the float32-safe ranges."""
    from ..core.mesh import load_mesh
    from ..core.params import read_params
    from ..core.safeio import check_output_path

    check_output_path(args.output, (mesh_file(args.mesh), args.params), what, allow_folder=allow_folder)
    mesh = load_mesh(args.mesh)
    params = read_params(args.params, mesh, allow_mesh_mismatch=args.ignore_mesh_mismatch)
    warn_ranges(args, mesh, params)
    return mesh, params


def warn(args, message: str) -> None:
    """One warning line on stderr."""
    print(f"axialdeform {args.command}: warning: {message}", file=sys.stderr)


def warn_ranges(args, mesh, params) -> None:
    """Warn (once) when a parameter file goes past the float32-safe ranges."""
    from ..core.params import range_warning

    message = range_warning(mesh, params, args.params)
    if message:
        warn(args, message)


def progress_bar(total: int, desc: str, unit: str = "inst", small: int = 2000):
    """A tqdm bar on stderr (hidden for small jobs when stderr is not a terminal)."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=total < small and not sys.stderr.isatty(), file=sys.stderr)

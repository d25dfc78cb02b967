"""``axialdeform scatter SURFACE MESH -n N -o OUT``: instances on a terrain.

SURFACE is a mesh file or a grey height-map image; see
:mod:`axialdeform.core.scatter` for the method.  When fewer than N fit, the
ones that fit are written, the count is said on stderr and the status is 2
(0 with ``--allow-fewer``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..core.errors import ParamFileError, TooFewError
from ..core.io.mesh import mesh_source_path
from ..core.io.params import BINARY_SUFFIXES, write_params
from ..core.io.safeio import check_output_path
from ..core.scatter import ANCHORS, Placement, scatter
from ..core.surface import IMAGE_SUFFIXES, load_surface
from ..core.variation import Variation
from ._common import add_axis, add_overwrite, add_variation_args, load_base, variation_args

__all__ = ["add_parser", "run"]


def _extent(text: str) -> tuple[float, ...]:
    try:
        parts = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected W or W,D (world units > 0), found {text!r}") from None
    if len(parts) not in (1, 2):
        raise argparse.ArgumentTypeError(f"expected W or W,D (world units > 0), found {text!r}")
    return parts


def add_parser(subparsers) -> None:
    s = subparsers.add_parser("scatter", help="place instances on a terrain (mesh or height map)", description=(
        "Place N instances of MESH on SURFACE (a mesh file, or a grey height-map image): area-uniform on the "
        "faces that face up, at least --min-distance apart, following a --density image (columns along +x, rows "
        "along +z, top row at the smallest z; black none, white full). Writes a parameter file (16 numbers per "
        "instance, 19 with --scale)."))
    s.add_argument("surface", metavar="SURFACE", help="terrain: a mesh file, or a grey height-map image")
    s.add_argument("mesh", metavar="MESH", help="base mesh file, or 'stone' / 'leaf' / 'leafcard' / 'tree'")
    add_axis(s)
    s.add_argument("-n", "--count", type=int, required=True, help="how many instances (required)")
    s.add_argument("-o", "--output", required=True, help="parameter file (.adp binary; .txt/.csv/.dat text; required)")
    s.add_argument("--min-distance", type=float, default=None, metavar="D", help="least distance between instances (default: none)")
    s.add_argument("--density", default=None, metavar="IMAGE", help="grey density map over the surface's bounding box (default: uniform)")
    s.add_argument("--align-to-normal", type=float, default=0.0, metavar="F",
                   help="tilt the up axis towards the surface normal by F in [0, 1] (default: 0, upright)")
    s.add_argument("--anchor", choices=ANCHORS, default="bottom",
                   help="point of MESH on the surface (default: %(default)s)")
    add_variation_args(s, ("bend", "yaw", "scale", "twist", "taper", "tint", "droop"))
    s.add_argument("--seed", type=int, default=0, help="random seed (default: %(default)s)")
    s.add_argument("--up", choices=("x", "y", "z"), default="y", help="world up axis (default: %(default)s)")
    s.add_argument("--height-scale", type=float, default=1.0, metavar="H",
                   help="height-map SURFACE: height of a white pixel (default: %(default)s)")
    s.add_argument("--extent", type=_extent, default=None, metavar="W[,D]",
                   help="height-map SURFACE: size along x (and z); default one unit per pixel")
    s.add_argument("--resample", action="store_true",
                   help="height-map SURFACE larger than the pixel bound (AXIALDEFORM_MAX_HEIGHTMAP_PIXELS, 2048x2048 by "
                        "default): read it at the largest resolution within it (default: refuse)")
    s.add_argument("--allow-fewer", action="store_true", help="exit 0 when fewer than N fit (default: exit 2)")
    s.add_argument("--quantize", action="store_true", help="write the compact quantized form, binary only (default: float32)")
    add_overwrite(s)
    s.set_defaults(handler=run)


def run(args) -> int | None:
    variation = variation_args(args)  # checked before any file is read

    if args.quantize and Path(args.output).suffix.lower() not in BINARY_SUFFIXES:  # before the work, not after
        raise ParamFileError(f"{args.output}: the quantized form is binary only; expected a "
                             f"{'/'.join(BINARY_SUFFIXES)} file name")
    check_output_path(args.output, (args.surface, mesh_source_path(args.mesh), args.density), "parameter file")
    mesh = load_base(args, args.mesh, textures=False)
    check_output_path(args.output, mesh.sources, "parameter file", overwrite=args.overwrite)  # the files the mesh names too
    surface = args.surface
    if args.resample and Path(surface).suffix.lower() in IMAGE_SUFFIXES:
        surface = load_surface(surface, up=args.up, height_scale=args.height_scale, extent=args.extent, resample=True)
    try:
        placement = Placement(min_distance=args.min_distance, density=args.density, align_to_normal=args.align_to_normal,
                              anchor=args.anchor, up=args.up, height_scale=args.height_scale, extent=args.extent)
        params = scatter(surface, mesh, args.count, Variation(**variation), placement, seed=args.seed,
                         allow_fewer=args.allow_fewer)
        short = None
    except TooFewError as exc:
        params, short = exc.params, exc
    path = write_params(args.output, params, mesh, quantize=args.quantize)
    print(f"wrote {path} ({len(params)} instances, {params.shape[1]} numbers each, {path.stat().st_size} bytes)")
    if short is not None:
        print(f"axialdeform scatter: error: {short}", file=sys.stderr)
        return 2
    if len(params) < args.count:
        print(f"axialdeform scatter: only {len(params)} of {args.count} instances fit (--allow-fewer)", file=sys.stderr)
    return None

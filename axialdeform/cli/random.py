"""``axialdeform random``: random parameters for a mesh."""

from __future__ import annotations

from ..core.errors import ArgumentError
from ..core.io.params import param_file_bytes, write_param_chunks
from ..core.io.safeio import (
    MAX_INSTANCES,
    check_count,
    check_disk_space,
    check_output_path,
)
from ..core.record import WIDTHS, tree_width
from ..core.variation import PLACEMENTS, Variation, iter_random_params
from ._common import AXES, add_axis, add_overwrite, add_variation_args, load_base, mesh_file, variation_args


def add_parser(sub) -> None:
    r = sub.add_parser("random", help="write random parameters for a mesh", description=(
        "Write COUNT random parameter records for MESH (a file, or 'stone' / 'leaf' / 'leafcard' / 'tree'); "
        "the output is binary for .adp, text for .txt/.csv/.dat."))
    r.add_argument("mesh", help="base mesh file, or 'stone' / 'leaf' / 'leafcard' / 'tree'")
    add_axis(r)
    r.add_argument("-n", "--count", type=int, required=True, help=(
        "number of instances (required, no default); at most 2147483647 and what the output's disk holds: "
        "64 bytes an instance in .adp, 32 quantized, up to 256 in text (19 numbers: 76, 38, 304; 22: 88, 44, 352); "
        "they are made and written 131072 at a time, so memory stays under 200 MB whatever the count"))
    r.add_argument("--seed", type=int, default=0, help="random seed (default: %(default)s)")
    r.add_argument("--placement", choices=PLACEMENTS, default="grid", help="how instances are laid out (default: %(default)s)")
    r.add_argument("--spacing", type=float, default=None, help="distance between neighbours, world units (default: 1.1 L)")
    r.add_argument("--up", choices=AXES, default="y", help="world up axis (default: %(default)s)")
    add_variation_args(r)
    r.add_argument("--quantize", action="store_true",
                   help="write the compact uint16 form, binary only: 32 bytes an instance, 38 extended (default: 64/76 bytes, lossless)")
    r.add_argument("-o", "--output", required=True, help="parameter file to write (required, no default)")
    add_overwrite(r)
    r.set_defaults(handler=run)


#: peak bytes per instance of ``random`` while it makes and writes one piece
#: (the generator's temporaries, the float32 piece and its encoding), for the
#: memory check of a piece: measured 533 for 19 numbers quantized (the
#: largest form; 16 numbers text 416) with ``python tools/random_memory.py``
#: (tracemalloc, pieces of 131072; docs/reliability.md), plus 20 %
RANDOM_BYTES_EACH = 640
#: instances made and written at a time: memory stays about
#: ``RANDOM_CHUNK * RANDOM_BYTES_EACH`` (80 MB) beyond the interpreter's
#: whatever ``-n`` is (measured peak: 189 MB resident at -n 300000 to 4800000)
RANDOM_CHUNK = 1 << 17


def run(args) -> None:
    variation = variation_args(args)  # before any work: a bad range is the first thing said
    check_output_path(args.output, (mesh_file(args.mesh),), "parameter file")
    count = int(args.count)
    if count < 0:
        raise ArgumentError(f"-n/--count: expected 0 or more instances, found {count}")
    if count > MAX_INSTANCES:
        raise ArgumentError(f"-n/--count: expected at most {MAX_INSTANCES} instances (a GL draw takes a signed "
                            f"32-bit count), found {count}")
    # memory holds one piece whatever the count; the file must fit on its disk
    check_count(min(count, RANDOM_CHUNK), RANDOM_BYTES_EACH, f"-n/--count (made {RANDOM_CHUNK} at a time)")
    mesh = load_base(args, args.mesh, textures=False)
    check_output_path(args.output, mesh.sources, "parameter file", overwrite=args.overwrite)  # the files the mesh names too
    # several axes: 10·K + 6 numbers (+ 3, + 6); pieces shrink so that memory stays the same
    variation = Variation(**variation)
    width = tree_width(mesh.axis_count, 2 if variation.tint is not None else 1 if variation.extended else 0)
    chunk = max(1, RANDOM_CHUNK * WIDTHS[0] // width)
    fixed = param_file_bytes(args.output, 0, width, quantize=args.quantize)
    each = param_file_bytes(args.output, 1, width, quantize=args.quantize) - fixed

    def fits(free: int) -> str:
        return f"-n/--count at most {max(0, (free - fixed) // each)} there ({each} bytes an instance)"

    check_disk_space(args.output, fixed + count * each, f"parameter file ({count} instances of {width} numbers)",
                     ArgumentError, expected=fits)
    options = dict(placement=args.placement, spacing=args.spacing, up=args.up)
    iter_random_params(mesh, count, args.seed, variation, **options)  # bad options are refused before the file is opened

    def pieces():  # called twice for the quantized form: a first pass finds the decode table
        return iter_random_params(mesh, count, args.seed, variation, chunk=chunk, **options)

    path = write_param_chunks(args.output, pieces, count, width, mesh, quantize=args.quantize)
    print(f"wrote {path} ({count} instances, {path.stat().st_size} bytes)")

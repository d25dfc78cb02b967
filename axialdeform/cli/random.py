"""``axialdeform random``: random parameters for a mesh."""

from __future__ import annotations

import math

from ._common import AXES, angle_range, extension_args


def add_parser(sub) -> None:
    from ..core.variation import PLACEMENTS

    r = sub.add_parser("random", help="write random parameters for a mesh", description=(
        "Write COUNT random parameter records for MESH (a file, or 'stone' / 'leaf'); "
        "the output is binary for .adp, text for .txt/.csv/.dat."))
    r.add_argument("mesh", help="base mesh file, or 'stone' / 'leaf'")
    r.add_argument("-n", "--count", type=int, required=True, help="number of instances (required, no default)")
    r.add_argument("--seed", type=int, default=0, help="random seed (default: %(default)s)")
    r.add_argument("--bend", type=float, default=0.08, help="offset amplitude as a fraction of the axis length L (default: %(default)s)")
    r.add_argument("--placement", choices=PLACEMENTS, default="grid", help="how instances are laid out (default: %(default)s)")
    r.add_argument("--spacing", type=float, default=None, help="distance between neighbours, world units (default: 1.1 L)")
    r.add_argument("--up", choices=AXES, default="y", help="world up axis (default: %(default)s)")
    r.add_argument("--yaw", type=angle_range, default=(0.0, 2 * math.pi),
                   help="MIN,MAX radians about the up axis (default: 0,2pi)")
    r.add_argument("--tilt", type=angle_range, default=(-0.25, 0.25),
                   help="MIN,MAX radians about the other two axes (default: -0.25,0.25)")
    r.add_argument("--scale", metavar="MIN:MAX", default=None,
                   help="extended instances: uniform scale s drawn in MIN..MAX, 0 < MIN <= MAX (default: none, 16 numbers)")
    r.add_argument("--twist", metavar="MAX", type=float, default=None,
                   help="extended instances: twist tw drawn in -MAX..MAX radians over the axis (default: none)")
    r.add_argument("--taper", metavar="MAX", type=float, default=None,
                   help="extended instances: taper tp drawn between 0 and MAX < 1 (default: none)")
    r.add_argument("--quantize", action="store_true",
                   help="write the compact uint16 form, binary only: 32 bytes an instance, 38 extended (default: 64/76 bytes, lossless)")
    r.add_argument("-o", "--output", required=True, help="parameter file to write (required, no default)")
    r.set_defaults(handler=run)


#: peak bytes per instance of ``random`` (random_params' temporaries, the
#: result and its encoding; measured with tracemalloc: about 700), for the -n check
RANDOM_BYTES_EACH = 768


def run(args) -> None:
    from ..core.mesh import load_mesh
    from ..core.params import write_params
    from ..core.variation import random_params

    from ..core.safeio import check_count, check_output_path
    from ._common import mesh_file

    extension = extension_args(args)  # before any work: a bad range is the first thing said
    check_output_path(args.output, (mesh_file(args.mesh),), "parameter file")
    check_count(args.count, RANDOM_BYTES_EACH, "-n/--count")
    mesh = load_mesh(args.mesh)
    params = random_params(mesh, args.count, args.seed, bend=args.bend, placement=args.placement,
                           spacing=args.spacing, up=args.up, yaw=args.yaw, tilt=args.tilt, **extension)
    path = write_params(args.output, params, mesh, quantize=args.quantize)
    print(f"wrote {path} ({len(params)} instances, {path.stat().st_size} bytes)")

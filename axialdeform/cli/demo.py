"""``axialdeform demo``: the default stone scene to a PNG."""

from __future__ import annotations

from pathlib import Path

from ..core.io.image import save_png
from ..core.io.mesh import load_mesh, mesh_source_path
from ..core.io.safeio import check_count, check_output_path
from ..core.look import Look
from ..core.variation import Variation, random_params
from ._common import add_max_triangles, add_overwrite, check_triangles

DEMO_COUNT = 2500


def add_parser(sub) -> None:
    d = sub.add_parser("demo", help="render the default stone scene to a PNG", description=(
        f"Render {DEMO_COUNT} bundled stones, each bent by its own control axis, solid and wireframe side by side."))
    d.add_argument("-o", "--output", default="axialdeform-demo.png", help="PNG to write (default: %(default)s)")
    d.add_argument("-n", "--count", type=int, default=DEMO_COUNT, help="number of stones (default: %(default)s)")
    d.add_argument("--size", default="800x600", help="size of each panel, WIDTHxHEIGHT (default: %(default)s)")
    d.add_argument("--seed", type=int, default=2003, help="random seed (default: %(default)s)")
    d.add_argument("--fast", action="store_true",
                   help="no multisampling, ground, shadows or hidden lines (default: all of them)")
    add_max_triangles(d)
    add_overwrite(d)
    d.set_defaults(handler=run)


#: peak bytes per instance of ``demo`` (random_params' temporaries, the
#: result, the GPU buffer and camera bounds), for the -n check
DEMO_BYTES_EACH = 1024


def run(args) -> None:
    from ..core.camera import frame_instances
    from ..gl.image import parse_size, render_image

    check_output_path(args.output, (mesh_source_path("stone"),), "PNG", overwrite=args.overwrite)  # the bundled mesh is an input too
    check_count(args.count, DEMO_BYTES_EACH, "-n/--count")
    mesh = load_mesh("stone")
    check_triangles([(f"stone x -n {args.count}", args.count, len(mesh.faces))], ("solid", "wireframe"),
                    args.max_triangles, args.fast)  # both panels, before the parameters are made
    params = random_params(mesh, args.count, seed=args.seed, variation=Variation(bend=0.14, tilt=(-0.2, 0.2)), placement="disc",
                           spacing=0.9 * mesh.axis.length)
    size = parse_size(args.size)
    camera = frame_instances(mesh, params, size[0] / size[1], elevation=30.0, azimuth=20.0)
    image = render_image(mesh, params, size, ("solid", "wireframe"), camera=camera, look=Look(fast=args.fast))
    save_png(args.output, image)
    print(f"wrote {Path(args.output).resolve()} ({args.count} stones, solid | wireframe, {image.shape[1]}x{image.shape[0]})")

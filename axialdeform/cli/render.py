"""``axialdeform render``: instances to a PNG, framed automatically or by ``--eye/--target/--fov``."""

from __future__ import annotations

import time

import numpy as np

from ..core.bounds import instance_bounds
from ..core.io.image import save_png
from ..core.look import Look
from ..core.options import RenderOptions
from ..gl.context import Offscreen, create_context
from ..gl.renderer import MODES, AxialRenderer
from . import scenes
from ._common import (
    AXES,
    add_cull_arguments,
    add_max_triangles,
    add_mesh_and_params,
    add_mesh_mismatch,
    add_overwrite,
    add_wind_args,
    check_triangles,
    cull_options,
    drawn_triangles,
    format_stats,
    load,
    vec3,
    view_args,
    wind_arg,
)


def add_parser(sub) -> None:
    rd = sub.add_parser("render", help="render instances to a PNG", description=(
        "Render MESH deformed by PARAMS. Without --eye/--target/--fov the camera frames every instance; "
        "any of them replaces that part of the automatic camera."))
    add_mesh_and_params(rd)
    rd.add_argument("-o", "--output", required=True, help="PNG to write (required, no default)")
    rd.add_argument("--mode", choices=MODES, default="solid", help="how to draw (default: %(default)s)")
    rd.add_argument("--size", default="800x600", help="WIDTHxHEIGHT (default: %(default)s)")
    rd.add_argument("--up", choices=AXES, default="y", help="world up axis (default: %(default)s)")
    rd.add_argument("--eye", type=vec3, default=None, metavar="X,Y,Z",
                    help="camera position, world units (default: framed automatically)")
    rd.add_argument("--target", type=vec3, default=None, metavar="X,Y,Z",
                    help="point the camera looks at (default: the centre of all instances)")
    rd.add_argument("--fov", type=float, default=None, metavar="DEG",
                    help="vertical field of view in degrees, 0 < DEG < 180 (default: 35)")
    rd.add_argument("--part", action="append", metavar="NAME",
                    help="draw only this part of the mesh (repeatable; default: every part)")
    rd.add_argument("--fast", action="store_true",
                    help="no multisampling, ground, shadows or hidden lines (default: all of them)")
    add_mesh_mismatch(rd)
    add_wind_args(rd)
    add_cull_arguments(rd)
    rd.add_argument("--stats", action="store_true", help="print instances submitted / drawn / per LOD level, "
                    "vertices processed and the frame time (default: off)")
    add_max_triangles(rd)
    add_overwrite(rd)
    rd.set_defaults(handler=run)


def camera_from_args(mesh, params, size, args):
    """The automatic camera, with ``--eye``, ``--target`` and ``--fov`` put in
    where given (near and far planes then enclose every instance)."""

    from ..core.camera import UP_VECTORS, Camera, frame_instances

    eye, target, fov, cam = view_args(args, lambda fov: frame_instances(mesh, params, size[0] / size[1], up=args.up,
                                                                       fovy=fov), args.up)
    if args.eye is None and args.target is None:
        return cam
    up = np.asarray(UP_VECTORS[args.up], dtype=np.float64)
    centers, radii = instance_bounds(mesh, params)  # a sphere around each instance
    reach = np.linalg.norm(centers - eye, axis=1) + radii if len(centers) else np.ones(1)
    far = float(reach.max()) * 1.05 + 1e-6
    return Camera(eye, target, up, fov, near=far * 1e-3, far=far)


def run(args) -> None:
    from ..gl.image import parse_size, render_image

    size = parse_size(args.size)  # options and files are checked before any mesh is loaded
    scene = scenes.scene_of(args)
    options = cull_options(args)
    if scene is not None:  # the scene's [wind] moves with --time; --wind replaces it
        return scenes.render(scene, args, wind_arg(args) if args.wind is not None else None, options)
    wind = wind_arg(args)
    wind_options = {"wind": wind, "time": args.time} if wind is not None else {}
    drawn = RenderOptions(up=args.up, parts=args.part, **wind_options)
    mesh, params = load(args, "PNG")
    check_triangles([(f"{args.mesh} x {args.params}", len(params), drawn_triangles(mesh, args.part))],
                    args.mode, args.max_triangles, args.fast, 2 if args.stats else 1)  # before the camera, context
    camera = camera_from_args(mesh, params, size, args)
    ctx = create_context()
    try:
        with AxialRenderer(ctx, mesh, params, RenderOptions(parts=args.part, **options)) as r:
            image = render_image(mesh, params, size, args.mode, ctx=ctx, camera=camera, options=drawn.replace(renderer=r),
                                 look=Look(fast=args.fast))
            if args.stats:
                print(format_stats(r.stats, _time_frame(ctx, r, camera, size, args.mode)))
    finally:
        ctx.release()
    save_png(args.output, image)
    print(f"wrote {args.output} ({len(params)} instances, {args.mode}, {image.shape[1]}x{image.shape[0]})")


def _time_frame(ctx, renderer, camera, size, mode) -> float:
    """Seconds for one more frame of ``renderer`` (cull pass + draws, GPU finished), same camera."""

    with Offscreen(ctx, size) as target:
        target.use()
        ctx.finish()
        start = time.perf_counter()
        renderer.render(camera.view(), camera.projection(size[0] / size[1]), mode)
        ctx.finish()
        return time.perf_counter() - start

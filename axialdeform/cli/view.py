"""``axialdeform view``: the interactive viewer (:mod:`axialdeform.viewer`)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..core.brush import Stroke, mask_path
from ..core.errors import AxialDeformError
from ..core.io.params import read_params
from ..core.io.safeio import check_count, check_output_path
from ..core.look import Look
from ..core.options import RenderOptions
from ..core.params import check_drawable
from ..core.variation import Variation, random_params
from ..gl.renderer import MODES
from . import scenes
from ._common import (
    AXES,
    add_axis,
    add_cull_arguments,
    add_max_triangles,
    add_mesh_mismatch,
    add_overwrite,
    bend_levels,
    check_triangles,
    cull_options,
    drawn_triangles,
    load_base,
    wind_arg,
)
from .random import RANDOM_BYTES_EACH


def add_parser(sub) -> None:
    v = sub.add_parser("view", help="look at instances in an interactive window", description=(
        "Open MESH (a file, or 'stone' / 'leaf' / 'leafcard' / 'tree') deformed by PARAMS (or by random parameters) in a window: "
        "drag to orbit, scroll to zoom; keys 1/2/3 solid/flat/wireframe, W next mode, N new seed, "
        "UP/DOWN bend amplitude, G ground, V wind, R reset camera, S screenshot, ESC quit; B brush (a drag paints "
        "where a scene's first generated layer grows), E paint/erase, [ ] its radius, M save the masks."))
    v.add_argument("mesh", help="base mesh file, or 'stone' / 'leaf' / 'leafcard' / 'tree'")
    add_axis(v)
    v.add_argument("params", nargs="?", help="parameter file (default: random parameters)")
    v.add_argument("-n", "--count", type=int, default=1000, help="random instances when no PARAMS (default: %(default)s)")
    v.add_argument("--seed", type=int, default=None,
                   help="seed of the random parameters when no PARAMS (default: 0; with PARAMS: none, the file's)")
    v.add_argument("--bend", type=bend_levels, default=Variation.bend, metavar="B[,B...]",
                   help="offset amplitude for N, fraction of L; a mesh of several axes takes one a level of its hierarchy "
                        "(trunk,branches,...; the last for deeper levels), as random and scatter do (default: %(default)s)")
    v.add_argument("--mode", choices=MODES, default="solid", help="how to draw at the start (default: %(default)s)")
    v.add_argument("--up", choices=AXES, default="y", help="world up axis (default: %(default)s)")
    v.add_argument("--size", default="960x720", help="WIDTHxHEIGHT (default: %(default)s)")
    v.add_argument("--no-ground", action="store_true", help="start without the ground plane (default: with it)")
    v.add_argument("--headless", action="store_true", help="no window: draw --frames frames offscreen, EGL (default: a window)")
    v.add_argument("--frames", type=int, default=3, help="frames to draw with --headless (default: %(default)s)")
    v.add_argument("--screenshot", help="PNG of the last frame, with --headless (default: none)")
    v.add_argument("--fast", action="store_true",
                   help="no shadows, hidden lines or multisampling (default: all of them)")
    v.add_argument("--part", action="append", metavar="NAME",
                   help="draw only this part of the mesh (repeatable; default: every part)")
    add_mesh_mismatch(v)
    v.add_argument("--wind", metavar="STRENGTH[,GUST[,FREQ[,WAVELENGTH]]]", default=None,
                   help="animate a wind on the GPU, docs/wind.md; V toggles it (default: still)")
    v.add_argument("--wind-dir", metavar="X,Y,Z", default="1,0,0", help="wind direction, world (default: %(default)s)")
    add_cull_arguments(v)
    v.add_argument("--walk", metavar="DX,DZ", default=None,
                   help="move the camera's target DX, DZ world units a frame (a walk; a scene's generated "
                        "layers are made tile by tile around it) (default: still)")
    v.add_argument("--paint", action="append", type=_stroke, metavar="LAYER:X,Z,R[:erase]",
                   help="paint (or erase) a disc of radius R at X, Z where a scene's generated LAYER grows, before the "
                        "frames (repeatable); with --headless the masks are then saved beside the scene file "
                        "(SCENE-LAYER-mask.png), which the scene reads again when loaded (default: none)")
    v.add_argument("--no-lod", action="store_true", help="no levels of detail (default: on from 100 000 instances)")
    add_max_triangles(v)
    add_overwrite(v)
    v.set_defaults(handler=run, time=None)



def _stroke(text: str) -> Stroke:
    layer, _, rest = text.partition(":")
    where, _, mode = rest.partition(":")
    try:
        x, z, r = (float(v) for v in where.split(","))
        if not layer or mode not in ("", "erase"):
            raise ValueError(text)
        return Stroke(layer, x, z, r, mode == "erase")
    except ValueError:  # a ParamError too: a radius <= 0
        raise argparse.ArgumentTypeError(f"expected LAYER:X,Z,R[:erase] with R > 0, found {text!r}") from None


def run(args) -> None:
    from ..gl.image import parse_size
    from ..viewer import Viewer, ViewerSettings

    wind = wind_arg(args)
    options = cull_options(args)
    if args.no_lod:
        options["lod"] = False
    elif not options["lod"]:
        options["lod"] = None  # automatic: on from LOD_AUTO_COUNT instances
    extra = None
    if args.frames < 1:
        raise AxialDeformError(f"--frames: expected 1 or more, found {args.frames}")
    # --headless draws them all unattended: every frame counts; a window is the user's to watch
    # and close (a million stones at full detail is its point): not capped
    frames = args.frames if args.headless else 0
    scene = scenes.scene_of(args, params_optional=True)
    if scene is not None:
        scenes.check_triangles(scene, args, args.mode, args.fast, frames)  # the mode it starts in; LOD: level 0
        mesh, params, seed = scene, None, args.seed
        # a terrain is the scene's ground; without one, the ground plane (as render draws it)
        args.up, args.no_ground = scene.up, args.no_ground or scene.terrain is not None
    elif args.params:
        mesh = load_base(args, args.mesh)
        params = read_params(args.params, mesh, allow_mesh_mismatch=args.ignore_mesh_mismatch)
        check_drawable(params, str(args.params))  # a picture: every number must survive the projection
        check_triangles([(f"{args.mesh} x {args.params}", len(params), drawn_triangles(mesh, args.part))],
                        args.mode, args.max_triangles, args.fast, frames)  # before the levels of detail, any drawing
        seed = args.seed  # a file records no seed: shown only if the user names one
    else:

        check_count(args.count, RANDOM_BYTES_EACH, "-n/--count")  # before anything is read or allocated
        mesh = load_base(args, args.mesh)
        check_triangles([(f"{args.mesh} x -n {args.count}", args.count, drawn_triangles(mesh, args.part))],
                        args.mode, args.max_triangles, args.fast, frames)  # before the parameters are made
        seed = 0 if args.seed is None else args.seed
        params = random_params(mesh, args.count, seed=seed, variation=Variation(bend=args.bend), up=args.up)
    if args.screenshot:  # never an input, nor a file that exists without --overwrite
        sources = scene.sources if scene is not None else (*mesh.sources, args.params)
        check_output_path(args.screenshot, sources, "screenshot", overwrite=args.overwrite)
    if args.paint and scene is None:
        raise AxialDeformError("--paint: expected a scene file with generated layers (view SCENE.toml --paint ...)")
    if args.paint:  # a mask replaces only the mask it was read from: never another input
        masks = {mask_path(scene.path, layer.name) for layer in scene.layers}
        others = [s for s in scene.sources if Path(s) not in masks]
        for layer in {stroke.layer for stroke in args.paint}:
            check_output_path(mask_path(scene.path, layer), others, "mask")
    walk = None
    if args.walk is not None:
        try:
            walk = [float(x) for x in args.walk.split(",")]
        except ValueError:
            walk = []
        if len(walk) != 2 or not all(math.isfinite(x) for x in walk):
            raise AxialDeformError(f"--walk: expected DX,DZ (two finite numbers), found {args.walk!r}")
    options = RenderOptions(up=args.up, wind=wind, parts=args.part, **options)
    settings = ViewerSettings(seed=seed, walk=walk, bend=args.bend, mode=args.mode, extra=extra,
                              on_screenshot=lambda path: print(f"wrote {path}"))
    look = (scene.look if scene is not None else Look()).replace(ground=not args.no_ground, fast=args.fast)
    viewer = Viewer.create(mesh, params, headless=args.headless, size=parse_size(args.size), look=look, options=options,
                           settings=settings)
    if not args.headless:
        import moderngl_window as mglw

        mglw.run_window_config_instance(viewer)
        return
    for stroke in args.paint or ():
        viewer.brush.stroke(stroke)
    try:
        viewer.step(args.frames)
        if args.screenshot:
            viewer.save_screenshot(args.screenshot)
        print(viewer.status() + (f" - wrote {args.screenshot}" if args.screenshot else ""))
        for path in viewer.brush.save() if args.paint else ():
            print(f"wrote {path} (the mask of its layer: read again whenever the scene is loaded)")
    finally:
        viewer.release()
        viewer.wnd.destroy()

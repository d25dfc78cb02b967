"""``axialdeform web``: the scene as a WebGL 2 page (three.js), and ``--serve``."""

from __future__ import annotations

import sys
from pathlib import Path
from urllib.parse import quote

from ..core.errors import AxialDeformError
from ..core.io.params import read_params
from ..core.look import DEFAULT_LOOK
from ..core.options import RenderOptions
from ..core.params import check_drawable
from ..core.scene import is_scene_file
from ..web import PageOptions, build_scene, build_scene_file, make_server, page_files, write_page
from ._common import add_axis, add_overwrite, add_wind_args, load_base, wind_arg
from .scenes import scene_of, scene_time

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> None:
    w = subparsers.add_parser("web", help="write the scene as a web page (WebGL 2, three.js)", description=(
        "Write MESH bent by PARAMS (or a scene file SCENE.toml: its layers, terrain, camera, light and wind) "
        "as a page that draws it in a browser with the package's own shader: "
        "OUT a folder (index.html + files, for a static server) or OUT.html (one self-contained file that "
        "works opened from disk). --serve serves the folder on 127.0.0.1 and prints the URL. "
        "The page: drag to orbit, W toggles wireframe; ?t=SECONDS freezes the wind's clock, ?size=WxH fixes the canvas."))
    w.add_argument("mesh", nargs="?", help="base mesh file, 'stone' / 'leaf' / 'leafcard' / 'tree', or a scene file .toml "
                   "(default: none: serve an exported page)")
    add_axis(w)
    w.add_argument("params", nargs="?", help="parameter file, .adp or text (default: none: serve an exported page)")
    w.add_argument("-o", "--output", required=True, help="folder, or a name ending in .html (required)")
    w.add_argument("--size", default=None, help="canvas WIDTHxHEIGHT, fixed; the camera is render's at this size "
                   "(default: the canvas fills the window, the camera framed for 800x600)")
    w.add_argument("--up", choices=("x", "y", "z"), default="y", help="world up axis (default: %(default)s)")
    w.add_argument("--mode", choices=("solid", "flat", "wireframe"), default="solid",
                   help="how to draw at first; W on the page toggles wireframe (default: %(default)s)")
    w.add_argument("--no-ground", action="store_true",
                   help="draw no ground plane (default: render's, under a scene without a terrain)")
    w.add_argument("--float32", action="store_true",
                   help="ship the float32 records instead of the quantized form (default: quantized)")
    w.add_argument("--ignore-mesh-mismatch", action="store_true",
                   help="use PARAMS even if made for another mesh (default: refuse)")
    add_wind_args(w)
    for action in w._actions:  # the page's clock: frozen at --time, else it runs
        if action.dest == "time":
            action.help = ("seconds: freeze the wind's clock there (a scene's [wind] or --wind; ?t= on the page "
                           "overrides) (default: the clock runs)")
    w.add_argument("--allow-outside", action="store_true",
                   help="let a scene's page carry files from outside the scene file's folder (default: refuse: "
                        "a page is shared, and ../ or absolute paths could reach private files)")
    w.add_argument("--serve", action="store_true", help="serve the page on 127.0.0.1 until Ctrl-C (default: only write)")
    w.add_argument("--port", type=int, default=8000, help="port for --serve; a busy one is replaced by a free one (default: %(default)s)")
    add_overwrite(w, " (in a folder: the files the page is made of)")
    w.set_defaults(handler=run)


def run(args) -> None:
    from ..gl.image import parse_size

    out = Path(args.output)
    if args.serve and not 0 <= args.port <= 65535:
        raise AxialDeformError(f"--port: expected a TCP port 0..65535 (0: any free one), found {args.port}")
    size = parse_size(args.size) if args.size is not None else (800, 600)
    time = args.time  # the page's frozen time (None: the wind's clock runs)
    if args.mesh is not None and is_scene_file(args.mesh):

        scene = scene_of(args)
        if args.wind is not None:  # replaces the scene's [wind]
            scene.wind = wind_arg(args)
        if time is not None:
            scene_time(scene, args)  # refuses a time without a wind
        if args.up != "y":
            raise AxialDeformError(f"--up: a scene file ({args.mesh}) names its own up axis; expected no --up")
        page = PageOptions(size=size, mode=args.mode, quantize=not args.float32, fixed_size=args.size is not None)
        look = scene.look.replace(ground=False) if args.no_ground else None
        web = build_scene_file(scene, page, look=look, options=RenderOptions(time=time), allow_outside=args.allow_outside)
        page = write_page(out, web, inputs=scene.sources, overwrite=args.overwrite)
        layers = [layer for layer in web.config["layers"] if not layer["terrain"]]
        made = [layer for layer in layers if layer.get("generate")]
        listed = sum(layer["instances"] for layer in layers if not layer.get("generate"))
        what = []
        if len(made) < len(layers):
            what.append(f"{listed} instances in parameter files, {'float32' if args.float32 else 'quantized'}")
        if made:  # a recipe: the page makes the tiles within reach of its camera, not render's extent
            what.append(f"{len(made)} generated layer{'s' if len(made) > 1 else ''} as recipes: the page makes "
                        f"{sum(layer['instances'] for layer in made)} instances within reach of its camera at the start "
                        "(render draws the extent)")
        print(f"wrote {page} ({len(layers)} layers{', a terrain' if len(layers) < len(web.config['layers']) else ''}; "
              + "; ".join(what) + ")")
    elif (args.mesh is None) != (args.params is None):
        raise AxialDeformError("web: expected both MESH and PARAMS, a scene file .toml, or neither (with --serve)")
    elif args.mesh is not None:

        mesh = load_base(args, args.mesh)
        params = read_params(args.params, mesh, allow_mesh_mismatch=args.ignore_mesh_mismatch)
        check_drawable(params, str(args.params))  # a picture: every number must survive the projection
        page = PageOptions(size=size, mode=args.mode, quantize=not args.float32, fixed_size=args.size is not None)
        look = DEFAULT_LOOK.replace(ground=False) if args.no_ground else None
        scene = build_scene(mesh, params, page, look=look, options=RenderOptions(up=args.up, wind=wind_arg(args), time=time))
        page = write_page(out, scene, inputs=(*mesh.sources, args.params), overwrite=args.overwrite)
        print(f"wrote {page} ({len(params)} instances, {'float32' if args.float32 else 'quantized'} parameters)")
    elif not args.serve:
        raise AxialDeformError("web: expected MESH and PARAMS (or --serve to serve an exported page)")
    else:
        page = out / "index.html" if out.is_dir() or out.suffix.lower() not in (".html", ".htm") else out
        if not page.is_file():
            raise AxialDeformError(f"{page}: no exported page to serve; give MESH and PARAMS to write one")
    if not args.serve:
        return
    if page.name == "index.html" and (page.parent / "scene.json").is_file():
        files = page_files(page.parent)  # a folder page: its own files, nothing else of the folder
    else:
        files = [page.name]  # one self-contained page: that file alone
    server, busy = make_server(page.parent, args.port, files=files)
    port = server.server_address[1]
    if busy:
        print(f"axialdeform web: port {args.port} is busy; using {port}", file=sys.stderr)
    print(f"serving {page.parent.resolve()} at http://127.0.0.1:{port}/{quote(page.name)}  (Ctrl-C to stop)", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()

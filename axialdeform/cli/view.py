"""``axialdeform view``: the interactive viewer (:mod:`axialdeform.viewer`)."""

from __future__ import annotations

from ._common import AXES, add_mesh_mismatch


def add_parser(sub) -> None:
    from ..gl.renderer import MODES

    v = sub.add_parser("view", help="look at instances in an interactive window", description=(
        "Open MESH (a file, or 'stone' / 'leaf') deformed by PARAMS (or by random parameters) in a window: "
        "drag to orbit, scroll to zoom; keys 1/2/3 solid/flat/wireframe, W next mode, N new seed, "
        "UP/DOWN bend amplitude, G ground, R reset camera, S screenshot, ESC quit."))
    v.add_argument("mesh", help="base mesh file, or 'stone' / 'leaf'")
    v.add_argument("params", nargs="?", help="parameter file (default: random parameters)")
    v.add_argument("-n", "--count", type=int, default=1000, help="random instances when no PARAMS (default: %(default)s)")
    v.add_argument("--seed", type=int, default=None,
                   help="seed of the random parameters when no PARAMS (default: 0; with PARAMS: none, the file's)")
    v.add_argument("--bend", type=float, default=0.08, help="offset amplitude for N, fraction of L (default: %(default)s)")
    v.add_argument("--mode", choices=MODES, default="solid", help="how to draw at the start (default: %(default)s)")
    v.add_argument("--up", choices=AXES, default="y", help="world up axis (default: %(default)s)")
    v.add_argument("--size", default="960x720", help="WIDTHxHEIGHT (default: %(default)s)")
    v.add_argument("--no-ground", action="store_true", help="start without the ground plane (default: with it)")
    v.add_argument("--headless", action="store_true", help="no window: draw --frames frames offscreen, EGL (default: a window)")
    v.add_argument("--frames", type=int, default=3, help="frames to draw with --headless (default: %(default)s)")
    v.add_argument("--screenshot", help="PNG of the last frame, with --headless (default: none)")
    add_mesh_mismatch(v)
    v.set_defaults(handler=run)


def run(args) -> None:
    from ..core.errors import AxialDeformError
    from ..core.mesh import load_mesh
    from ..core.params import read_params
    from ..core.variation import random_params
    from ..gl.image import parse_size
    from ..viewer import Viewer

    mesh = load_mesh(args.mesh)
    if args.params:
        params = read_params(args.params, mesh, allow_mesh_mismatch=args.ignore_mesh_mismatch)
        seed = args.seed  # a file records no seed: shown only if the user names one
    else:
        seed = 0 if args.seed is None else args.seed
        params = random_params(mesh, args.count, seed=seed, bend=args.bend, up=args.up)
    if args.frames < 1:
        raise AxialDeformError(f"--frames: expected 1 or more, found {args.frames}")
    viewer = Viewer.create(mesh, params, headless=args.headless, size=parse_size(args.size), seed=seed,
                           bend=args.bend, mode=args.mode, up=args.up, ground=not args.no_ground,
                           on_screenshot=lambda path: print(f"wrote {path}"))
    if not args.headless:
        import moderngl_window as mglw

        mglw.run_window_config_instance(viewer)
        return
    try:
        viewer.step(args.frames)
        if args.screenshot:
            viewer.save_screenshot(args.screenshot)
        print(viewer.status() + (f" - wrote {args.screenshot}" if args.screenshot else ""))
    finally:
        viewer.release()
        viewer.wnd.destroy()

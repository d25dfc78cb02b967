"""``axialdeform view MESH [PARAMS]``: an interactive viewer on moderngl-window.

Mouse: drag to orbit, scroll to zoom.  Keys::

    1 / 2 / 3   solid / flat / wireframe        W   next mode
    N           new seed (new individual shapes, same placement)
    UP / DOWN   bend amplitude x1.25 / x0.8 (also + and -)
    G           ground plane on / off          R   reset the camera
    V           wind on / off (``--wind``; moves control points on the GPU, no upload)
    S           save a screenshot (axialdeform-view-NNN.png)
    ESC         quit

The window title shows the instance count, the mode, the bend amplitude and
the frame rate.  ``--headless`` runs the same viewer in moderngl-window's
headless window (an EGL context, no display) for a number of frames and
can save the last one (``--screenshot``), which is how the tests drive it.

From Python::

    from axialdeform.viewer import Viewer
    Viewer.open(mesh, params)                                   # a window
    v = Viewer.create(mesh, params, headless=True)              # drive it yourself
    v.on_key_event("w", v.wnd.keys.ACTION_PRESS, None); v.step(); image = v.screenshot()
"""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path

import numpy as np

from .gl.camera import UP_VECTORS, frame_instances, instance_bounds
from .core.errors import AxialDeformError, ContextError, ParamError
from .gl.renderer import MODES

__all__ = ["Viewer", "add_parser", "run", "KEY_ACTIONS"]

#: key name -> what it does (names are moderngl-window's key attribute names)
KEY_ACTIONS = {
    "NUMBER_1": "solid", "NUMBER_2": "flat", "NUMBER_3": "wireframe", "W": "next mode",
    "N": "new seed", "UP": "more bend", "EQUAL": "more bend", "DOWN": "less bend", "MINUS": "less bend",
    "G": "ground", "R": "reset camera", "S": "screenshot", "V": "wind",
}
#: single characters accepted by ``on_key_event`` in place of a window's key code
_CHAR_KEYS = {"1": "NUMBER_1", "2": "NUMBER_2", "3": "NUMBER_3", "+": "EQUAL", "-": "MINUS"}
BACKGROUND = (0.80, 0.86, 0.92)


def _window_config_base():
    try:
        import moderngl_window as mglw
    except ImportError as exc:  # pragma: no cover - a dependency
        raise ContextError(f"moderngl-window is not installed ({exc}); pip install 'moderngl-window>=2.4'") from None
    return mglw


class _ViewerMixin:
    """The viewer's state and event handlers; mixed into a moderngl-window
    ``WindowConfig`` by :meth:`Viewer.create` (so importing this module does
    not need moderngl-window)."""

    gl_version = (3, 3)
    title = "axialdeform view"
    window_size = (960, 720)
    aspect_ratio = None
    resizable = True
    samples = 4
    vsync = True
    clear_color = None
    log_level = logging.WARNING
    scene: dict = {}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        from .gl.ground import GroundPlane
        from .gl.renderer import AxialRenderer

        s = self.scene
        self.mesh = s["mesh"]
        self.base = np.array(s["params"], dtype=np.float32)
        self.animate = s.get("animate")
        self.seed = int(s.get("seed", 0))
        self.bend = float(s.get("bend", 0.08))
        self.up = s.get("up", "y")
        self.mode = s.get("mode", "solid")
        if self.mode not in MODES:
            raise AxialDeformError(f"mode: expected one of {', '.join(MODES)}, found {self.mode!r}")
        self.bend_scale = 1.0
        self.show_ground = bool(s.get("ground", True))
        self.wind = s.get("wind")  # the Wind the V key switches on and off
        self.renderer = AxialRenderer(self.ctx, self.mesh, self.base, wind=self.wind)
        if s.get("tint") is not None:
            self.renderer.set_tint(s["tint"])
        self.ground = GroundPlane(self.ctx, up=self.up).fit(self.mesh, self.base)
        self.fps = 0.0
        self.frames = 0
        self.screenshots = 0
        self._last_title = 0.0
        self._last_frame = None
        self._time = 0.0
        keys = self.wnd.keys
        self._keymap = {}
        for name in KEY_ACTIONS:
            code = getattr(keys, name, "undefined")
            if code != "undefined":
                self._keymap[code] = name
        self.reset_camera()
        self._update_title(force=True)

    # ------------------------------------------------------------ camera
    def reset_camera(self) -> None:
        """Frame every instance (azimuth 35 deg, elevation 30 deg)."""
        cam = frame_instances(self.mesh, self.base, self._aspect(), up=self.up, elevation=30.0)
        self.target = cam.target
        self.distance = float(np.linalg.norm(cam.eye - cam.target))
        self.azimuth, self.elevation = 35.0, 30.0
        centers, radii = instance_bounds(self.mesh, self.base)
        lo = (centers - radii[:, None]).min(axis=0) if len(centers) else -np.ones(3)
        hi = (centers + radii[:, None]).max(axis=0) if len(centers) else np.ones(3)
        self.extent = float(np.linalg.norm(hi - lo)) / 2 + 1e-6

    def _aspect(self) -> float:
        w, h = self.wnd.buffer_size
        return w / max(h, 1)

    def matrices(self):
        """Current ``(view, projection)``, (4, 4) float32 pyrr layout."""
        from .gl.camera import Camera

        up = np.asarray(UP_VECTORS[self.up])
        side = np.roll(up, 1)
        fwd = np.cross(side, up)
        az, el = math.radians(self.azimuth), math.radians(self.elevation)
        to_eye = math.cos(el) * (math.cos(az) * fwd + math.sin(az) * side) + math.sin(el) * up
        eye = self.target + self.distance * to_eye
        reach = self.extent * 3.0  # the ground reaches past the instances
        cam = Camera(eye, self.target, up, fovy=35.0, near=max(self.distance - reach, self.distance * 2e-3),
                     far=self.distance + reach)
        return cam.view(), cam.projection(self._aspect())

    def on_mouse_drag_event(self, x, y, dx, dy):
        """Orbit: 0.3 degrees per pixel."""
        self.azimuth = (self.azimuth - 0.3 * dx) % 360.0
        self.elevation = float(np.clip(self.elevation + 0.3 * dy, -5.0, 89.0))

    def on_mouse_scroll_event(self, x_offset, y_offset):
        """Zoom: 10 % per scroll step."""
        self.distance = float(np.clip(self.distance * 0.9 ** y_offset, 1e-3 * self.extent, 50.0 * self.extent))

    # ------------------------------------------------------------ keys
    def on_key_event(self, key, action, modifiers):
        """A window key code, or a key's name (``"W"``, ``"w"``, ``"1"``, ``"UP"``)."""
        if action != self.wnd.keys.ACTION_PRESS:
            return
        name = self._keymap.get(key)
        if name is None and isinstance(key, str):
            name = _CHAR_KEYS.get(key, key.upper())
        if name not in KEY_ACTIONS:
            return
        what = KEY_ACTIONS[name]
        if what in MODES:
            self.mode = what
        elif what == "next mode":
            self.mode = MODES[(MODES.index(self.mode) + 1) % len(MODES)]
        elif what == "new seed":
            self.regenerate(self.seed + 1)
        elif what == "more bend":
            self.set_bend_scale(self.bend_scale * 1.25)
        elif what == "less bend":
            self.set_bend_scale(self.bend_scale * 0.8)
        elif what == "ground":
            self.show_ground = not self.show_ground
        elif what == "wind":
            if self.wind is None:
                from .core.wind import Wind

                self.wind = Wind()
            self.renderer.wind = None if self.renderer.wind is not None else self.wind
        elif what == "reset camera":
            self.reset_camera()
        elif what == "screenshot":
            path = Path(f"axialdeform-view-{self.screenshots:03d}.png")
            self.screenshots += 1
            self.save_screenshot(path)
            print(f"wrote {path.resolve()}")
        self._update_title(force=True)

    # ------------------------------------------------------------ parameters
    def regenerate(self, seed: int) -> None:
        """New offsets (the individual shapes) from ``seed``; placement and
        orientation stay.  Written in place: the count does not change."""
        from .core.variation import random_params

        self.seed = int(seed)
        fresh = random_params(self.mesh, len(self.base), seed=self.seed, bend=self.bend)
        self.base[:, :10] = fresh[:, :10]
        self._upload(self.base)

    def set_bend_scale(self, scale: float) -> None:
        """Multiply every offset by ``scale`` (relative to the loaded ones)."""
        self.bend_scale = float(np.clip(scale, 0.0, 20.0))
        self._upload(self.base)

    def _upload(self, params) -> None:
        shown = np.array(params, dtype=np.float32)
        shown[:, :10] *= self.bend_scale
        self.renderer.update_params(shown)

    # ------------------------------------------------------------ drawing
    def on_render(self, time_s: float, frame_time: float):
        self._time = time_s
        if self.animate is not None:
            self._upload(self.animate(time_s))
        view, proj = self.matrices()
        self.wnd.use()
        self.ctx.clear(*BACKGROUND, 1.0, depth=1.0)
        if self.show_ground:
            self.ground.render(view, proj, background=BACKGROUND)
        self.renderer.render(view, proj, self.mode, up=UP_VECTORS[self.up], time=time_s)  # wind: uniforms only
        self.frames += 1
        now = time.perf_counter()  # measured, not the timer's frame_time (headless steps are simulated)
        if self._last_frame is not None and now > self._last_frame:
            rate = 1.0 / (now - self._last_frame)
            self.fps = rate if self.fps == 0 else 0.9 * self.fps + 0.1 * rate
        self._last_frame = now
        self._update_title()

    def status(self) -> str:
        """What the title bar shows."""
        wind = self.renderer.wind
        return (f"axialdeform view - {self.mesh.name}: {self.renderer.count} instances - {self.mode} - "
                f"bend x{self.bend_scale:.2f} - seed {self.seed}"
                + (f" - wind {wind.strength:g}" if wind is not None else "") + f" - {self.fps:.0f} fps")

    def _update_title(self, force: bool = False) -> None:
        now = time.perf_counter()
        if force or now - self._last_title > 0.5:
            self._last_title = now
            self.wnd.title = self.status()

    def step(self, frames: int = 1, dt: float = 1 / 30) -> None:
        """Draw ``frames`` frames (headless driving: time advances ``dt`` s each)."""
        for _ in range(int(frames)):
            self.wnd.render(self._time + dt, dt)
            self.wnd.swap_buffers()

    def screenshot(self) -> np.ndarray:
        """The last drawn frame, ``(height, width, 3) uint8``, first row at the top."""
        w, h = self.wnd.buffer_size
        color = self.ctx.renderbuffer((w, h), 4)
        fbo = self.ctx.framebuffer(color)
        try:
            self.ctx.copy_framebuffer(fbo, self.wnd.fbo)
            data = fbo.read(components=3, alignment=1)
        finally:
            fbo.release()
            color.release()
        self.wnd.use()
        return np.frombuffer(data, dtype=np.uint8).reshape(h, w, 3)[::-1].copy()

    def save_screenshot(self, path) -> None:
        """Write the last drawn frame as a PNG, atomically."""
        from .gl.image import save_png

        save_png(path, self.screenshot())

    def on_close(self):
        self.release()

    def release(self) -> None:
        """Free the renderer and the ground plane (the window keeps its context)."""
        self.renderer.release()
        self.ground.release()


class Viewer:
    """Builds and runs the viewer window (see the module docstring)."""

    @staticmethod
    def create(mesh, params, *, headless: bool = False, size=(960, 720), animate=None, tint=None, seed: int = 0,
               bend: float = 0.08, mode: str = "solid", up: str = "y", ground: bool = True, samples: int = 4,
               wind=None):
        """A ready viewer (a moderngl-window ``WindowConfig``) with its window.

        mesh : BaseMesh; params : (n, 16) the instances; animate : optional
        ``f(t_seconds) -> (n, 16)`` called every frame; tint : optional (n, 3)
        linear RGB per instance; seed, bend : what ``N`` regenerates offsets
        with (bend as a fraction of L); headless : moderngl-window's headless
        window on an EGL context (no display needed); wind : an
        :class:`axialdeform.Wind` animated on the GPU (``V`` toggles it).
        params may be (n, 19): extended instances.
        """
        from .core.params import as_params

        mglw = _window_config_base()
        params = as_params(params)
        if animate is not None and as_params(animate(0.0)).shape != params.shape:
            raise ParamError("animate(t) must return as many instances as params")
        scene = dict(mesh=mesh, params=params, animate=animate, tint=tint, seed=seed, bend=bend, mode=mode,
                     up=up, ground=ground, wind=wind)
        app = type("AxialViewer", (_ViewerMixin, mglw.WindowConfig), {"scene": scene, "samples": samples})
        w, h = (int(size[0]), int(size[1]))
        argv = ["--size", f"{w}x{h}"]
        if headless:
            argv += ["--window", "headless", "--backend", "egl"]
        logging.getLogger("moderngl_window").setLevel(logging.WARNING)
        try:
            return mglw.create_window_config_instance(app, args=argv)
        except AxialDeformError:
            raise
        except Exception as exc:
            hint = "" if headless else "; without a display use --headless"
            raise ContextError(f"could not open the viewer window ({type(exc).__name__}: {exc}){hint}") from None

    @classmethod
    def open(cls, mesh, params, **kwargs) -> None:
        """Open a window and run until it is closed (blocking)."""
        import moderngl_window as mglw

        viewer = cls.create(mesh, params, **kwargs)
        mglw.run_window_config_instance(viewer)


# ---------------------------------------------------------------- the command
def add_parser(subparsers) -> None:
    """Register ``axialdeform view`` (the cli.PLUGINS hook)."""
    v = subparsers.add_parser("view", help="look at instances in an interactive window", description=(
        "Open MESH (a file, or 'stone' / 'leaf') deformed by PARAMS (or by random parameters) in a window: "
        "drag to orbit, scroll to zoom; keys 1/2/3 solid/flat/wireframe, W next mode, N new seed, "
        "UP/DOWN bend amplitude, G ground, V wind, R reset camera, S screenshot, ESC quit."))
    v.add_argument("mesh")
    v.add_argument("params", nargs="?", help="parameter file (default: random parameters)")
    v.add_argument("-n", "--count", type=int, default=1000, help="random instances when no PARAMS (default: %(default)s)")
    v.add_argument("--seed", type=int, default=0)
    v.add_argument("--bend", type=float, default=0.08, help="offset amplitude for N, fraction of L (default: %(default)s)")
    v.add_argument("--mode", choices=MODES, default="solid")
    v.add_argument("--up", choices=("x", "y", "z"), default="y")
    v.add_argument("--size", default="960x720", help="WIDTHxHEIGHT (default: %(default)s)")
    v.add_argument("--no-ground", action="store_true", help="start without the ground plane")
    v.add_argument("--headless", action="store_true", help="no window: draw --frames frames offscreen (EGL)")
    v.add_argument("--frames", type=int, default=3, help="frames to draw with --headless (default: %(default)s)")
    v.add_argument("--screenshot", help="PNG of the last frame (with --headless)")
    v.add_argument("--ignore-mesh-mismatch", action="store_true")
    v.add_argument("--wind", metavar="STRENGTH[,GUST[,FREQ[,WAVELENGTH]]]", default=None,
                   help="animate a wind on the GPU (docs/wind.md); V toggles it")
    v.add_argument("--wind-dir", metavar="X,Y,Z", default="1,0,0", help="wind direction, world (default: %(default)s)")
    v.set_defaults(handler=run)


def run(args) -> None:
    """The ``view`` command."""
    from .gl.image import parse_size
    from .core.mesh import load_mesh
    from .core.params import read_params
    from .core.variation import random_params

    from .core.wind import Wind

    wind = None
    if args.wind is not None:
        try:
            direction = tuple(float(x) for x in args.wind_dir.split(","))
        except ValueError:
            direction = ()
        if len(direction) != 3:
            raise ParamError(f"--wind-dir: expected X,Y,Z (three numbers), found {args.wind_dir!r}")
        wind = Wind.parse(args.wind, direction=direction)
    mesh = load_mesh(args.mesh)
    if args.params:
        params = read_params(args.params, mesh, allow_mesh_mismatch=args.ignore_mesh_mismatch)
    else:
        params = random_params(mesh, args.count, seed=args.seed, bend=args.bend, up=args.up)
    if args.frames < 1:
        raise AxialDeformError(f"--frames: expected 1 or more, found {args.frames}")
    viewer = Viewer.create(mesh, params, headless=args.headless, size=parse_size(args.size), seed=args.seed,
                           bend=args.bend, mode=args.mode, up=args.up, ground=not args.no_ground, wind=wind)
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

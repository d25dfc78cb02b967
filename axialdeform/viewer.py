"""``axialdeform view MESH [PARAMS]``: an interactive viewer on moderngl-window.

Mouse: drag to orbit, scroll to zoom.  Keys::

    1 / 2 / 3   solid / flat / wireframe        W   next mode
    N           new seed (new individual shapes, same placement)
    UP / DOWN   bend amplitude x1.25 / x0.8 (also + and -)
                (a scene file: N, UP/DOWN and V act on every layer)
    G           ground plane on / off          R   reset the camera
    V           wind on / off (``--wind``; moves control points on the GPU, no upload)
    S           save a screenshot (axialdeform-view-NNN.png)
    ESC         quit

Instances outside the view are culled on the GPU (``--no-cull`` turns it
off) and, from 100 000 instances on (or with ``--lod``), far ones are drawn
with simplified levels of detail (``--no-lod``, ``--lod-error PX``), so
``axialdeform view stone -n 1000000`` draws only what is in view, mostly
with the coarse levels (docs/culling.md has measured frame times).  The window title shows the instance
count, the mode, the bend amplitude, how many instances were drawn and
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
import time
from dataclasses import dataclass, replace
from dataclasses import fields as dataclass_fields
from pathlib import Path

import moderngl_window as mglw
import numpy as np

from .core.bounds import instance_bounds, stack_spheres
from .core.camera import UP_VECTORS, OrbitCamera
from .core.errors import ArgumentError, AxialDeformError, ContextError, ParamError
from .core.generate import extent_box, tile_size, tile_spheres, tiles_around, world_edge
from .core.io.image import save_png
from .core.look import DEFAULT_LOOK
from .core.options import RenderOptions, warn_field_keywords
from .core.params import as_params
from .core.scene import Scene
from .core.variation import Variation, random_params
from .core.wind import Wind
from .gl.context import check_image_size, create_context, read_pixels
from .gl.frame import Frame
from .gl.generated import GeneratedTiles
from .gl.ground import GroundPlane
from .gl.image import look_from_keywords, pop_look_keywords
from .gl.renderer import MODES, AxialRenderer
from .gl.scene import SceneRenderer, ground_spheres
from .gl.shadow import ShadowMap
from .viewer_brush import Brush, Stroke

__all__ = ["Viewer", "ViewerSettings", "KEY_ACTIONS"]

_log = logging.getLogger(__name__)

#: key name -> what it does (names are moderngl-window's key attribute names)
KEY_ACTIONS = {
    "NUMBER_1": "solid", "NUMBER_2": "flat", "NUMBER_3": "wireframe", "W": "next mode",
    "N": "new seed", "UP": "more bend", "EQUAL": "more bend", "DOWN": "less bend", "MINUS": "less bend",
    "G": "ground", "R": "reset camera", "S": "screenshot", "V": "wind", "B": "brush", "E": "erase",
    "LEFT_BRACKET": "smaller brush", "RIGHT_BRACKET": "larger brush", "M": "save masks",
}
#: single characters accepted by ``on_key_event`` in place of a window's key code
_CHAR_KEYS = {"1": "NUMBER_1", "2": "NUMBER_2", "3": "NUMBER_3", "+": "EQUAL", "-": "MINUS", "[": "LEFT_BRACKET",
              "]": "RIGHT_BRACKET"}
#: the viewer draws levels of detail by default from this many instances on
LOD_AUTO_COUNT = 100_000


def _window_config_base():
    try:
        import moderngl_window as mglw
    except ImportError as exc:  # pragma: no cover - a dependency
        raise ContextError(f"moderngl-window is not installed ({exc}); pip install 'moderngl-window>=3.0'") from None
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

        s = self.scene
        self.mesh = s["mesh"]
        self.base = np.array(s["params"], dtype=np.float32)
        #: generated layers (core/generate.py) are made tile by tile around the camera's target
        self.generate = s.get("generate")
        self.animate = s.get("animate")
        seed = s.get("seed")
        self.seed = None if seed is None else int(seed)  # None: the parameters came from elsewhere (a file)
        self.on_screenshot = s.get("on_screenshot")
        bend = s.get("bend", Variation.bend)  # one amplitude, or one a level of a hierarchy
        self.bend = tuple(float(b) for b in bend) if isinstance(bend, (tuple, list)) else float(bend)
        self.up = s.get("up", "y")
        self.mode = s.get("mode", "solid")
        if self.mode not in MODES:
            raise ArgumentError(f"mode: expected one of {', '.join(MODES)}, found {self.mode!r}")
        self.bend_scale = 1.0
        #: how the frames look (axialdeform.Look); G toggles its ground
        self.look = s.get("look") or DEFAULT_LOOK
        self.show_ground = self.look.draws_ground
        self.wind = s.get("wind")  # the Wind the V key switches on and off
        # levels of detail part by part, carrying UVs, colours and tangents (core/lod.py)
        held = len(self.base) if self.generate is None else (  # a generated layer: the slots within its reach
            len(tiles_around(self.generate.generate, 0.0, 0.0, self.generate.reach)) * tile_size(self.generate.generate)[0] ** 2)
        lod = s.get("lod", held >= LOD_AUTO_COUNT)
        options = RenderOptions(parts=s.get("parts"), wind=self.wind, culling=s.get("culling", True), lod=lod,
                                lod_error=s.get("lod_error", 1.0), position_ids=s.get("generate") is not None)
        self.renderer = AxialRenderer(self.ctx, self.mesh, self.base, options)
        if s.get("tint") is not None:
            self.renderer.set_tint(s["tint"])
        # render's ground rule (gl/scene.py ground_spheres): under the viewer's own instances and the scene's other
        # layers; a generated layer of its own refits it to the tiles it holds (_page_tiles)
        spheres = ([instance_bounds(self.mesh, self.base)] if len(self.base) else []) + (
            ground_spheres(s["extra"]) if s.get("extra") is not None else [])
        self.ground = GroundPlane(self.ctx, up=self.up)
        if spheres:
            self.ground.fit_spheres(*stack_spheres(spheres))
        self.fast = self.look.fast
        self.shadow = None
        if self.look.draws_shadow:  # shadows from the key light, redrawn each frame (one instanced draw per part)

            self.shadow = ShadowMap(self.ctx, 2048)
        self.extra = None  # the other layers and the terrain of a scene file
        #: the other layers of a scene: [(layer, renderer, loaded params (n, 16|19) float32)];
        #: N, UP/DOWN and V act on them as on the viewer's own instances
        self.layers = []
        if s.get("extra") is not None:

            self.extra = SceneRenderer(self.ctx, s["extra"], generated_empty=True)  # the GPU makes their tiles
            self.layers = [(layer, r, layer.empty() if getattr(layer, "generate", None) is not None
                            else np.array(layer.params, dtype=np.float32)) for layer, r in self.extra.layers()]
            scene = s["extra"]
            #: a scene's wind, on or off for every layer at once (V)
            self.scene_wind_on = self.renderer.wind is not None or (
                scene.wind is not None and any(layer.wind for layer in scene.layers))
        if self.samples and self.samples > 1 and not getattr(self.wnd.fbo, "color_attachments", None):
            # a window's own multisampled framebuffer has no attachments to ask: BLEND parts by coverage
            for r in [self.renderer, *(r for _, r, _ in self.layers)]:
                r.alpha_to_coverage = True
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
        #: (dx, dz) world units the camera's target moves a frame (a walk), or None
        self.walk = None if s.get("walk") is None else np.asarray(s["walk"], dtype=np.float64).reshape(2)
        self._tiles = {}  # key -> the tiles held (a frozenset)
        self._gpu = {}  # key -> GeneratedTiles: the GPU makes the instances straight into the layer's renderer
        self._spheres = {}  # key -> (k, 4) the held tiles' bounds (shadows, the ground)
        self._rounds = 0  # N pressed: generated layers take seed + 7919 rounds
        #: painting where generated layers grow (B; viewer_brush.py)
        self.brush = Brush(self, s.get("scene_file"), s.get("first_name", ""), getattr(s.get("extra"), "terrain", None))
        self._update_title(force=True)

    # ------------------------------------------------------------ camera
    def reset_camera(self) -> None:
        """Frame every instance (azimuth 35 deg, elevation 30 deg); a generated layer of its own: its extent,
        from the recipe alone (its instances are made on the GPU, around the camera)."""
        if self.generate is not None:
            g = self.generate
            corners = extent_box(g.generate, self.mesh, g.extent, g.maps)
            spheres = np.column_stack([corners, np.zeros(len(corners))])
            self.orbit = OrbitCamera.framing_spheres(spheres, self._aspect(), up=self.up, azimuth=35.0, elevation=30.0)
            return
        self.orbit = OrbitCamera.framing(self.mesh, self.base, self._aspect(), up=self.up, azimuth=35.0, elevation=30.0)

    @property
    def azimuth(self) -> float:
        return self.orbit.azimuth

    @property
    def elevation(self) -> float:
        return self.orbit.elevation

    @property
    def distance(self) -> float:
        return self.orbit.distance

    def _aspect(self) -> float:
        w, h = self.wnd.buffer_size
        return w / max(h, 1)

    def matrices(self):
        """Current ``(view, projection)``, (4, 4) float32 pyrr layout."""
        return self.orbit.matrices(self._aspect())

    def on_mouse_drag_event(self, x, y, dx, dy):
        """Orbit: 0.3 degrees per pixel; with the brush on (B), paint the first generated layer under the cursor."""
        at = self.brush.at(x, y) if self.brush.on and self.brush.layers() else None
        if at is not None:
            self.brush.stroke(Stroke(next(iter(self.brush.layers())), *at, self.brush.radius, self.brush.erase))
        elif not self.brush.on:
            self.orbit.orbit(-0.3 * dx, 0.3 * dy)

    def on_mouse_scroll_event(self, x_offset, y_offset):
        """Zoom: 10 % per scroll step."""
        self.orbit.zoom(0.9 ** y_offset)

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
            self.regenerate(0 if self.seed is None else self.seed + 1)
        elif what == "more bend":
            self.set_bend_scale(self.bend_scale * 1.25)
        elif what == "less bend":
            self.set_bend_scale(self.bend_scale * 0.8)
        elif what == "ground":
            self.show_ground = not self.show_ground
        elif what == "wind":
            if self.extra is not None:  # a scene: every layer with wind = true sways or stills together
                self.scene_wind_on = not self.scene_wind_on
                self.extra.wind_enabled = self.scene_wind_on
                self.renderer.wind = self.wind if self.scene_wind_on else None
            else:
                if self.wind is None:

                    self.wind = Wind()
                self.renderer.wind = None if self.renderer.wind is not None else self.wind
        elif what == "brush":
            self.brush.on = not self.brush.on
        elif what == "erase":
            self.brush.erase = not self.brush.erase
        elif what in ("smaller brush", "larger brush"):
            self.brush.radius *= 0.8 if what == "smaller brush" else 1.25
        elif what == "save masks":
            for path in self.brush.save():
                _log.info("wrote %s", path)
        elif what == "reset camera":
            self.reset_camera()
        elif what == "screenshot":
            path = Path(f"axialdeform-view-{self.screenshots:03d}.png")
            self.screenshots += 1
            self.save_screenshot(path)
            _log.info("wrote %s", path.resolve())
            if self.on_screenshot is not None:
                self.on_screenshot(path.resolve())
        self._update_title(force=True)

    # ------------------------------------------------------------ parameters
    def regenerate(self, seed: int) -> None:
        """New offsets (the individual shapes) from ``seed``; placement and
        orientation stay.  Written in place: the count does not change.  Generated
        layers take their recipe's seed + 7919 a call instead: other instances, made
        again on the GPU (their places too: the seed draws them)."""

        self.seed = int(seed)
        self._rounds += 1  # generated layers: another seed of their recipe, the tiles made again (_upload)
        if self.generate is None:
            fresh = random_params(self.mesh, len(self.base), seed=self.seed, variation=Variation(bend=self.bend))
            cols = _offsets(self.mesh)
            self.base[:, cols] = fresh[:, cols]
        for k, (layer, _, base) in enumerate(self.layers):  # each other layer: its own seed, derived from the seed
            if len(base) and getattr(layer, "generate", None) is None:
                cols = _offsets(layer.mesh)
                base[:, cols] = random_params(layer.mesh, len(base), seed=self.seed + 7919 * (k + 1),
                                              variation=Variation(bend=self.bend))[:, cols]
        self._upload(self.base)

    def set_bend_scale(self, scale: float) -> None:
        """Multiply every offset by ``scale`` (relative to the loaded ones)."""
        self.bend_scale = float(np.clip(scale, 0.0, 20.0))
        self._upload(self.base)

    def _upload(self, params) -> None:
        self._tiles.clear()  # generated layers: made again with their offsets scaled
        for gpu in self._gpu.values():
            gpu.set_bend_scale(self.bend_scale)
        if self.generate is None:
            shown = np.array(params, dtype=np.float32)
            shown[:, _offsets(self.mesh)] *= self.bend_scale
            self.renderer.update_params(shown)
            self._shown = shown
        for layer, renderer, base in self.layers:
            if len(base) and getattr(layer, "generate", None) is None:
                other = base.copy()
                other[:, _offsets(layer.mesh)] *= self.bend_scale
                renderer.update_params(other)

    # ------------------------------------------------------------ drawing
    def _page_tiles(self) -> None:
        """Generated layers: the tiles within their reach of the camera's target, made on the GPU straight into
        the layer's renderer when the set changes (gl/generated.py: no record on the CPU; a tile is the same
        whatever made it, whenever); the ones out of reach are let go, so the instances held stay bounded
        however far the camera walks (docs/generate.md)."""

        target = self.orbit.target
        jobs = []
        if self.generate is not None:
            jobs.append(("", self.generate, self.mesh, self.renderer))
        for layer, renderer, _ in self.layers:
            if getattr(layer, "generate", None) is not None:
                jobs.append((layer.name, layer.generate, layer.mesh, renderer))
        for key, recipe, mesh, renderer in jobs:
            tiles = tiles_around(recipe.generate, float(target[0]), float(target[2]), recipe.reach)
            wanted = frozenset(map(tuple, tiles.tolist()))
            if self._tiles.get(key) == wanted:
                continue
            self._tiles[key] = wanted
            gpu = self._gpu.get(key)
            if gpu is None:
                gpu = self._gpu[key] = GeneratedTiles(renderer, recipe.generate, mesh, recipe.maps)
                gpu.set_bend_scale(self.bend_scale)
            gpu.set_seed(recipe.generate.seed + 7919 * self._rounds)
            gpu.make(tiles)
            self._spheres[key] = tile_spheres(gpu.recipe, mesh, tiles, recipe.maps)
            if key == "":  # a generated world stands on 0
                self.ground.fit_spheres(self._spheres[key][:, :3], self._spheres[key][:, 3], height=0.0)

    def _in_world(self, target: np.ndarray) -> np.ndarray:
        """``target`` with x and z held within the generated layers' world (docs/generate.md, "Bounds"): a walk
        stops at the nearest world's edge, where float32 positions still keep the cell grid."""
        recipes = [self.generate] if self.generate is not None else []
        recipes += [layer.generate for layer, _, _ in self.layers if getattr(layer, "generate", None) is not None]
        if not recipes:
            return target
        edge = min(world_edge(r.generate) for r in recipes)
        out = np.array(target, dtype=np.float64)
        out[[0, 2]] = np.clip(out[[0, 2]], -edge, edge)
        return out

    def on_render(self, time_s: float, frame_time: float):
        self._time = time_s
        if self.walk is not None:
            self.orbit.target = self._in_world(self.orbit.target + np.array([self.walk[0], 0.0, self.walk[1]]))
        if self.generate is not None or any(getattr(layer, "generate", None) is not None for layer, _, _ in self.layers):
            self._page_tiles()
        if self.animate is not None:
            self._upload(self.animate(time_s))
        view, proj = self.matrices()
        look = self.look
        # the viewer's own instances, then the scene's terrain and other layers: one frame (gl/frame.py)
        self.renderer.up = UP_VECTORS[self.up]
        self.renderer.time = time_s  # the shadows bend in this frame's wind; the wind: uniforms only
        renderers = [self.renderer]
        casters = [] if self.generate is not None else [(self.mesh, getattr(self, "_shown", self.base))]
        if self.extra is not None:
            self.extra.prepare(time_s)
            renderers += [r for r, _, _ in self.extra.renderers]
            casters += [(layer.mesh, layer.params) for layer in self.extra.scene.layers
                        if getattr(layer, "generate", None) is None]
        frame = Frame(renderers, ground=self.ground if self.show_ground else None, shadow=self.shadow)
        frame.shadow_pass(casters, look, spheres=np.vstack([np.zeros((0, 4)), *self._spheres.values()]))
        self.wnd.use()
        self.ctx.clear(*look.background, 1.0, depth=1.0)
        frame.draw(view, proj, self.mode, look)
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
        shown = self.renderer.stats.get("visible", self.renderer.count)
        seed = "" if self.seed is None else f" - seed {self.seed}"
        others = (f" + {sum(r.count for _, r, _ in self.layers)} in {len(self.layers)} more "
                  f"layer{'s' if len(self.layers) != 1 else ''}") if self.layers else ""
        return (f"axialdeform view - {self.mesh.name}: {self.renderer.count} instances{others} - {self.mode} - "
                f"bend x{self.bend_scale:.2f}{seed}"
                + (f" - wind {wind.strength:g}" if wind is not None else "") + f" - {shown} drawn - {self.fps:.0f} fps")

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

        image = read_pixels(self.ctx, self.wnd.fbo, resolve=True)
        self.wnd.use()
        return image

    def save_screenshot(self, path) -> None:
        """Write the last drawn frame as a PNG, atomically."""

        save_png(path, self.screenshot())

    def on_close(self):
        self.release()

    def release(self) -> None:
        """Free the renderer and the ground plane (the window keeps its context)."""
        for gpu in self._gpu.values():
            gpu.release()
        self.renderer.release()
        self.ground.release()
        if self.shadow is not None:
            self.shadow.release()
        if self.extra is not None:
            self.extra.release()


@dataclass(frozen=True)
class ViewerSettings:
    """The viewer's own settings (:meth:`Viewer.create`), beside what is drawn (:class:`RenderOptions`) and how
    it looks (:class:`~axialdeform.Look`).

    Attributes
    ----------
    animate : callable or None
        ``f(t_seconds) -> (n, 16)``, called every frame.
    tint : (n, 3) float or None
        Linear RGB per instance.
    seed : int or None
        The seed ``params`` were made with, shown in the title; None: not known, ``N`` then starts at 0.
    bend : float
        What ``N`` regenerates offsets with, a fraction of L (default :attr:`Variation.bend`).
    mode : {"solid", "flat", "wireframe"}
        The first drawing mode.
    on_screenshot : callable or None
        ``f(path)``, called after the S key wrote a screenshot.
    extra : Scene or None
        A loaded scene drawn too, every frame, in the same mode.
    walk : (dx, dz) or None
        Walk the camera by this much a frame (a generated layer's tiles follow it).
    """

    animate: object = None
    tint: object = None
    seed: int | None = None
    bend: object = Variation.bend
    mode: str = "solid"
    on_screenshot: object = None
    extra: object = None
    walk: object = None


_VIEWER_SETTINGS = tuple(f.name for f in dataclass_fields(ViewerSettings))


class Viewer:
    """Builds and runs the viewer window (see the module docstring)."""

    @staticmethod
    def create(scene, params=None, *, headless: bool = False, size=(960, 720), look=None,
               options: RenderOptions | None = None, settings: ViewerSettings | None = None, **fields):
        """A ready viewer (a moderngl-window ``WindowConfig``) with its window.

        Parameters
        ----------
        scene : Scene or BaseMesh
            A :class:`axialdeform.Scene` (its first layer is the viewer's own: N, UP/DOWN and V
            act on every layer; the terrain and the other layers are drawn too; its look, up and
            wind), or a BaseMesh with ``params``.
        params : (n, 16|19|22) float32, optional
            The instances of a mesh.
        headless : bool
            moderngl-window's headless window on an EGL context (no display needed).
        size : (int, int)
            The window's size.
        look : Look, optional
            How the frames look (:class:`axialdeform.Look`: ground, shadow, samples, light,
            background; ``Look(fast=True)``: no shadows, hidden lines or multisampling; the old
            ``ground``, ``samples`` and ``fast`` keywords still work, with a DeprecationWarning).
        options : RenderOptions, optional
            ``up``, ``parts`` (names of the mesh's parts to draw), ``wind`` (animated on the GPU;
            ``V`` toggles it), ``culling``, ``lod``, ``lod_error`` (:class:`axialdeform.RenderOptions`;
            ``lod=None``, the default: on from :data:`LOD_AUTO_COUNT` instances, so a million can be
            flown through, unless the mesh has parts or appearance).
        settings : ViewerSettings, optional
            The viewer's own: ``animate``, ``tint``, ``seed``, ``bend`` (what ``N`` regenerates offsets
            with), the first ``mode``, ``on_screenshot``, ``extra`` (a scene drawn too) and ``walk``
            (:class:`ViewerSettings`).
        **fields
            Deprecated (still working for one release, with a DeprecationWarning): fields of
            :class:`ViewerSettings` or of :class:`RenderOptions` as keywords.
        """

        own = {k: fields.pop(k) for k in list(fields) if k in _VIEWER_SETTINGS}
        warn_field_keywords("Viewer.create", own, "settings", "viewer.ViewerSettings")
        if settings is not None and not isinstance(settings, ViewerSettings):
            raise ArgumentError(f"settings: expected an axialdeform.viewer.ViewerSettings, found {type(settings).__name__}")
        s = replace(settings or ViewerSettings(), **own)
        animate, tint, seed, extra, walk = s.animate, s.tint, s.seed, s.extra, s.walk
        bend, mode, on_screenshot = s.bend, s.mode, s.on_screenshot
        old_keywords = pop_look_keywords(fields)
        opts = RenderOptions.of(options, fields, "Viewer.create", ("up", "parts", "wind", "culling", "lod", "lod_error"))
        up, parts, wind, culling, lod_error = opts.up, opts.parts, opts.wind, opts.culling, opts.lod_error
        lod = opts.lod  # None: on from LOD_AUTO_COUNT instances
        # the one mesh-or-scene check; the first layer is the viewer's own, the others and the terrain are drawn too
        scene = Scene.of(scene, params, up=up, wind=wind, parts=parts)
        if not scene.layers:
            raise AxialDeformError(f"{scene.path}: the scene has no layer; expected at least one [[layer]]")
        first = scene.layers[0]
        # a generated layer of its own: none made here; the GPU makes the tiles around the camera (_page_tiles)
        mesh, up = first.mesh, scene.up
        params = first.empty() if first.generate is not None else first.params
        wind = wind if wind is not None else (scene.wind if first.wind else None)
        if wind is not None:
            scene.wind = wind
        if len(scene.layers) > 1 or scene.terrain is not None:
            extra = replace(scene, layers=scene.layers[1:])
        look = scene.look.replace(ground=scene.terrain is None) if look is None else look
        look = look_from_keywords(look, old_keywords, "Viewer.create")

        mglw = _window_config_base()
        params = as_params(params, axes=mesh.axis_count)
        if animate is not None and as_params(animate(0.0), axes=mesh.axis_count).shape != params.shape:
            raise ParamError("animate(t) must return as many instances as params")
        scene = dict(mesh=mesh, params=params, animate=animate, tint=tint, seed=seed, bend=bend, mode=mode,
                     up=up, look=look, on_screenshot=on_screenshot, parts=parts, wind=wind, extra=extra,
                     culling=culling, lod_error=lod_error, walk=walk, generate=first.generate, scene_file=scene.path,
                     first_name=first.name)
        if lod is not None:
            scene["lod"] = bool(lod)
        app = type("AxialViewer", (_ViewerMixin, mglw.WindowConfig), {"scene": scene, "samples": look.msaa})
        w, h = (int(size[0]), int(size[1]))
        argv = ["--size", f"{w}x{h}"]
        if headless:
            argv += ["--window", "headless", "--backend", "egl"]
            # the headless window is a framebuffer: the error says the context's limit (as render's does)

            probe = create_context()
            try:
                check_image_size(probe, (w, h), samples=0)
            finally:
                probe.release()
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

        viewer = cls.create(mesh, params, **kwargs)
        mglw.run_window_config_instance(viewer)


def _offsets(mesh) -> slice:
    """The columns of every axis's offsets: 10 a axis (several axes: axis 0's, then each child's)."""
    return slice(0, 10 * mesh.axis_count)

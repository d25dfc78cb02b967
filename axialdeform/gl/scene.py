"""Drawing a scene (:mod:`axialdeform.core.scene`): one :class:`AxialRenderer`
per layer, one draw call each, plus the terrain (drawn as ONE undeformed
instance of itself: zero offsets, no rotation, at the origin)."""

from __future__ import annotations

import numpy as np

from .camera import UP_VECTORS, Camera
from .context import Offscreen, create_context
from .renderer import AxialRenderer

__all__ = ["SceneRenderer", "scene_camera", "render_scene"]

TERRAIN_INSTANCE = np.zeros((1, 16), dtype=np.float32)


def _all_instances(scene):
    """Every layer's instances as spheres' worth of (mesh, params) pairs for framing."""
    pairs = [(layer.mesh, layer.params) for layer in scene.layers if len(layer.params)]
    if scene.terrain is not None:
        pairs.append((scene.terrain, TERRAIN_INSTANCE))
    return pairs


def scene_camera(scene, aspect: float) -> Camera:
    """The scene's camera: ``eye``/``target`` when given, else one that frames
    every layer and the terrain at the scene's elevation and azimuth."""
    cam = scene.camera
    fov = cam.get("fov", 35.0)
    up = UP_VECTORS[scene.up]
    if "eye" in cam:
        eye, target = np.asarray(cam["eye"]), np.asarray(cam["target"])
        dist = float(np.linalg.norm(eye - target))
        return Camera(eye, target, up, fov, near=dist * 1e-3, far=dist * 10)
    from ..core.bounds import instance_bounds
    from .camera import camera_for_points

    points, radii = [], []
    for layer in scene.layers:  # a sphere per instance (it holds the instance at any time of the wind)
        if len(layer.params):
            c, r = instance_bounds(layer.mesh, layer.params, wind=scene.wind if layer.wind else None)
            points.append(c)
            radii.append(np.broadcast_to(r, (len(c),)))
    if scene.terrain is not None:
        points.append(scene.terrain.positions)  # float32: concatenated (or read) as float64 once, below
        radii.append(np.zeros(len(scene.terrain.positions)))
    pts = np.concatenate(points) if points else np.zeros((0, 3))
    rad = np.concatenate(radii) if radii else np.zeros(0)
    return camera_for_points(pts, rad, aspect, scene.up, fov, cam.get("azimuth", 35.0), cam.get("elevation", 35.0))


class SceneRenderer:
    """Draws every layer of a scene (and its terrain) with one renderer each.

    ctx : moderngl.Context.  scene : a loaded :class:`~axialdeform.core.scene.Scene`.
    culling, lod, lod_error : each layer's :class:`AxialRenderer` options
    (per-instance culling, levels of detail -- textured and multi-part layer
    meshes too, one draw per level and part); the terrain, ONE instance, is
    always drawn whole.
    """

    def __init__(self, ctx, scene, *, culling: bool = True, lod: bool = False, lod_error: float = 1.0):
        self.ctx = ctx
        self.scene = scene
        self.renderers = []
        self._released = False
        #: False stills every layer's wind (the viewer's V key); True: the scene's
        self.wind_enabled = True
        try:
            if scene.terrain is not None:
                # no back-face culling: a height map is never a closed volume, and finding out
                # (BaseMesh.is_volume sorts every directed edge) costs ~100 bytes a face
                self.renderers.append((AxialRenderer(ctx, scene.terrain, TERRAIN_INSTANCE, cull_back_faces=False),
                                       scene.terrain_color, False))
            for layer in scene.layers:
                self.renderers.append((AxialRenderer(ctx, layer.mesh, layer.params, culling=culling, lod=lod,
                                                     lod_error=lod_error), layer.color, layer.wind))
        except BaseException:
            self.release()
            raise

    def layer(self, name: str) -> AxialRenderer:
        """The renderer of the layer called ``name`` (e.g. to ``update_params`` it each frame)."""
        start = 1 if self.scene.terrain is not None else 0
        for layer, (renderer, _, _) in zip(self.scene.layers, self.renderers[start:]):
            if layer.name == name:
                return renderer
        from ..core.errors import SceneError

        raise SceneError(f"layer: expected one of {', '.join(x.name for x in self.scene.layers)}, found {name!r}")

    def layers(self) -> list:
        """``[(layer, renderer), ...]`` of every layer, in the scene's order."""
        start = 1 if self.scene.terrain is not None else 0
        return [(layer, renderer) for layer, (renderer, _, _) in zip(self.scene.layers, self.renderers[start:])]

    def render(self, view, projection, mode: str = "solid", *, time: float = 0.0, look=None) -> None:
        """Draw everything into the bound framebuffer; ``time`` drives the wind of layers
        with ``wind = true`` (while :attr:`wind_enabled`); ``look`` (default: the
        scene file's, :attr:`Scene.look`) gives the light."""
        up = UP_VECTORS[self.scene.up]
        look = self.scene.look.replace(hidden_line=False) if look is None else look
        for renderer, color, sways in self.renderers:
            renderer.up = up
            if color is not None:
                renderer.color = tuple(color)
            renderer.wind = self.scene.wind if sways and self.wind_enabled else None
            renderer.render(view, projection, mode, look=look, time=time)

    def release(self) -> None:
        """Free every renderer; safe to call twice."""
        for renderer, _, _ in self.renderers:
            renderer.release()
        self.renderers = []
        self._released = True

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def render_scene(scene, size=(800, 600), mode: str = "solid", *, ctx=None, time: float = 0.0, samples: int = 4,
                 camera: Camera | None = None, culling: bool = True, lod: bool = False,
                 lod_error: float = 1.0) -> np.ndarray:
    """Render a scene to an ``(height, width, 3) uint8`` image (an EGL context is made if ``ctx`` is None);
    ``culling``, ``lod``, ``lod_error``: as :class:`SceneRenderer`."""
    own = ctx is None
    ctx = create_context() if own else ctx
    try:
        w, h = size
        cam = camera or scene_camera(scene, w / h)
        with SceneRenderer(ctx, scene, culling=culling, lod=lod, lod_error=lod_error) as sr, Offscreen(ctx, (w, h), samples=samples) as target:
            target.use(scene.background)
            sr.render(cam.view(), cam.projection(w / h), mode, time=time)
            return target.read()
    finally:
        if own:
            ctx.release()

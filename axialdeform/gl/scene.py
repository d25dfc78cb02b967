"""Drawing a scene (:mod:`axialdeform.core.scene`): one :class:`AxialRenderer`
per layer, one draw call each, plus the terrain (drawn as ONE undeformed
instance of itself: zero offsets, no rotation, at the origin)."""

from __future__ import annotations

import numpy as np

from ..core.bounds import instance_bounds, outline_points, wind_reach
from ..core.camera import UP_VECTORS, Camera, camera_for_points
from ..core.errors import SceneError
from ..core.generate import extent_box, tile_spheres, tiles_in
from ..core.options import RenderOptions
from ..core.record import WIDTH
from .renderer import AxialRenderer

__all__ = ["SceneRenderer", "scene_camera", "ground_spheres", "TERRAIN_INSTANCE"]

TERRAIN_INSTANCE = np.zeros((1, WIDTH), dtype=np.float32)


def scene_camera(scene, aspect: float, *, margin: float = 0.03) -> Camera:
    """THE framing rule of every picture: the scene's ``eye``/``target`` when
    its file gives them, else the orbit camera (the scene's elevation,
    azimuth and fov; 35 degrees each by default) that just sees every layer's
    bent instances -- tight outline points
    (:func:`axialdeform.core.bounds.outline_points`), or the bounding spheres
    of the wind's reach for a layer that sways -- and the terrain.  Its near
    and far planes enclose them; :meth:`Camera.enclosing_square` widens them
    for a ground plane."""
    cam = scene.camera
    fov = cam.fov
    up = UP_VECTORS[scene.up]
    if cam.eye is not None:
        eye, target = np.asarray(cam.eye), np.asarray(cam.target)
        dist = float(np.linalg.norm(eye - target))
        return Camera(eye, target, up, fov, near=dist * 1e-3, far=dist * 10)

    points, radii = [], []
    for layer in scene.layers:
        g = getattr(layer, "generate", None)
        if g is not None:  # a generated layer: its extent, from the recipe alone (no instance made for a frame)
            corners = extent_box(g.generate, layer.mesh, g.extent, g.maps)
            s_hi = max(g.generate.scale) if g.generate.scale is not None else 1.0
            sway = s_hi * wind_reach(layer.mesh, scene.wind) if layer.wind and scene.wind is not None else 0.0
            points.append(corners)
            radii.append(np.full(len(corners), sway))
            continue
        if not len(layer.params):
            continue
        if layer.wind and scene.wind is not None:  # a sphere per instance: it holds the instance at any time
            c, r = instance_bounds(layer.mesh, layer.params, wind=scene.wind)
        else:
            c, r = outline_points(layer.mesh, layer.params)
        points.append(c)
        radii.append(np.broadcast_to(r, (len(c),)))
    if scene.terrain is not None:
        # the terrain's float32 vertices as they are (2.25 M of a 1 500 x 1 500 map): never copied
        points.append(scene.terrain.positions)
        radii.append(np.broadcast_to(0.0, (len(scene.terrain.positions),)))
    return camera_for_points(points, radii, aspect, scene.up, fov, cam.azimuth, cam.elevation, margin)


def ground_spheres(scene) -> list:
    """THE spheres a ground plane is fitted under (:func:`~axialdeform.core.bounds.ground_square`), in render, the
    page and the widget alike: ``[(centers (n, 3), radii (n,)), ...]``, each listed layer's instance bounds and each
    generated layer's tiles over its extent (:func:`~axialdeform.core.generate.tile_spheres`: from the recipe
    alone, no instance made)."""
    out = []
    for layer in scene.layers:
        g = getattr(layer, "generate", None)
        if g is not None:
            s = tile_spheres(g.generate, layer.mesh, tiles_in(g.generate, g.extent, layer.mesh.axis_count), g.maps)
            out.append((s[:, :3], s[:, 3]))
        elif len(layer.params):
            out.append(instance_bounds(layer.mesh, layer.params))
    return out


class SceneRenderer:
    """Draws every layer of a scene (and its terrain) with one renderer each.

    ctx : moderngl.Context.  scene : a loaded :class:`~axialdeform.core.scene.Scene`.
    culling, lod, lod_error : each layer's :class:`AxialRenderer` options
    (per-instance culling, levels of detail -- textured and multi-part layer
    meshes too, one draw per level and part); the terrain, ONE instance, is
    always drawn whole.  position_ids : every layer's wind phases and shades hash where its
    instances stand (a generated layer's always do: :class:`~axialdeform.core.options.RenderOptions`).
    generated_empty : a generated layer's renderer starts empty, for the GPU to make its tiles into
    (:class:`~axialdeform.gl.generated.GeneratedTiles`, the viewer's); otherwise it draws the layer's
    extent, made by numpy when first asked for.
    """

    def __init__(self, ctx, scene, *, culling: bool = True, lod: bool = False, lod_error: float = 1.0,
                 renderer: AxialRenderer | None = None, position_ids: bool = False, generated_empty: bool = False):
        self.ctx = ctx
        self.scene = scene
        self.renderers = []
        self._released = False
        #: a renderer the caller made for the one layer (render_image(renderer=...)): used, never released
        self._borrowed = renderer
        #: False stills every layer's wind (the viewer's V key); True: the scene's
        self.wind_enabled = True
        try:
            if scene.terrain is not None:
                # no back-face culling: a height map is never a closed volume, and finding out
                # (BaseMesh.is_volume sorts every directed edge) costs ~100 bytes a face
                self.renderers.append((AxialRenderer(ctx, scene.terrain, TERRAIN_INSTANCE, options=RenderOptions(cull_back_faces=False)),
                                       scene.terrain_color, False))
            for layer in scene.layers:
                generated = getattr(layer, "generate", None) is not None
                params = layer.empty() if generated and generated_empty else layer.params
                r = renderer if renderer is not None and len(scene.layers) == 1 else AxialRenderer(
                    ctx, layer.mesh, params, RenderOptions(culling=culling, lod=lod, lod_error=lod_error, parts=layer.parts,
                                                           position_ids=position_ids or getattr(layer, "generate", None) is not None))
                self.renderers.append((r, layer.color, layer.wind))
        except BaseException:
            self.release()
            raise

    def layer(self, name: str) -> AxialRenderer:
        """The renderer of the layer called ``name`` (e.g. to ``update_params`` it each frame)."""
        start = 1 if self.scene.terrain is not None else 0
        for layer, (renderer, _, _) in zip(self.scene.layers, self.renderers[start:]):
            if layer.name == name:
                return renderer

        raise SceneError(f"layer: expected one of {', '.join(x.name for x in self.scene.layers)}, found {name!r}")

    def layers(self) -> list:
        """``[(layer, renderer), ...]`` of every layer, in the scene's order."""
        start = 1 if self.scene.terrain is not None else 0
        return [(layer, renderer) for layer, (renderer, _, _) in zip(self.scene.layers, self.renderers[start:])]

    def prepare(self, time: float | None = None) -> None:
        """Set every renderer's up, colour, wind and (unless None) clock from
        the scene: before :meth:`render_shadow` and :meth:`render`."""
        up = UP_VECTORS[self.scene.up]
        for renderer, color, sways in self.renderers:
            renderer.up = up
            if color is not None:
                renderer.color = tuple(color)
            if renderer is not self._borrowed or sways:
                renderer.wind = self.scene.wind if sways and self.wind_enabled else None
            if time is not None:
                renderer.time = float(time)

    def render_shadow(self, shadow) -> None:
        """Every layer and the terrain into ``shadow`` (one map, cleared once)."""
        for k, (renderer, _, _) in enumerate(self.renderers):
            renderer.render_shadow(shadow, clear=k == 0)

    def render(self, view, projection, mode: str = "solid", *, time: float | None = 0.0, look=None,
               shadow=None) -> None:
        """Draw everything into the bound framebuffer; ``time`` drives the wind of layers
        with ``wind = true`` (while :attr:`wind_enabled`; None: keep each renderer's
        clock); ``look`` (default: the scene file's, :attr:`Scene.look`) gives
        the light; ``shadow`` a drawn :class:`ShadowMap` (:meth:`render_shadow`)."""
        look = self.scene.look.replace(hidden_line=False) if look is None else look
        self.prepare(time)
        for renderer, _, _ in self.renderers:
            renderer.render(view, projection, mode, look=look, shadow=shadow)

    def release(self) -> None:
        """Free every renderer; safe to call twice."""
        for renderer, _, _ in self.renderers:
            if renderer is not self._borrowed:
                renderer.release()
        self.renderers = []
        self._released = True

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

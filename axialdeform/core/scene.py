"""Scene files: several layers (base mesh + parameters or a scatter recipe),
a terrain, camera, light and wind, in one TOML file (``tomllib``; ``tomli``
on Python 3.10).

::

    up = "y"                       # world up axis (default "y")
    background = [0.80, 0.87, 0.95]  # the clear colour, sRGB (default: axialdeform.Look's)
    include = ["common.toml"]      # optional: layers of other scene files (paths relative to this file)

    [terrain]                      # optional: what scatter recipes place on, drawn as a mesh
    heightmap = "terrain.png"      # or: mesh = "terrain.obj"
    height_scale = 6.0             # heightmap only
    extent = [40.0, 30.0]          # heightmap only: W or [W, D]
    color = [0.35, 0.42, 0.25]

    [camera]                       # optional; default: frame everything
    elevation = 30.0
    azimuth = 20.0
    fov = 35.0
    eye = [0, 20, 40]              # with target: an explicit camera
    target = [0, 0, 0]

    [light]                        # axialdeform.Look's light (every key optional)
    direction = [0.35, 0.85, 0.4]
    ambient = 0.35
    color = [1.0, 0.96, 0.88]      # the sun (linear RGB)
    sky = [0.80, 0.88, 1.05]       # the hemisphere ambient from above ...
    ground = [0.50, 0.44, 0.38]    # ... and bounced from below

    [wind]                         # axialdeform.core.wind.Wind; layers with wind = true sway in it
    direction = [1, 0, 0]
    strength = 0.15

    [[layer]]
    name = "stones"
    mesh = "stone"                 # a bundled name or a mesh file
    color = [0.46, 0.44, 0.41]
    params = "stones.adp"          # either a parameter file ...

    [[layer]]
    name = "grass"
    mesh = "grass.obj"
    wind = true
    [layer.scatter]                # ... or a scatter recipe on the terrain (keys as axialdeform.scatter)
    count = 2000
    min_distance = 0.3
    density = "grass.png"
    align_to_normal = 0.3
    anchor = "bottom"
    scale = [0.7, 1.3]
    bend = 0.1
    seed = 1
    lift = [0.0, 0.0]              # extra height along up, random in [min, max] (e.g. leaves in the air)

Every path is relative to the file that names it.  An unknown key, a wrong
type, a missing file or a cycle of includes raises :class:`SceneError`
naming the file, the line and the key.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import ClassVar

import numpy as np

from .brush import fold, mask_path
from .camera import CameraSpec
from .errors import ArgumentError, SceneError
from .generate import GroundMaps, check_extent, check_extent_slots, check_reach, generate_extent
from .io.mesh import load_mesh, with_axes
from .io.params import read_params
from .io.scene import LayerRecipe, SceneRecipe, parse_scene
from .look import DEFAULT_LOOK, Look
from .mesh import BaseMesh, area_weighted_normals
from .params import as_params, check_drawable
from .scatter import scatter
from .surface import load_density, load_mask, load_surface

__all__ = ['Scene', 'Layer', 'load_scene', 'is_scene_file', 'SCENE_SUFFIXES']

SCENE_SUFFIXES = (".toml",)


def is_scene_file(path) -> bool:
    return isinstance(path, (str, os.PathLike)) and Path(path).suffix.lower() in SCENE_SUFFIXES


@dataclass
class Layer:
    """One layer: ``params`` (n, 16|19) float32 instances of ``mesh``."""

    name: str
    mesh: object
    params: np.ndarray
    color: tuple | None = None
    wind: bool = False
    lift: np.ndarray | None = None  # (n,) float32: height a scatter recipe's ``lift`` added along up
    parts: tuple | None = None  # names of the mesh's parts to draw (None: all)
    generate: object = None  # a generated layer's GenerateRecipe (its params: the extent materialized)


@dataclass
class GeneratedLayer(Layer):
    """A generated layer (``generate``: its recipe, extent and ground maps): ``params``, the instances of its
    extent, are made by numpy the first time they are asked for (``render``, ``export``, ``info``, a user's
    code); the viewer makes the tiles around its camera on the GPU and never asks (:attr:`made` stays False)."""

    make: object = field(default=None, repr=False, compare=False)  # () -> (n, width) float32

    @property
    def params(self) -> np.ndarray:
        if self._records is None:
            self._records = self.make()
        return self._records

    @params.setter
    def params(self, value) -> None:
        self._records = value if isinstance(value, np.ndarray) else None

    @property
    def made(self) -> bool:
        """Whether ``params`` were made (or given)."""
        return self._records is not None

    @property
    def width(self) -> int:
        """Numbers an instance: the recipe's record and 10 a child axis."""
        return self.generate.generate.width + 10 * (self.mesh.axis_count - 1)

    def empty(self) -> np.ndarray:
        """``(0, width)`` float32: what a renderer the GPU fills starts from."""
        return np.zeros((0, self.width), np.float32)


@dataclass
class Scene:
    """What is drawn: layers of instances, a terrain, and the scene's camera,
    light and wind -- the one front end of every picture
    (:func:`axialdeform.render_image`, the viewer, ``axialdeform web``, the
    notebook widget and the command line all take a scene).

    Make one with :meth:`single` (one mesh and its instances) or
    :meth:`load` (a scene file, several layers).

    Attributes
    ----------
    path : Path or None
        The scene file (None for :meth:`single`).
    up : {"x", "y", "z"}
    layers : list of Layer
        ``Layer(name, mesh, params, color, wind, lift, parts)``.
    terrain : BaseMesh or None
        Drawn as one undeformed instance of itself.
    camera : CameraSpec
        The file's ``[camera]``: ``elevation``, ``azimuth``, ``fov`` or ``eye`` + ``target``
        (default: frame everything from 35 degrees up and around).
    look : Look
        How it looks: the file's ``[light]`` and ``background`` (default :data:`DEFAULT_LOOK`).
    wind : Wind or None
        What layers with ``wind = True`` sway in.
    terrain_color : (float, float, float)
        The terrain's linear RGB colour.
    sources : list of Path
        Every file the scene was read from (the scene file, includes, meshes, parameters, images):
        what an output must never replace.
    """

    #: the class of the layers (what a scene file's reader makes)
    layer_type: ClassVar[type] = Layer

    path: Path | None
    up: str = "y"
    layers: list = field(default_factory=list)
    terrain: object = None
    terrain_color: tuple = (0.36, 0.40, 0.30)
    camera: CameraSpec = field(default_factory=CameraSpec)
    look: Look = DEFAULT_LOOK
    wind: object = None
    #: every file the scene was read from (the scene file, includes, meshes, parameters, images):
    #: what an output must never replace
    sources: list = field(default_factory=list)

    def __post_init__(self):
        if isinstance(self.camera, dict):  # a scene file's [camera] table as given
            self.camera = CameraSpec(**self.camera)
        if not isinstance(self.camera, CameraSpec):
            raise ArgumentError(f"camera: expected an axialdeform.core.CameraSpec, found {type(self.camera).__name__}")
        if not isinstance(self.look, Look):
            raise ArgumentError(f"look: expected an axialdeform.Look, found {type(self.look).__name__}")

    @property
    def count(self) -> int:
        return sum(len(layer.params) for layer in self.layers)

    @property
    def background(self) -> tuple:
        """The clear colour (sRGB): :attr:`look`'s."""
        return self.look.background

    @classmethod
    def single(cls, mesh, params, *, up: str = "y", wind=None, color=None, parts=None,
               name: str | None = None) -> Scene:
        """A scene of one layer: ``params`` ((n, 16|19) float32) instances of ``mesh``.

        Parameters
        ----------
        mesh : BaseMesh
        params : (n, 16) or (n, 19) float32
        up : {"x", "y", "z"}
            World up.
        wind : Wind, optional
            The layer sways in it.
        color : (3,) float, optional
            Base colour (linear RGB); default: the mesh's.
        parts : sequence of str, optional
            The mesh's parts to draw.
        name : str, optional
            The layer's name (default: the mesh's).
        """

        if up not in ("x", "y", "z"):
            raise SceneError(f"up: expected one of x, y, z, found {up!r}")
        parts = None if parts is None else tuple([parts] if isinstance(parts, str) else parts)
        layer = Layer(str(name or getattr(mesh, "name", "mesh")), mesh,
                      as_params(params, axes=getattr(mesh, "axis_count", 1)),
                      color=None if color is None else tuple(color), wind=wind is not None, parts=parts)
        return cls(path=None, up=up, layers=[layer], wind=wind)

    @classmethod
    def of(cls, scene, params=None, *, up: str = "y", wind=None, parts=None) -> Scene:
        """THE check of what a picture, the viewer or the widget was given: a :class:`Scene` as it
        is; a scene file's path (with no ``params``) read by :meth:`load`; a mesh (a BaseMesh, a
        mesh file or a bundled name) with its ``params`` as :meth:`single` (``up``, ``wind``,
        ``parts``).  Anything else is an :class:`ArgumentError` saying what was expected."""
        if isinstance(scene, Scene):
            if params is not None:
                raise ArgumentError("params: a Scene carries its own instances; expected no params beside it")
            return scene
        if params is None:
            if is_scene_file(scene):
                return cls.load(scene)
            raise ArgumentError("params: expected the instances ((n, 16) float32) beside a mesh, or a Scene")
        mesh = scene if isinstance(scene, BaseMesh) else load_mesh(scene)
        return cls.single(mesh, params, up=up, wind=wind, parts=parts)

    @property
    def ground_height(self) -> float | None:
        """Where the ground is along up when the scene says so: 0 when every layer is generated (their
        instances stand on it, docs/generate.md); None: the ground plane is fitted under the instances."""
        return 0.0 if self.terrain is None and self.layers and all(getattr(x, "generate", None) is not None
                                                                   for x in self.layers) else None

    @classmethod
    def load(cls, path: str | os.PathLike, *, scale_counts: float = 1.0) -> Scene:
        """The scene file at ``path`` (TOML, see :mod:`axialdeform.core.scene`); errors are
        :class:`SceneError` naming the file, the line and the key.
        ``scale_counts`` multiplies every scatter recipe's ``count`` (0.1: a quick preview)."""
        return load_scene(path, scale_counts=scale_counts)


def load_scene(path: str | os.PathLike, *, scale_counts: float = 1.0) -> Scene:
    """Read, check and resolve a scene file (:meth:`Scene.load`): the file parsed
    (:func:`axialdeform.core.io.scene.parse_scene`), then its meshes loaded, its
    parameters read or scattered.

    scale_counts : multiply every scatter recipe's ``count`` (e.g. 0.1 for a quick preview).
    """

    return build_scene(parse_scene(path), scale_counts=scale_counts)


def build_scene(recipe: SceneRecipe, scene_type: type = Scene, *, scale_counts: float = 1.0) -> Scene:
    """A :class:`Scene` from a parsed scene file: the terrain's surface and mesh made, each layer's
    mesh loaded (its axis frame, its axes), its instances read or scattered.  What fails is a
    :class:`SceneError` naming the file, line and key of what asked for it."""
    scene = scene_type(path=recipe.path, up=recipe.up, camera=recipe.camera, look=recipe.look or DEFAULT_LOOK,
                       wind=recipe.wind)
    if recipe.terrain_color is not None:
        scene.terrain_color = recipe.terrain_color
    surface = None
    if recipe.terrain is not None:
        t = recipe.terrain
        with t.src.wrap(t.kind, "terrain", 0):
            surface = load_surface(t.file, up=scene.up, height_scale=t.height_scale, extent=t.extent, resample=t.resample)
        # the drawing copy: float32 positions and normals; the uint32 faces are the surface's own (shared); a
        # height map's wireframe edges are the grid's (made when drawn, without a search)
        v, f = surface.vertices, surface.faces
        scene.terrain = BaseMesh(v, area_weighted_normals(v, f), f, name=str(t.file), grid=surface.grid)
    for layer in recipe.layers:
        scene.layers.append(_build_layer(layer, scene, surface, scale_counts))
    # every file the scene read: the scene files, meshes and what they name, parameters, images
    masks = [lay.generate.mask for lay in scene.layers if getattr(lay, "generate", None) is not None and lay.generate.mask]
    scene.sources = list(dict.fromkeys([*recipe.sources, *(s for layer in scene.layers for s in layer.mesh.sources), *masks]))
    return scene


def _build_layer(recipe: LayerRecipe, scene: Scene, surface, scale_counts: float) -> Layer:
    src, nth = recipe.src, recipe.nth
    with src.wrap("mesh", "layer", nth):
        mesh = load_mesh(recipe.mesh)
    if recipe.parts is not None:
        with src.wrap("parts", "layer", nth):
            mesh = mesh.with_parts(recipe.parts)
    with src.wrap("axis", "layer", nth):
        mesh = mesh.with_axis(recipe.frame)
    if recipe.axes is not None:
        with src.wrap("axes", "layer", nth):
            mesh = with_axes(mesh, recipe.axes, recipe.frame)
    lift = None
    if recipe.params is not None:
        with src.wrap("params", "layer", nth):
            params = read_params(recipe.params, mesh)
    elif recipe.generate is not None:
        gen = recipe.generate
        if scene.terrain is not None and scene.terrain.grid is None:
            raise src.error("a generated layer stands on a height-map terrain or on the flat ground y = 0; this "
                            "scene's terrain is a mesh (expected [terrain] heightmap = ..., or no terrain)",
                            "generate", "layer", nth)
        if gen.generate.needs_heights and scene.terrain is None:
            raise src.error("altitude and slope bands need the scene's height-map terrain ([terrain] heightmap)",
                            "altitude" if gen.generate.altitude is not None else "slope", "layer", nth)
        with src.wrap("generate", "layer", nth):
            if gen.extent is None:  # no extent on a height map: the layer covers the terrain
                g = np.asarray(scene.terrain.positions, np.float64)
                gen = replace(gen, extent=check_extent(gen.generate, (g[:, 0].min(), g[:, 2].min(), g[:, 0].max(), g[:, 2].max())))
            density = load_density(gen.density) if gen.density is not None else None
            painted = mask_path(scene.path, recipe.name) if scene.path is not None else None
            if painted is not None and painted.is_file():  # the brush's mask, read again (core/brush.py)
                density = fold(density, load_mask(painted))
                gen = replace(gen, mask=painted)
            gen = replace(gen, maps=GroundMaps.of(scene.terrain, density, gen.extent))
            check_reach(gen.generate, gen.reach, mesh.axis_count)  # a tree's slots hold every axis: bounded before any is made
            check_extent_slots(gen.generate, gen.extent, mesh.axis_count)

        def make(gen=gen, mesh=mesh):  # the extent's instances, made when first asked for (GeneratedLayer)
            with src.wrap("generate", "layer", nth):
                made = generate_extent(gen.generate, mesh, gen.extent, gen.maps)
                check_drawable(made, "the generated instances")  # what a parameter file is held to
            return made

        return GeneratedLayer(name=recipe.name, mesh=mesh, params=None, color=recipe.color, wind=recipe.wind,
                              generate=gen, make=make)
    else:
        params, lift = _scatter(recipe, mesh, scene, surface, scale_counts)
    return scene.layer_type(name=recipe.name, mesh=mesh, params=params, color=recipe.color, wind=recipe.wind,
                            lift=lift, generate=recipe.generate)


def _scatter(recipe: LayerRecipe, mesh, scene: Scene, surface, scale_counts: float):
    """A scatter recipe's instances (and the heights its ``lift`` added, or None)."""
    src, nth, sc = recipe.src, recipe.nth, recipe.scatter
    count = max(1, int(round(sc.count * scale_counts))) if sc.count else 0
    placement = replace(sc.placement, up=scene.up)
    if placement.min_distance and scale_counts < 1:  # a preview keeps the look: fewer, further apart
        placement = replace(placement, min_distance=placement.min_distance / math.sqrt(scale_counts))
    if sc.surface is not None:
        with src.wrap("surface", "layer", nth):
            surface = load_surface(sc.surface, up=scene.up)
    with src.wrap("scatter", "layer", nth):
        params = scatter(surface, mesh, count, sc.variation, placement, seed=sc.seed, allow_fewer=sc.allow_fewer)
    lo, hi = sc.lift
    if not (lo or hi):
        return params, None
    rng = np.random.Generator(np.random.PCG64(int(sc.seed) + 7919))
    up_i = "xyz".index(scene.up)
    params = params.copy()
    added = (lo + (hi - lo) * rng.random(len(params))).astype(np.float32)
    params[:, 10 + up_i] += added
    return params, added



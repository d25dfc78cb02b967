"""The same scene in a browser: a WebGL 2 page (three.js) that bends every
instance in its vertex shader from the package's own GLSL.

``build_scene`` (one mesh and its parameters) and ``build_scene_file`` (a
scene file: every layer and the terrain) gather what a page needs: per layer
the base mesh as GLB (with its parts and materials) and the parameters in the
binary ``.adp`` form (quantized by default), and a config with the layers,
the camera, background, light and wind of ``axialdeform render`` for the same
canvas size and the shaders, assembled at export time from ``glsl/`` by
:func:`axialdeform.gl.shaders.assemble` and moved to GLSL ES 3.00 (version
line and precision only: :func:`to_glsl_es`).  ``write_folder`` writes
``index.html`` + files for a static server; ``write_single_file`` ONE ``.html``
with everything inlined (base64), which works opened from disk.

The page's JavaScript (``app.js``) verifies the file's CRC-32 and compares
the base mesh's fingerprint: the SHA-256 of the GLB's positions and triangles,
computed in the browser with WebCrypto (available on ``file://``,
``http://127.0.0.1`` and ``https://``), else the fingerprint taken at export.

This is an application layer: ``core/`` and ``gl/`` never import it.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..core.bounds import instance_bounds
from ..core.brush import mask_path
from ..core.errors import AxialDeformError
from ..core.generate import children_table, generate_tiles, recipe_json, recipe_uniforms, tiles_around
from ..core.generate_ground import density_area
from ..core.io.gltf import encode_base_mesh
from ..core.io.mesh import mesh_source_path
from ..core.io.params import encode_binary
from ..core.look import DEFAULT_LOOK
from ..core.material import default_color
from ..core.options import RenderOptions, warn_field_keywords
from ..core.params import as_params
from ..core.record import WIDTHS, level_of, tree_shape
from ..core.scene import Scene
from ..core.surface import load_density, load_mask
from ..core.wind import SECOND_HARMONIC
from ..gl.material import ALPHA_MODE_INDEX
from ..gl.renderer import MODE_INDEX, MODES, unit_vector
from ..gl.shaders import GLSL_VERSION, assemble
from .files import (
    WebScene,
    check_page_outputs,
    embedded_file,
    page_files,
    scene_bytes,
    single_file_html,
    write_folder,
    write_page,
    write_single_file,
)
from .serve import make_server
from .sources import (
    MESH_FILE,
    MODULE_DIR,
    MODULE_FILES,
    PARAMS_FILE,
    THREE_VERSION,
    VENDOR_FILES,
    module_source,
    page_source,
    three_version,
    vendor_file,
)

__all__ = [
    "THREE_VERSION", "WebScene", "PageOptions", "build_scene", "build_scene_file", "page_shaders", "shader_key", "to_glsl_es",
    "write_folder", "single_file_html", "make_server", "page_files", "scene_bytes", "embedded_file", "write_single_file",
    "write_page", "vendor_file", "page_source", "module_source", "check_page_outputs", "MODULE_DIR",
    "MODULE_FILES", "VENDOR_FILES", "ground_plane", "fit_ground_and_shadow",
]

GLSL_ES_HEADER = "#version 300 es\nprecision highp float;\nprecision highp int;\nprecision highp sampler2DShadow;"


def to_glsl_es(source: str) -> str:
    """An assembled GLSL 3.30 core stage as GLSL ES 3.00 (WebGL 2): only the
    version line changes, and default precisions follow it; every other
    line, every ``#line``, stays as assembled."""

    first, _, rest = source.partition("\n")
    if first.strip() != GLSL_VERSION:
        raise AxialDeformError(f"shader: expected an assembled source starting with {GLSL_VERSION!r}, found {first!r}")
    return GLSL_ES_HEADER + "\n" + rest


#: the suffix of a shader build per record level and its defines: ``_extended``
#: 19-number instances, ``_tinted`` 22 (core/record.py)
LEVEL_VARIANTS = (("", {}), ("_extended", {"AXIAL_EXTENDED": 1}), ("_tinted", {"AXIAL_EXTENDED": 1, "AXIAL_TINT": 1}))
#: the page's shader builds: key -> defines (``_extended`` / ``_tinted``: a
#: record level; ``_material``: a mesh with UVs, colours, parts or materials)
#: (AXIAL_THREE: the instances are the npm module's AxialInstancedMesh, whose attributes are float32
#: -- a quantized file is decoded by its parser -- and whose rigid part is instanceMatrix)
#: (AXIAL_WIND: the page's wind is a uniform switch, ``axialWindStrength`` 0 when still)
SHADER_VARIANTS = {f"float{suffix}": {"AXIAL_THREE": 1, "AXIAL_WIND": 1, **defines} for suffix, defines in LEVEL_VARIANTS}
SHADER_VARIANTS.update({f"{k}_material": {**v, "AXIAL_MATERIAL": 1} for k, v in list(SHADER_VARIANTS.items())})
#: ``_framed``: a mesh with a chosen axis frame (``u_frame`` instead of ``u_axis``)
SHADER_VARIANTS.update({f"{k}_framed": {**v, "AXIAL_FRAME": 1} for k, v in list(SHADER_VARIANTS.items())})


def page_shaders(keys=None) -> dict:
    """The page's shaders, assembled from ``glsl/scene.vert`` / ``scene.frag``
    (which include ``axial.glsl``, ``wind.glsl`` and ``lighting.glsl``) with
    ``AXIAL_THREE`` (the instances are an AxialInstancedMesh of the npm module):
    ``{"float": {"vertex", "fragment"}, "float_extended": ..., "float_tinted": ...}``
    and the same three with ``_material`` (``AXIAL_MATERIAL``: textures, vertex
    colours, alpha modes), and each of those with ``_framed`` (``AXIAL_FRAME``: a
    chosen axis frame); ``keys``: only those builds, and ``"ground"`` among them: render's ground plane
    (``glsl/ground.vert`` / ``ground.frag``)."""

    out = {variant: {stage: to_glsl_es(assemble(name, defines).source)
                     for stage, name in (("vertex", "scene.vert"), ("fragment", "scene.frag"))}
           for variant, defines in SHADER_VARIANTS.items() if keys is None or variant in keys}
    if keys is not None and "ground" in keys:
        out["ground"] = {stage: to_glsl_es(assemble(name).source) for stage, name in (("vertex", "ground.vert"),
                                                                                       ("fragment", "ground.frag"))}
    return out


def shader_key(quantize: bool, fields: int, material: bool, framed: bool = False) -> str:
    """The :data:`SHADER_VARIANTS` key of a layer (``quantize`` shrinks the file only: the page's
    AxialInstancedMesh holds float32 attributes either way)."""
    return "float" + LEVEL_VARIANTS[tree_shape(fields)[1]][0] + (
        "_material" if material else "") + ("_framed" if framed else "")


def _parts(mesh, color) -> list:
    """The parts as the page draws them (the GLB's primitives, in order):
    triangle range and material, as :class:`axialdeform.gl.material.GpuMaterials`
    binds them (a default material takes the layer's colour and is lit on both sides)."""

    out = []
    for part in mesh.parts:
        if part.count == 0:  # no primitive in the GLB either
            continue
        m = part.material
        base = [float(c) for c in m.base_color]
        if m.is_default:
            base[:3] = [float(c) for c in color]
        out.append({"name": str(part.name), "start": int(part.start), "count": int(part.count),
                    "alpha_mode": ALPHA_MODE_INDEX[m.alpha_mode], "alpha_cutoff": float(m.alpha_cutoff),
                    "double_sided": bool(m.double_sided), "lit_two_sided": bool(m.double_sided or m.is_default),
                    "base_color": base, "texture": m.texture is not None and mesh.uvs is not None,
                    "normal_map": (m.normal_texture is not None and mesh.uvs is not None
                                   and mesh.tangents is not None)})
    return out


def _generated(recipe, mesh, files: dict, name: str) -> dict:
    """A generated layer's recipe as the page takes it: the recipe (tiles, reach), generate.glsl's numbers
    as the desktop generator gets them (:func:`~axialdeform.core.generate.recipe_uniforms`) and the ground
    maps' pixels and a tree's child-axis table (float32, little-endian, row after row: ``files``), the
    same whatever the count."""
    g = recipe.generate
    maps = recipe.maps
    grids = {}
    tree = getattr(mesh, "tree", None)  # several axes: the child axes' amplitudes and joint projections
    for key, grid in (("heights", getattr(maps, "heights", None)), ("density", getattr(maps, "density", None)),
                      ("children", None if tree is None else children_table(g, mesh))):
        if grid is not None:
            file = f"layer-{name}-{key}.f32"
            files[file] = np.ascontiguousarray(grid, "<f4").tobytes()
            grids[key] = {"file": file, "cols": int(grid.shape[1]), "rows": int(grid.shape[0])}
    return {"recipe": recipe_json(g, recipe.reach),
            "uniforms": recipe_uniforms(g, mesh, maps), "maps": grids, "width": int(g.width)}


def _brush(recipe, scene, name: str, files: dict) -> dict:
    """What the page's brush needs of a generated layer (core/brush.py, the npm module's AxialBrush): the
    ground its density map covers as the library places it, whether the map repeats, the layer's own density
    map and its saved mask (float32 files, before they were folded into the map the page draws), and the name
    of the mask's file beside the scene file."""
    area, wrap = density_area(scene.terrain, recipe.extent)
    named = mask_path(scene.path, name).name if scene.path is not None else f"{name}-mask.png"
    out = {"area": [float(a) for a in area], "wrap": bool(wrap), "file": named}
    for key, grid in (("density", None if recipe.density is None else load_density(recipe.density)),
                      ("mask", None if recipe.mask is None else load_mask(recipe.mask))):
        if grid is not None:
            file = f"layer-{name}-brush-{key}.f32"
            files[file] = np.ascontiguousarray(grid, "<f4").tobytes()
            out[key] = {"file": file, "cols": int(grid.shape[1]), "rows": int(grid.shape[0])}
    return out


def _layer(name: str, mesh, params, *, files: dict, glb_file: str, params_file: str | None, quantize: bool,
           color=None, wind: bool = False, adp: bytes | None = None, terrain: bool = False, generate=None) -> dict:
    """One layer's config entry; its GLB and ``.adp`` go into ``files`` (a generated layer, ``generate``
    its :class:`GenerateRecipe`: the GLB and the recipe only -- the page makes the instances)."""

    axis = mesh.axis
    if color is None:
        color = default_color(mesh)
    material = bool(mesh.has_appearance)
    files[glb_file] = encode_base_mesh(mesh)
    if generate is None:
        if adp is None:
            adp = encode_binary(params, axis=mesh, mesh_fingerprint=mesh.fingerprint, quantize=quantize)  # its axis or tree
        files[params_file] = bytes(adp)
    width = params.shape[1] if generate is None else generate.generate.width
    return {
        "name": name,
        "terrain": bool(terrain),  # drawn, not counted among the instances
        "instances": int(len(params)),
        # axis -1 (the adp header's 3) and "frame" (rows e_a, e_u, e_v): a chosen axis frame, u_frame
        "mesh": {"file": glb_file, "name": Path(str(mesh.name)).name, "axis": int(axis.index), "lo": float(axis.lo),
                 "length": float(axis.length), "fingerprint": mesh.fingerprint.hex(),
                 # the axis line across the axis (twist and taper turn about it): u_center
                 "center": list(axis.line),
                 **({"frame": [list(row) for row in axis.frame], "frame_digest": axis.frame_digest.hex()}
                    if axis.framed else {}),
                 # several axes (AXIAL_AXES): the tree's frames, lo, L and parents; its digest as the adp's
                 **({"axes": mesh.tree.to_json(), "frame_digest": mesh.tree.digest.hex()}
                    if mesh.tree is not None else {}),
                 "vertices": int(mesh.vertex_count)},
        **({"params_file": params_file} if generate is None else {"generate": _generated(generate, mesh, files, name)}),
        "shader": shader_key(quantize, width, material, axis.framed),
        "material": material,
        "color": [float(x) for x in color],
        "wind": bool(wind),
        "cull_back_faces": bool(mesh.is_volume),
        "parts": _parts(mesh, color),
    }


def _ground_and_shadow(look, up: str, spheres, cam, aspect: float, height: float | None = None):
    """``(ground, shadow, camera)`` of a page over ``spheres``: the ground plane (:func:`ground_plane`), the key
    light's shadow map (:func:`_shadow`) and the camera with its near and far planes widened to hold the ground, as
    render's (``cam`` as it is where the look draws no ground)."""
    from ..core.camera import UP_VECTORS

    ground = ground_plane(look, up, spheres, height)
    if ground is not None:
        cam = cam.enclosing_square(np.asarray(ground["center"]), UP_VECTORS[up], ground["radius"], aspect)
    return ground, _shadow(look, spheres, ground), cam


def ground_plane(look, up: str, spheres, height: float | None = None) -> dict | None:
    """The page's ground plane: render's under a scene without a terrain (:class:`~axialdeform.gl.ground.GroundPlane`:
    fitted under ``spheres``, ``[(centers (n, 3), radii (n,)), ...]``, drawn
    :attr:`~axialdeform.gl.ground.GroundPlane.EXTENT` times as wide, fading into the background), its uniforms as
    ``glsl/ground.vert`` and ``ground.frag`` take them; None where the look draws no ground or nothing stands on it."""
    from ..core.axis import AXIS_NAMES
    from ..core.bounds import ground_square, stack_spheres
    from ..gl.ground import GROUND_COLOR, GroundPlane

    centers, radii = stack_spheres(spheres)
    if not look.draws_ground or not len(centers):
        return None
    a = AXIS_NAMES.index(up)
    center, radius = ground_square(centers, radii, a, height=height)
    axis_u, axis_v = (np.eye(3)[i] for i in range(3) if i != a)
    return {"center": center.tolist(), "radius": float(GroundPlane.EXTENT * radius), "axis_u": axis_u.tolist(),
            "axis_v": axis_v.tolist(), "color": list(GROUND_COLOR), "cell": 0.0}


def fit_ground_and_shadow(mesh, params, look=None, up: str = "y") -> tuple[dict | None, dict | None]:
    """``(ground, shadow)`` of a page of ``mesh`` x ``params``, as :func:`build_scene` puts them in its config
    (:func:`ground_plane`, and the key light's shadow map over the instances and the ground's centre part): the
    widget fits them again when its instances change."""
    spheres = [instance_bounds(mesh, as_params(params, axes=mesh.axis_count))]
    look = look or DEFAULT_LOOK
    ground = ground_plane(look, up, spheres)
    return ground, _shadow(look, spheres, ground)


def _shadow(look, spheres, ground) -> dict | None:
    """The page's shadow map: render's (:class:`~axialdeform.gl.shadow.ShadowMap`, fitted by
    :func:`~axialdeform.core.bounds.light_box` over ``spheres``, ``[(centers, radii), ...]``: the layers' and a
    terrain's, and the ground plane's centre part), its light matrices in GLSL's column order; None where the look
    draws none or there is nothing to draw.  Without a ground plane or a terrain the instances still shadow each
    other, as render's do."""
    from ..core.bounds import light_box, stack_spheres
    from ..gl.ground import GroundPlane
    from ..gl.shadow import SHADOW_SIZE

    centers, radii = stack_spheres(spheres)
    if not look.draws_shadow or not len(centers):
        return None
    near = np.zeros((0, 4)) if ground is None else np.array([[*ground["center"], 0.5 * ground["radius"] / GroundPlane.EXTENT]])
    view, projection, offset = light_box(np.vstack([np.hstack([centers, radii[:, None]]), near]), look.light_dir, SHADOW_SIZE)
    matrix = (np.asarray(view, np.float64) @ np.asarray(projection, np.float64)).astype(np.float32)
    flat = lambda m: [float(x) for x in np.asarray(m, np.float32).reshape(-1)]  # noqa: E731 - pyrr's rows: GLSL's columns
    return {"view": flat(view), "projection": flat(projection), "matrix": flat(matrix), "offset": float(offset),
            "size": SHADOW_SIZE}


def _check_view(size, up: str, mode: str) -> tuple:
    from ..core.camera import UP_VECTORS

    if mode not in MODES:
        raise AxialDeformError(f"mode: the page draws {', '.join(MODES)}, found {mode!r}")
    if up not in UP_VECTORS:
        raise AxialDeformError(f"up: expected x, y or z, found {up!r}")
    w, h = (int(x) for x in size)
    if not (0 < w <= 16384 and 0 < h <= 16384):
        raise AxialDeformError(f"size: expected 1..16384 pixels each way, found {w}x{h}")
    return w, h


def _config(*, title, layers, size, fixed_size, mode, cam, look, up, wind, shaders,
            time=None, ground=None, shadow=None) -> dict:
    from ..core.camera import UP_VECTORS

    return {
        "generator": "axialdeform",
        "title": title,
        "instances": int(sum(layer["instances"] for layer in layers if not layer["terrain"])),
        "size": [int(size[0]), int(size[1])],
        "fixed_size": bool(fixed_size),
        "mode": mode,
        "mode_index": MODE_INDEX[mode],
        "layers": layers,
        "camera": {"eye": cam.eye.tolist(), "target": cam.target.tolist(), "up": cam.up.tolist(),
                   "fovy": cam.fovy, "near": cam.near, "far": cam.far},
        # how it looks: axialdeform.Look, the one home of the defaults (light normalised here)
        "look": {**look.to_json(), "light_dir": [float(x) for x in unit_vector(look.light_dir)]},
        "up": [float(x) for x in unit_vector(UP_VECTORS[up])],
        "wind": _wind_config(wind),
        "time": None if time is None else float(time),  # seconds: the wind's clock frozen there (None: it runs)
        "three": three_version(),
        "shaders": {**shaders, **(page_shaders(["ground"]) if ground is not None else {})},
        # render's ground plane under a scene without a terrain (glsl/ground.vert, ground.frag), or None
        "ground": ground,
        # render's shadow map (the key light's camera over the instances and the ground's centre), or None
        "shadow": shadow,
        # the shader build's suffix for each record width (LEVEL_VARIANTS): the page picks a file's build by it
        "shader_suffix": {str(w): LEVEL_VARIANTS[level_of(w)][0] for w in WIDTHS},
    }


def _wind_config(wind) -> dict | None:
    """The wind's uniforms but the time (the page computes the two cycles,
    ``frac(f T)`` and ``frac(harmonic f T)``, as :meth:`Wind.cycles` does)."""
    if wind is None or wind.strength == 0:
        return None

    return {"strength": float(wind.strength), "direction": [float(x) for x in wind.unit_direction],
            "gustiness": float(wind.gustiness), "frequency": float(wind.frequency),
            "harmonic": float(SECOND_HARMONIC), "wavenumber": float(wind.wavenumber)}


def _time(wind, time):
    if time is None:
        return None

    if wind is None:
        raise AxialDeformError("time: only meaningful with a wind (the wind is the only thing that moves with time)")
    if not math.isfinite(float(time)):
        raise AxialDeformError(f"time: expected a finite number of seconds, found {time!r}")
    return float(time)


def _shaders(layers, all_shaders: bool) -> dict:
    if all_shaders:  # the widget, whose parameters may change: every build of its mesh's kind
        material, framed = layers[0]["material"], "frame" in layers[0]["mesh"]
        return page_shaders([k for k in SHADER_VARIANTS
                             if ("_material" in k) == material and k.endswith("_framed") == framed])
    return page_shaders({layer["shader"] for layer in layers})


@dataclass(frozen=True)
class PageOptions:
    """How a page is made; what it shows is the scene, how it looks a :class:`Look`.

    Attributes
    ----------
    size : (int, int)
        The canvas (width, height): the camera is ``axialdeform render``'s at that size.
    mode : {"solid", "flat", "wireframe"}
        The first drawing mode.
    quantize : bool
        Ship the instances quantized (uint16: half the bytes).
    fixed_size : bool
        Keep the canvas at ``size``; else it fills the window.
    title : str, optional
        The page's title (default: what it shows).
    all_shaders : bool
        Carry every shader build of the mesh's kind (the widget, whose parameters may change).
    """

    size: tuple = (800, 600)
    mode: str = "solid"
    quantize: bool = True
    fixed_size: bool = True
    title: str | None = None
    all_shaders: bool = False


def _page_options(page, options, fields: dict, where: str):
    """``page`` and ``options`` with ``fields`` (of either) applied."""
    page = page or PageOptions()
    own = {k: fields.pop(k) for k in list(fields) if k in PageOptions.__dataclass_fields__}
    warn_field_keywords(where, own, "page", "web.PageOptions", stacklevel=3)
    return replace(page, **own), RenderOptions.of(options, fields, where, ("up", "wind", "time"), stacklevel=3)


def build_scene(mesh, params, page: PageOptions | None = None, *, look=None, options: RenderOptions | None = None,
                adp: bytes | None = None, **fields) -> WebScene:
    """The page's data for ``mesh`` and ``params`` ((n, 16) float32).

    Parameters
    ----------
    mesh : BaseMesh
    params : (n, 16|19|22) float32
    page : PageOptions, optional
        The canvas size, first mode, quantization, title (:class:`PageOptions`).
    look : Look, optional
        Reaches the page as JSON (light, ambient, background, line colour; the page draws no
        ground or shadow); default the default look.
    options : RenderOptions, optional
        ``up``; ``wind`` (:class:`axialdeform.Wind`) sways the instances; ``time`` freezes its
        clock at that many seconds (else it runs; ``?t=`` on the page overrides).
    adp : bytes, optional
        A parameter file written as given instead of encoding ``params`` (tests use it to ship a
        corrupt file).
    **fields
        Deprecated (still working for one release, with a DeprecationWarning): fields of
        :class:`PageOptions` or :class:`RenderOptions` (``size=(640, 480), up="z"``).

    Returns
    -------
    WebScene
        The page's config and files.

    Notes
    -----
    The camera is :func:`axialdeform.gl.scene.scene_camera` of :meth:`Scene.single` for the
    canvas size.  The config carries the shader build for these parameters (16 or 19 numbers,
    float32 or quantized, with or without material); ``all_shaders`` carries the four of the mesh's
    kind.
    """
    from ..gl.scene import scene_camera  # the GL layer (pyrr) only when a page is built

    page, opts = _page_options(page, options, fields, "build_scene")
    up, wind, time, mode = opts.up, opts.wind, opts.time, page.mode
    w, h = _check_view(page.size, up, mode)
    params = as_params(params, axes=mesh.axis_count)
    cam = scene_camera(Scene.single(mesh, params, up=up, wind=wind), w / h)
    look = look or DEFAULT_LOOK
    ground, shadow, cam = _ground_and_shadow(look, up, [instance_bounds(mesh, params)], cam, w / h)
    files: dict = {}
    layer = _layer(str(mesh.name), mesh, params, files=files, glb_file=MESH_FILE, params_file=PARAMS_FILE,
                   quantize=page.quantize, adp=adp, wind=wind is not None)
    config = _config(title=page.title or f"{len(params)} × {mesh.name}", layers=[layer], size=(w, h),
                     fixed_size=page.fixed_size, mode=mode, cam=cam, look=look, up=up, wind=wind,
                     shaders=_shaders([layer], page.all_shaders), time=_time(wind, time), ground=ground, shadow=shadow)
    return WebScene(config, files)


def check_inside(scene) -> None:
    """Refuse a scene whose page would carry a file from outside the scene file's folder (``../`` or an
    absolute path in it, or a link out of it): a page is shared.  The package's bundled meshes are fine."""
    if scene.path is None:
        return
    folder = os.path.realpath(Path(scene.path).parent)
    bundled = os.path.dirname(os.path.realpath(mesh_source_path("stone")))
    for source in scene.sources:
        real = os.path.realpath(source)
        if os.path.commonpath([real, folder]) != folder and os.path.commonpath([real, bundled]) != bundled:
            raise AxialDeformError(f"{scene.path}: names {source}, outside the scene's folder {folder}; a page carries "
                                   "only files from there (--allow-outside to carry it anyway)")


def build_scene_file(scene, page: PageOptions | None = None, *, look=None, options: RenderOptions | None = None,
                     allow_outside: bool = False, **fields) -> WebScene:
    """The page's data for a loaded scene file (:func:`axialdeform.core.scene.load_scene`):
    every layer (its base mesh and parameters: one instanced draw per part),
    the terrain (one undeformed instance of itself, float32), the scene's
    camera (:func:`axialdeform.gl.scene.scene_camera` at the page's ``size``),
    background, light and wind (``options.wind`` replaces the scene's; ``options.time``
    freezes its clock; ``look`` replaces :attr:`Scene.look`), as
    ``axialdeform render SCENE [--time T]`` draws them.  ``page``, ``options`` and ``**fields``
    as :func:`build_scene`'s.  A page is shared: a file the scene names outside its own folder
    (``../``, an absolute path, a link out of it) is refused unless ``allow_outside``."""
    if not allow_outside:
        check_inside(scene)

    from ..gl.scene import (  # the GL layer (pyrr) only when a page is built
        TERRAIN_INSTANCE,
        ground_spheres,
        scene_camera,
    )

    page, opts = _page_options(page, options, fields, "build_scene_file")
    if opts.up != "y":
        raise AxialDeformError(f"up: a scene has its own ({scene.up}); expected no up beside it")
    mode, quantize, time = page.mode, page.quantize, opts.time
    w, h = _check_view(page.size, scene.up, mode)
    wind = scene.wind if opts.wind is None else opts.wind
    files: dict = {}
    layers = []
    if scene.terrain is not None:
        layers.append(_layer("terrain", scene.terrain, TERRAIN_INSTANCE, files=files, glb_file="terrain.glb",
                             params_file="terrain.adp", quantize=False, color=scene.terrain_color, terrain=True))
    generated_layers = []  # (config entry, recipe)
    for item in scene.layers:
        generated = getattr(item, "generate", None)
        if generated is None and len(item.params) == 0:
            continue
        if generated is not None:  # the page makes its instances on the GPU: none made here
            generated_layers.append((len(layers), (generated, item.mesh)))
        params = item.empty() if generated is not None else as_params(item.params, axes=item.mesh.axis_count)
        layers.append(_layer(item.name, item.mesh, params, files=files,
                             glb_file=f"layer-{item.name}.glb",
                             params_file=None if generated is not None else f"layer-{item.name}.adp",
                             quantize=quantize, color=item.color, wind=item.wind and wind is not None,
                             generate=generated))
        if generated is not None:
            layers[-1]["generate"]["brush"] = _brush(generated, scene, item.name, files)
    if not layers:
        raise AxialDeformError(f"{scene.path}: the scene has nothing to draw; expected a terrain or a layer with instances")

    cam = scene_camera(replace(scene, wind=wind), w / h)
    for k, (recipe, mesh) in generated_layers:  # what the page holds at the start: the tiles within reach of the target
        tiles = tiles_around(recipe.generate, float(cam.target[0]), float(cam.target[2]), recipe.reach)
        layers[k]["instances"] = int(len(generate_tiles(recipe.generate, mesh, tiles, recipe.maps)))
    look = look or scene.look
    spheres = ground_spheres(scene)  # each layer's bounds (gl/scene.py: no instance made)
    if scene.terrain is None:  # render's ground plane
        ground, shadow, cam = _ground_and_shadow(look, scene.up, spheres, cam, w / h, scene.ground_height)
    else:  # render's terrain casts and receives them
        ground, shadow = None, _shadow(look, [*spheres, instance_bounds(scene.terrain, TERRAIN_INSTANCE)], None)
    config = _config(title=page.title or Path(scene.path).stem, layers=layers, size=(w, h),
                     fixed_size=page.fixed_size, mode=mode,
                     cam=cam, look=look, up=scene.up, wind=wind,
                     shaders=_shaders(layers, False), time=_time(wind, time), ground=ground, shadow=shadow)
    return WebScene(config, files)

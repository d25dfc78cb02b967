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

import base64
import contextlib
import errno
import functools
import hashlib
import html
import json
import math
import operator
import os
from dataclasses import dataclass, replace
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path

from ..core.errors import AxialDeformError
from ..core.io.atomic import atomic_write_bytes
from ..core.io.gltf import encode_base_mesh
from ..core.io.params import encode_binary
from ..core.io.safeio import check_output_path, read_regular
from ..core.look import DEFAULT_LOOK
from ..core.params import as_params
from ..core.record import WIDTHS, level_of, tree_shape
from ..core.scene import Scene
from ..core.wind import SECOND_HARMONIC
from ..gl.material import ALPHA_MODE_INDEX
from ..gl.renderer import _MODE_INDEX, DEFAULT_COLORS, MODES, _unit
from ..gl.shaders import GLSL_VERSION, assemble

__all__ = [
    "THREE_VERSION", "WebScene", "build_scene", "build_scene_file", "page_shaders", "shader_key", "to_glsl_es",
    "write_folder", "single_file_html", "make_server", "scene_bytes", "embedded_file", "write_single_file",
    "write_page", "vendor_file", "page_source", "module_source",
]

#: the files of the vendored three.js, relative to ``web/vendor/``
VENDOR_FILES = {
    "three": "three.module.min.js",
    "orbit": "addons/controls/OrbitControls.js",
    "gltf": "addons/loaders/GLTFLoader.js",
    "bgu": "addons/utils/BufferGeometryUtils.js",
}
GLSL_ES_HEADER = "#version 300 es\nprecision highp float;\nprecision highp int;"
MESH_FILE = "mesh.glb"
PARAMS_FILE = "params.adp"


def _here():
    return resources.files("axialdeform.web")


def page_source(name: str) -> str:
    """The text of one file of the page code (``app.js``, ``loader.js``, ``page.html``)."""
    return _here().joinpath(name).read_text(encoding="utf-8")


#: the npm module axialdeform-three's files (js/src; the wheel's axialdeform/three), which the page code
#: imports; the folder page keeps them in MODULE_DIR
MODULE_FILES = ("adp.js", "glsl.js", "bend.js", "mesh.js", "gltf.js", "index.js")
MODULE_DIR = "axialdeform-three/"


def module_source(name: str) -> str:
    """The text of one file of the npm module axialdeform-three (``js/src``; the wheel's ``axialdeform/three``)."""
    return resources.files("axialdeform.three").joinpath(name).read_text(encoding="utf-8")


def vendor_file(relative: str) -> bytes:
    """The bytes of one vendored three.js file (``web/vendor/<relative>``)."""
    res = _here().joinpath("vendor", *relative.split("/"))
    if not res.is_file():
        raise AxialDeformError(f"axialdeform/web/vendor/{relative}: missing; run tools/vendor_three.sh")
    return res.read_bytes()


def _three_version() -> str:
    return vendor_file("VERSION").decode().strip()


THREE_VERSION = "0.160.1"  # tools/vendor_three.sh pins it; tests compare with vendor/VERSION


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
SHADER_VARIANTS = {f"float{suffix}": {"AXIAL_THREE": 1, **defines} for suffix, defines in LEVEL_VARIANTS}
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
    chosen axis frame); ``keys``: only those builds."""

    return {variant: {stage: to_glsl_es(assemble(name, defines).source)
                      for stage, name in (("vertex", "scene.vert"), ("fragment", "scene.frag"))}
            for variant, defines in SHADER_VARIANTS.items() if keys is None or variant in keys}


def shader_key(quantize: bool, fields: int, material: bool, framed: bool = False) -> str:
    """The :data:`SHADER_VARIANTS` key of a layer (``quantize`` shrinks the file only: the page's
    AxialInstancedMesh holds float32 attributes either way)."""
    return "float" + LEVEL_VARIANTS[tree_shape(fields)[1]][0] + (
        "_material" if material else "") + ("_framed" if framed else "")


@dataclass
class WebScene:
    """What a page shows: ``config`` (JSON-able dict) and ``files``
    (file name -> bytes: a GLB and an ``.adp`` per layer)."""

    config: dict
    files: dict

    @property
    def count(self) -> int:
        return int(self.config["instances"])

    @property
    def glb(self) -> bytes:
        """The first layer's base mesh (GLB bytes)."""
        return self.files[self.config["layers"][0]["mesh"]["file"]]

    @property
    def adp(self) -> bytes:
        """The first layer's parameter file (``.adp`` bytes)."""
        return self.files[self.config["layers"][0]["params_file"]]


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


def _layer(name: str, mesh, params, *, files: dict, glb_file: str, params_file: str, quantize: bool,
           color=None, wind: bool = False, adp: bytes | None = None, terrain: bool = False) -> dict:
    """One layer's config entry; its GLB and ``.adp`` go into ``files``."""

    axis = mesh.axis
    if color is None:
        color = DEFAULT_COLORS.get(str(mesh.name), (0.46, 0.44, 0.41))
    material = bool(mesh.has_appearance)
    if adp is None:
        adp = encode_binary(params, axis=mesh, mesh_fingerprint=mesh.fingerprint, quantize=quantize)  # its axis or tree
    files[glb_file] = encode_base_mesh(mesh)
    files[params_file] = bytes(adp)
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
        "params_file": params_file,
        "shader": shader_key(quantize, params.shape[1], material, axis.framed),
        "material": material,
        "color": [float(x) for x in color],
        "wind": bool(wind),
        "cull_back_faces": bool(mesh.is_volume),
        "parts": _parts(mesh, color),
    }


def _check_view(size, up: str, mode: str) -> tuple:
    from ..gl.camera import UP_VECTORS

    if mode not in MODES:
        raise AxialDeformError(f"mode: the page draws {', '.join(MODES)}, found {mode!r}")
    if up not in UP_VECTORS:
        raise AxialDeformError(f"up: expected x, y or z, found {up!r}")
    w, h = (int(x) for x in size)
    if not (0 < w <= 16384 and 0 < h <= 16384):
        raise AxialDeformError(f"size: expected 1..16384 pixels each way, found {w}x{h}")
    return w, h


def _config(*, title, layers, size, fixed_size, mode, cam, look, up, wind, shaders,
            time=None) -> dict:
    from ..gl.camera import UP_VECTORS

    return {
        "generator": "axialdeform",
        "title": title,
        "instances": int(sum(layer["instances"] for layer in layers if not layer["terrain"])),
        "size": [int(size[0]), int(size[1])],
        "fixed_size": bool(fixed_size),
        "mode": mode,
        "mode_index": _MODE_INDEX[mode],
        "layers": layers,
        "camera": {"eye": cam.eye.tolist(), "target": cam.target.tolist(), "up": cam.up.tolist(),
                   "fovy": cam.fovy, "near": cam.near, "far": cam.far},
        # how it looks: axialdeform.Look, the one home of the defaults (light normalised here)
        "look": {**look.to_json(), "light_dir": [float(x) for x in _unit(look.light_dir)]},
        "up": [float(x) for x in _unit(UP_VECTORS[up])],
        "wind": _wind_config(wind),
        "time": None if time is None else float(time),  # seconds: the wind's clock frozen there (None: it runs)
        "three": _three_version(),
        "shaders": shaders,
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


def build_scene(mesh, params, *, size=(800, 600), up: str = "y", mode: str = "solid", quantize: bool = True,
                title: str | None = None, adp: bytes | None = None, all_shaders: bool = False,
                fixed_size: bool = True, wind=None, time: float | None = None, look=None) -> WebScene:
    """The page's data for ``mesh`` and ``params`` ((n, 16) float32).

    The camera is :func:`axialdeform.gl.scene.scene_camera` of
    :meth:`Scene.single` for the canvas ``size`` (width, height) -- the
    camera of ``axialdeform render`` at that size; ``look`` (an
    :class:`axialdeform.Look`, default the default look) reaches the page as
    JSON (light, ambient, background, line colour; the page draws no ground
    or shadow).  ``fixed_size`` keeps the canvas at ``size``; else it fills the
    window.  ``adp`` (bytes of a parameter file) is written as given instead of
    encoding ``params`` (tests use it to ship a corrupt file).  The config
    carries the shader build for these parameters (16 or 19 numbers, float32
    or quantized, with or without material); ``all_shaders`` carries the four
    of the mesh's kind (the widget, whose parameters may change).  ``wind``
    (:class:`axialdeform.Wind`) sways the instances; ``time`` freezes its
    clock at that many seconds (else it runs; ``?t=`` on the page overrides).
    """
    from ..gl.scene import scene_camera  # the GL layer (pyrr) only when a page is built

    w, h = _check_view(size, up, mode)
    params = as_params(params, axes=mesh.axis_count)
    cam = scene_camera(Scene.single(mesh, params, up=up, wind=wind), w / h)
    files: dict = {}
    layer = _layer(str(mesh.name), mesh, params, files=files, glb_file=MESH_FILE, params_file=PARAMS_FILE,
                   quantize=quantize, adp=adp, wind=wind is not None)
    config = _config(title=title or f"{len(params)} × {mesh.name}", layers=[layer], size=(w, h),
                     fixed_size=fixed_size, mode=mode, cam=cam, look=look or DEFAULT_LOOK, up=up, wind=wind,
                     shaders=_shaders([layer], all_shaders), time=_time(wind, time))
    return WebScene(config, files)


def build_scene_file(scene, *, size=(800, 600), mode: str = "solid", quantize: bool = True,
                     fixed_size: bool = True, wind=None, time: float | None = None, look=None) -> WebScene:
    """The page's data for a loaded scene file (:func:`axialdeform.core.scene.load_scene`):
    every layer (its base mesh and parameters: one instanced draw per part),
    the terrain (one undeformed instance of itself, float32), the scene's
    camera (:func:`axialdeform.gl.scene.scene_camera` at this ``size``),
    background, light and wind (``wind`` replaces the scene's; ``time``
    freezes its clock; ``look`` replaces :attr:`Scene.look`), as
    ``axialdeform render SCENE [--time T]`` draws them."""

    from ..gl.scene import (  # the GL layer (pyrr) only when a page is built
        TERRAIN_INSTANCE,
        scene_camera,
    )

    w, h = _check_view(size, scene.up, mode)
    wind = scene.wind if wind is None else wind
    files: dict = {}
    layers = []
    if scene.terrain is not None:
        layers.append(_layer("terrain", scene.terrain, TERRAIN_INSTANCE, files=files, glb_file="terrain.glb",
                             params_file="terrain.adp", quantize=False, color=scene.terrain_color, terrain=True))
    for item in scene.layers:
        if len(item.params) == 0:
            continue
        layers.append(_layer(item.name, item.mesh, as_params(item.params, axes=item.mesh.axis_count), files=files,
                             glb_file=f"layer-{item.name}.glb", params_file=f"layer-{item.name}.adp",
                             quantize=quantize, color=item.color, wind=item.wind and wind is not None))
    if not layers:
        raise AxialDeformError(f"{scene.path}: the scene has nothing to draw; expected a terrain or a layer with instances")

    cam = scene_camera(replace(scene, wind=wind), w / h)
    config = _config(title=Path(scene.path).stem, layers=layers, size=(w, h), fixed_size=fixed_size, mode=mode,
                     cam=cam, look=look or scene.look, up=scene.up, wind=wind,
                     shaders=_shaders(layers, False), time=_time(wind, time))
    return WebScene(config, files)


def _json_in_html(obj) -> str:
    # inside <script>: no "</" can close the element
    return json.dumps(obj, ensure_ascii=False, separators=(",", ":")).replace("</", "<\\/")


def _page(config: dict, head: str, body_data: str, entry: str) -> str:
    template = page_source("page.html")
    return (template.replace("{{TITLE}}", html.escape(f"axialdeform: {config['title']}"))
            .replace("{{HEAD}}", head).replace("{{DATA}}", body_data).replace("{{ENTRY}}", entry))


_FOLDER_ENTRY = """
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import * as app from './app.js';

async function fetchBytes(name) {
  const r = await fetch(encodeURIComponent(name));
  if (!r.ok) throw new app.SceneError(`${name}: ${r.status} ${r.statusText}`);
  return r.arrayBuffer();
}
async function load() {
  try {
    const config = await (await fetch('scene.json')).json();
    const names = config.layers.flatMap((l) => [l.mesh.file, l.params_file]);
    const files = {};
    await Promise.all(names.map(async (n) => { files[n] = await fetchBytes(n); }));
    return { config, files };
  } catch (err) {
    if (err instanceof app.SceneError) throw err;
    throw new app.SceneError(location.protocol === 'file:'
      ? 'this folder page needs a web server (axialdeform web --serve), or export one .html file'
      : `could not load the scene: ${err.message}`);
  }
}
start(() => load(), { THREE, OrbitControls, GLTFLoader }, app);
"""

_SINGLE_ENTRY = """
import { loadModules } from '{{LOADER}}';
const text = (id) => document.getElementById(id).textContent;
const b64text = (id) => new TextDecoder().decode(Uint8Array.from(atob(text(id).trim()), (c) => c.charCodeAt(0)));
const { lib, app } = await loadModules({ three: b64text('axd-three'), orbit: b64text('axd-orbit'),
  gltf: b64text('axd-gltf'), bgu: b64text('axd-bgu'), app: b64text('axd-app'),
  module: Object.fromEntries([...document.querySelectorAll('script[id^="axd-module-"]')]
    .map((e) => [e.id.slice('axd-module-'.length) + '.js', b64text(e.id)])) });
const files = {};
for (const e of document.querySelectorAll('script[data-file]')) files[e.dataset.file] = app.fromBase64(e.textContent);
start(async () => ({ config: JSON.parse(text('axd-config')), files }), lib, app);
"""

# shared by both entries: mount, then tell tools the first frame is drawn
_START = """
function start(load, lib, app) {
  const root = document.getElementById('axd-page');
  load().then((scene) => {
    document.title = `axialdeform: ${scene.config.title}`;
    const view = app.mount(root, lib, scene, app.pageOptions(location.search));
    window.axialdeformView = view;
    return view.ready;
  }).then((r) => {
    // firstFrameMs: from the start of the navigation (performance.timeOrigin) to the first frame drawn
    window.axialdeform = { ready: true, instances: r.instances, firstFrameMs: performance.now() };
  }).catch((err) => {
    const msg = err && err.message ? err.message : String(err);
    if (!root.querySelector('.axd-message')) {
      const m = document.createElement('div');
      m.className = 'axd-message';
      m.setAttribute('role', 'alert');
      m.textContent = msg;
      root.appendChild(m);
    }
    window.axialdeform = { ready: false, error: msg };
  });
}
"""


def _import_map(imports: dict) -> str:
    return f'<script type="importmap">{_json_in_html({"imports": imports})}</script>'


#: the list of files (and their SHA-256) an export wrote into its folder: what a later export may replace
MANIFEST = ".axialdeform-web.json"
#: what marks a single-file page this library wrote (in its config JSON)
_GENERATOR_MARK = b'"generator":"axialdeform"'


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def check_page_outputs(out: Path, names, inputs=(), overwrite: bool = False) -> None:
    """Refuse, before anything is written, to replace an input or a file this
    command did not write.

    ``names`` are the files the export writes (relative to the folder
    ``out``; a single ``.html`` page: ``[""]``).  An output that is one of
    ``inputs`` (by device and inode: a hard link or symlink counts) is always
    refused; an existing output is replaced only if an earlier export wrote
    it unchanged (the folder's :data:`MANIFEST`, or the generator mark of a
    single page), or with ``overwrite``.
    """

    manifest = {}
    if out.is_dir():
        with contextlib.suppress(OSError, ValueError, AxialDeformError):  # none or unreadable: nothing is ours
            manifest = json.loads(bytes(read_regular(out / MANIFEST, 1 << 20, "a web export's manifest")))
    for name in names:
        path = out / name if name else out
        check_output_path(path, inputs, "web page")
        if overwrite or not path.is_file():
            continue
        data = bytes(read_regular(path, what="a file of an earlier web export"))
        ours = _GENERATOR_MARK in data if not name else manifest.get(name) == _sha256(data)
        if not ours:
            raise AxialDeformError(f"{path}: exists and was not written by an earlier axialdeform web export (or was "
                                   "changed since); refusing to replace it (--overwrite replaces it)")


def _folder_files(scene: WebScene) -> dict:
    head = _import_map({"three": "./three/three.module.min.js", "three/addons/": "./three/addons/",
                        "axialdeform-three": "./" + MODULE_DIR + "index.js"})
    page = _page(scene.config, head, "", _START + _FOLDER_ENTRY)
    files = {
        "index.html": page.encode("utf-8"),
        "app.js": page_source("app.js").encode("utf-8"),
        **{MODULE_DIR + name: module_source(name).encode("utf-8") for name in MODULE_FILES},
        "scene.json": json.dumps(scene.config, ensure_ascii=False, indent=1).encode("utf-8"),
        **scene.files,
    }
    for rel in list(VENDOR_FILES.values()) + ["LICENSE", "VERSION"]:
        files["three/" + rel] = vendor_file(rel)
    return files


def write_folder(out: str | os.PathLike, scene: WebScene, *, inputs=(), overwrite: bool = False) -> Path:
    """Write ``OUT/index.html`` + ``app.js``, ``scene.json``, ``mesh.glb``,
    ``params.adp`` and ``three/`` (the vendored three.js and its licence)
    for a static web server.  Every file is written atomically; none is an
    input or a file an earlier export did not write (:func:`check_page_outputs`),
    and :data:`MANIFEST` records what was written."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise AxialDeformError(f"{out}: exists and is not a folder; give a folder, or a name ending in .html")
    files = _folder_files(scene)
    check_page_outputs(out, list(files), inputs, overwrite)
    out.mkdir(parents=True, exist_ok=True)
    for rel, data in files.items():
        path = out / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, data)
    manifest = {rel: _sha256(data) for rel, data in files.items()}
    atomic_write_bytes(out / MANIFEST, json.dumps(manifest, indent=1, sort_keys=True).encode("utf-8"))
    return out / "index.html"


def _data_script(element_id: str, data: bytes, kind: str = "application/octet-stream;base64") -> str:
    return f'<script type="{kind}" id="{element_id}">{base64.b64encode(data).decode("ascii")}</script>\n'


def _file_script(name: str, data: bytes) -> str:
    """One of the scene's files inlined: ``<script data-file="NAME">`` (base64)."""
    return (f'<script type="application/octet-stream;base64" data-file="{html.escape(name)}">'
            f'{base64.b64encode(data).decode("ascii")}</script>\n')


def embedded_file(page: str, name: str) -> bytes:
    """The bytes of the file ``name`` inlined in a single-file page (for tools and tests)."""
    marker = f'data-file="{html.escape(name)}">'
    if marker not in page:
        raise AxialDeformError(f"page: no inlined file {name!r}")
    return base64.b64decode(page.split(marker, 1)[1].split("<", 1)[0])


def single_file_html(scene: WebScene) -> str:
    """ONE self-contained page (works from ``file://``): three.js, the page
    code, the GLB and the ``.adp`` inlined as base64; three.js's licence in a comment."""
    loader = "data:text/javascript;base64," + base64.b64encode(page_source("loader.js").encode()).decode()
    licence = vendor_file("LICENSE").decode("utf-8").replace("--", "- -")
    head = f"<!-- three.js {_three_version()} (inlined below), its licence:\n{licence}-->"
    data = f'<script type="application/json" id="axd-config">{_json_in_html(scene.config)}</script>\n'
    data += "".join(_file_script(name, blob) for name, blob in scene.files.items())
    for key, rel in VENDOR_FILES.items():
        data += _data_script(f"axd-{key}", vendor_file(rel), "text/javascript;base64")
    data += _data_script("axd-app", page_source("app.js").encode("utf-8"), "text/javascript;base64")
    for name in MODULE_FILES:
        data += _data_script("axd-module-" + name.split(".")[0], module_source(name).encode("utf-8"),
                             "text/javascript;base64")
    return _page(scene.config, head, data, _START + _SINGLE_ENTRY.replace("{{LOADER}}", loader))


def write_single_file(out: str | os.PathLike, scene: WebScene, *, inputs=(), overwrite: bool = False) -> Path:
    out = Path(out)
    if out.is_dir():
        raise AxialDeformError(f"{out}: is a folder; a single page needs a name ending in .html")
    check_page_outputs(out, [""], inputs, overwrite)
    atomic_write_bytes(out, single_file_html(scene).encode("utf-8"))
    return out


def write_page(out: str | os.PathLike, scene: WebScene, *, inputs=(), overwrite: bool = False) -> Path:
    """``OUT.html`` (or ``.htm``): one self-contained file; anything else: a folder.
    Returns the page's path (the file, or the folder's ``index.html``).
    ``inputs`` are never replaced; an existing file an earlier export did
    not write is replaced only with ``overwrite`` (:func:`check_page_outputs`)."""
    out = Path(out)
    if out.suffix.lower() in (".html", ".htm"):
        return write_single_file(out, scene, inputs=inputs, overwrite=overwrite)
    return write_folder(out, scene, inputs=inputs, overwrite=overwrite)


def scene_bytes(out: str | os.PathLike) -> dict:
    """Bytes a browser downloads for an exported folder: ``page`` (index.html,
    app.js, scene.json), ``mesh`` (every layer's GLB), ``params`` (every
    ``.adp``) and ``three`` (the vendored three.js files the page imports)."""
    out = Path(out)
    size = lambda *names: sum((out / n).stat().st_size for n in names)  # noqa: E731
    config = json.loads((out / "scene.json").read_text(encoding="utf-8"))
    return {"page": size("index.html", "app.js", "scene.json", *(MODULE_DIR + n for n in MODULE_FILES)),
            "mesh": size(*(layer["mesh"]["file"] for layer in config["layers"])),
            "params": size(*(layer["params_file"] for layer in config["layers"])),
            "three": size(*("three/" + r for r in VENDOR_FILES.values()))}


def make_server(folder: str | os.PathLike, port: int = 8000):
    """An HTTP server for ``folder`` on 127.0.0.1 (not started).

    Returns ``(server, busy)``: when ``port`` is taken the operating system
    picks a free one and ``busy`` is True.  Call ``server.serve_forever()``;
    ``server.server_address[1]`` is the port."""

    folder = Path(folder)
    if not folder.is_dir():
        raise AxialDeformError(f"{folder}: no such folder to serve")

    class Handler(SimpleHTTPRequestHandler):
        extensions_map = {**SimpleHTTPRequestHandler.extensions_map, ".js": "text/javascript",
                          ".json": "application/json", ".glb": "model/gltf-binary",
                          ".adp": "application/octet-stream", ".html": "text/html; charset=utf-8"}

        def log_message(self, format, *args):  # quiet: the CLI prints the URL only
            pass

    handler = functools.partial(Handler, directory=str(folder))

    try:
        number = operator.index(port)
    except TypeError:
        number = -1
    if not 0 <= number <= 65535:
        raise AxialDeformError(f"serve: expected a TCP port 0..65535 (0: any free one), found {port!r}")
    port = number
    try:
        return ThreadingHTTPServer(("127.0.0.1", int(port)), handler), False
    except OSError as exc:
        if exc.errno not in (errno.EADDRINUSE, errno.EACCES):
            raise AxialDeformError(f"serve: cannot listen on 127.0.0.1:{port}: {exc.strerror}") from None
    return ThreadingHTTPServer(("127.0.0.1", 0), handler), True

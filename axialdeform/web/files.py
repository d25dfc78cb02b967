"""Writing a page: a folder for a static server (``index.html`` + files), ONE
self-contained ``.html``, and the list of a folder page's files (what ``serve`` answers)."""

from __future__ import annotations

import base64
import html
import json
import os
from dataclasses import dataclass
from pathlib import Path

from ..core.errors import AxialDeformError
from ..core.io.atomic import atomic_write_bytes
from ..core.io.safeio import check_new_outputs, check_output_path
from .sources import MODULE_DIR, MODULE_FILES, VENDOR_FILES, module_source, page_source, three_version, vendor_file

__all__ = ["WebScene", "check_page_outputs", "write_folder", "single_file_html", "embedded_file",
           "write_single_file", "write_page", "scene_bytes", "page_files"]


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
    const names = config.layers.flatMap((l) => (l.generate
      ? [l.mesh.file, ...Object.values(l.generate.maps || {}).map((m) => m.file),
        ...['density', 'mask'].map((k) => l.generate.brush && l.generate.brush[k]).filter(Boolean).map((m) => m.file)]
      : [l.mesh.file, l.params_file]));
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
def check_page_outputs(out: Path, names, inputs=(), overwrite: bool = False) -> None:
    """Refuse, before anything is written, to replace an input, or a file
    that exists without ``overwrite`` (the command line's one rule).

    ``names`` are the files the export writes (relative to the folder
    ``out``; a single ``.html`` page: ``[""]``).  An output that is one of
    ``inputs`` (by device and inode: a hard link or symlink counts) is
    always refused, ``overwrite`` or not.
    """

    paths = [out / name if name else out for name in names]
    for path in paths:
        check_output_path(path, inputs, "web page")
    check_new_outputs(paths, "the page's files", overwrite)


def _folder_files(scene: WebScene) -> dict:
    head = _import_map({"three": "./three/three.module.min.js", "three/addons/": "./three/addons/",
                        "axialdeform-three": "./" + MODULE_DIR + "index.js",
                        "axialdeform-three/helpers": "./" + MODULE_DIR + "helpers.js"})
    page = _page(scene.config, head, "", _START + _FOLDER_ENTRY)
    files = {
        "index.html": page.encode("utf-8"),
        "app.js": page_source("app.js").encode("utf-8"),
        **{MODULE_DIR + name: module_source(name).encode("utf-8") for name in MODULE_FILES},
        "scene.json": json.dumps(scene.config, ensure_ascii=False, indent=1).encode("utf-8"),
        **scene.files,
    }
    for rel in _VENDORED:
        files["three/" + rel] = vendor_file(rel)
    return files


#: three.js's files a folder page carries (under ``three/``)
_VENDORED = (*VENDOR_FILES.values(), "LICENSE", "VERSION")
#: the files of every folder page, whatever its scene (its layers' files come from its scene.json)
_PAGE_FILES = frozenset({"index.html", "app.js", "scene.json", *(MODULE_DIR + n for n in MODULE_FILES),
                         *("three/" + r for r in _VENDORED)})


def write_folder(out: str | os.PathLike, scene: WebScene, *, inputs=(), overwrite: bool = False) -> Path:
    """Write ``OUT/index.html`` + ``app.js``, ``scene.json``, ``mesh.glb``,
    ``params.adp`` and ``three/`` (the vendored three.js and its licence)
    for a static web server.  Every file is written atomically; none is an
    input, nor a file that exists without ``overwrite`` (:func:`check_page_outputs`)."""
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
    head = f"<!-- three.js {three_version()} (inlined below), its licence:\n{licence}-->"
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
    ``inputs`` are never replaced; an existing file is replaced only with
    ``overwrite`` (:func:`check_page_outputs`)."""
    out = Path(out)
    if out.suffix.lower() in (".html", ".htm"):
        return write_single_file(out, scene, inputs=inputs, overwrite=overwrite)
    return write_folder(out, scene, inputs=inputs, overwrite=overwrite)


def scene_bytes(out: str | os.PathLike) -> dict:
    """Bytes a browser downloads for an exported folder: ``page`` (index.html,
    app.js, scene.json), ``mesh`` (every layer's GLB), ``params`` (every
    ``.adp``; a generated layer has none) and ``three`` (the vendored three.js files the page imports)."""
    out = Path(out)
    size = lambda *names: sum((out / n).stat().st_size for n in names)  # noqa: E731
    config = json.loads((out / "scene.json").read_text(encoding="utf-8"))
    return {"page": size("index.html", "app.js", "scene.json", *(MODULE_DIR + n for n in MODULE_FILES)),
            "mesh": size(*(layer["mesh"]["file"] for layer in config["layers"])),
            "params": size(*(layer["params_file"] for layer in config["layers"] if "params_file" in layer)),
            "three": size(*("three/" + r for r in VENDOR_FILES.values()))}


def page_files(folder: str | os.PathLike) -> frozenset:
    """The relative paths (``/``-separated) of the files a folder page written by :func:`write_folder` is
    made of, read from its ``scene.json`` as the page's loader reads it: ``index.html``, ``app.js``,
    ``scene.json``, the npm module's files, the vendored three.js and every layer's mesh, parameter file
    and ground maps.  What a server of the page answers (:func:`~axialdeform.web.serve.make_server`)."""
    folder = Path(folder)
    path = folder / "scene.json"
    try:
        config = json.loads(path.read_text(encoding="utf-8"))
        layers = config["layers"]
        names = set()
        for layer in layers:
            gen = layer.get("generate")
            if gen:
                names.add(layer["mesh"]["file"])
                names.update(m["file"] for m in (gen.get("maps") or {}).values())
                brush = gen.get("brush") or {}  # the brush's grids: the layer's own density map, its saved mask
                names.update(brush[k]["file"] for k in ("density", "mask") if isinstance(brush.get(k), dict))
            else:
                names.update((layer["mesh"]["file"], layer["params_file"]))
    except OSError as exc:
        raise AxialDeformError(f"{path}: cannot read the page's scene ({exc.strerror}); expected a folder "
                               "written by 'axialdeform web'") from None
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise AxialDeformError(f"{path}: not a page's scene.json ({type(exc).__name__}: {str(exc)[:80]}); "
                               "expected a folder written by 'axialdeform web'") from None
    if not all(isinstance(n, str) for n in names):
        raise AxialDeformError(f"{path}: layers: expected file names (strings)")
    return _PAGE_FILES | names

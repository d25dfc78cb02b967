"""Where the page's files come from: the page code (``app.js``, ``loader.js``, ``page.html``), the
npm module axialdeform-three (``js/src``; the wheel's ``axialdeform/three``) and the vendored
three.js (``web/vendor/``)."""

from __future__ import annotations

from importlib import resources

from ..core.errors import AxialDeformError

__all__ = ["VENDOR_FILES", "MESH_FILE", "PARAMS_FILE", "MODULE_FILES", "MODULE_DIR", "THREE_VERSION", "page_source",
           "module_source", "vendor_file", "three_version"]

#: the files of the vendored three.js, relative to ``web/vendor/``
VENDOR_FILES = {
    "three": "three.module.min.js",
    "orbit": "addons/controls/OrbitControls.js",
    "gltf": "addons/loaders/GLTFLoader.js",
    "bgu": "addons/utils/BufferGeometryUtils.js",
}
MESH_FILE = "mesh.glb"
PARAMS_FILE = "params.adp"


def _here():
    return resources.files("axialdeform.web")


def page_source(name: str) -> str:
    """The text of one file of the page code (``app.js``, ``loader.js``, ``page.html``)."""
    return _here().joinpath(name).read_text(encoding="utf-8")


#: the npm module axialdeform-three's files of its WebGL entry (js/src; the wheel's axialdeform/three), which
#: the page code imports, each after the files it imports; the folder page keeps them in MODULE_DIR
MODULE_FILES = ("core/record.js", "core/adp.js", "core/bend.js", "core/wind.js", "core/limits.js", "core/baked.js",
                "core/raycast.js", "core/cull.js", "core/variant.js", "core/generate.js", "core/mesh.js", "core/gltf.js", "core/brush.js",
                "webgl/glsl.js",
                "webgl/shader.js", "webgl/feedback.js", "webgl/bake.js", "webgl/raycast.js", "webgl/instance_cull.js",
                "webgl/tiles.js", "webgl/generate.js", "webgl/mesh.js", "webgl/gltf.js", "index.js", "helpers.js")
MODULE_DIR = "axialdeform-three/"


def module_source(name: str) -> str:
    """The text of one file of the npm module axialdeform-three (``js/src``; the wheel's ``axialdeform/three``):
    ``name`` relative to it (``core/adp.js``)."""
    return resources.files("axialdeform.three").joinpath(*name.split("/")).read_text(encoding="utf-8")


def vendor_file(relative: str) -> bytes:
    """The bytes of one vendored three.js file (``web/vendor/<relative>``)."""
    res = _here().joinpath("vendor", *relative.split("/"))
    if not res.is_file():
        raise AxialDeformError(f"axialdeform/web/vendor/{relative}: missing; run tools/vendor_three.sh")
    return res.read_bytes()


def three_version() -> str:
    """The vendored three.js's version (``web/vendor/VERSION``)."""
    return vendor_file("VERSION").decode().strip()


THREE_VERSION = "0.160.1"  # tools/vendor_three.sh pins it; tests compare with vendor/VERSION

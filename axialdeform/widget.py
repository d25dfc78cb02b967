"""``SceneWidget``: the web page's scene inline in a notebook (an anywidget
running the same page code, ``axialdeform/web/app.js``).  Tested in a real
JupyterLab (tests/web/test_notebook.py); Jupyter Notebook 7 and VS Code load
anywidgets the same way but are not tested here.

    from axialdeform.widget import SceneWidget
    w = SceneWidget("stone", params)      # a mesh (or its name / file) and (n, 16) float32
    w                                     # shows it; drag to orbit
    w.set_params(other_params)            # updates the drawing in place

``status`` is what the page reports: ``{"ready": True, "instances": n}`` after
the first frame, or ``{"ready": False, "error": "..."}``.
"""

from __future__ import annotations

import anywidget
import traitlets

from .core.io.mesh import load_mesh
from .core.io.params import encode_binary
from .core.mesh import BaseMesh
from .core.params import as_params
from .web import VENDOR_FILES, build_scene, page_source, vendor_file

__all__ = ["SceneWidget"]


def _esm() -> str:
    return page_source("loader.js") + "\n" + page_source("widget.js")


class SceneWidget(anywidget.AnyWidget):
    """The scene of ``mesh`` and ``params`` ((n, 16) float32) in a notebook.

    size : (width, height) of the canvas; the first view is ``axialdeform
    render``'s camera at that size.  up : world up ('x', 'y', 'z').
    quantize : send the 32-byte quantized records (default) or float32.
    """

    _esm = traitlets.Unicode(_esm()).tag(sync=True)
    config = traitlets.Dict().tag(sync=True)
    mesh_glb = traitlets.Bytes().tag(sync=True)
    params_adp = traitlets.Bytes().tag(sync=True)
    _sources = traitlets.Dict().tag(sync=True)
    status = traitlets.Dict().tag(sync=True)

    def __init__(self, mesh, params, *, size=(640, 480), up: str = "y", quantize: bool = True, **kwargs):

        self._mesh = mesh if isinstance(mesh, BaseMesh) else load_mesh(mesh)
        self._quantize = bool(quantize)
        scene = build_scene(self._mesh, params, size=size, up=up, quantize=quantize, all_shaders=True)
        sources = {key: vendor_file(rel).decode("utf-8") for key, rel in VENDOR_FILES.items()}
        sources["app"] = page_source("app.js")
        super().__init__(config=scene.config, mesh_glb=scene.glb, params_adp=scene.adp, _sources=sources,
                         status={}, **kwargs)

    def set_params(self, params) -> None:
        """Draw ``params`` ((m, 16) float32, any count) instead; the camera stays."""
        params = as_params(params)
        axis = self._mesh.axis
        adp = encode_binary(params, axis=axis, mesh_fingerprint=self._mesh.fingerprint, quantize=self._quantize)
        with self.hold_sync():  # one update message to the front end, not two
            self.params_adp = adp
            self.config = {**self.config, "instances": int(len(params))}

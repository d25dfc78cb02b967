"""``SceneWidget``: the web page's scene inline in a notebook (an anywidget
running the same page code, ``axialdeform/web/app.js``).  Tested in a real
JupyterLab (tests/web/test_notebook.py); Jupyter Notebook 7 and VS Code load
anywidgets the same way but are not tested here.

    from axialdeform.widget import SceneWidget
    w = SceneWidget("stone", params)      # a mesh (or its name / file) and (n, 16) float32
    w                                     # shows it; drag to orbit
    w.set_params(other_params)            # updates the drawing in place
    SceneWidget("landscape.toml")         # a scene file (or an axialdeform.Scene): every layer

``status`` is what the page reports: ``{"ready": True, "instances": n}`` after
the first frame, or ``{"ready": False, "error": "..."}``.

A scene file's generated layers can be painted with the page's brush (B, then drag; E erase, M save):
each saved mask comes back here and is written beside the scene file (``SCENE-LAYER-mask.png``,
atomically), where the scene finds it when it is loaded again; ``masks_saved`` lists them.
"""

from __future__ import annotations

from pathlib import Path

import anywidget
import numpy as np
import traitlets

from .core.bounds import scene_box
from .core.brush import mask_path
from .core.errors import AxialDeformError
from .core.io.atomic import atomic_path
from .core.io.params import encode_binary
from .core.options import RenderOptions
from .core.params import as_params
from .core.scene import Scene
from .core.surface import load_mask
from .web import (
    MODULE_FILES,
    VENDOR_FILES,
    PageOptions,
    build_scene,
    build_scene_file,
    fit_ground_and_shadow,
    module_source,
    page_source,
    vendor_file,
)

__all__ = ["SceneWidget"]


def _esm() -> str:
    return page_source("loader.js") + "\n" + page_source("widget.js")


class SceneWidget(anywidget.AnyWidget):
    """A scene in a notebook: the page ``axialdeform web`` writes, inline.

    Parameters
    ----------
    scene : Scene, str, PathLike or BaseMesh
        A :class:`axialdeform.Scene`, a scene file (``.toml``: every layer,
        the terrain, the file's camera, light and wind), or a mesh (a
        :class:`BaseMesh`, a bundled name or a mesh file) with ``params``.
    params : (n, 16) or (n, 19) float32, optional
        The instances of a mesh.
    size : (int, int)
        The canvas; the first view is ``axialdeform render``'s camera at
        that size.
    up : {"x", "y", "z"}
        World up of a mesh (a scene has its own).
    quantize : bool
        Send the 32-byte quantized records (default) or float32.
    look : Look, optional
        Light, ambient, background (default: the scene's).
    """

    _esm = traitlets.Unicode(_esm()).tag(sync=True)
    config = traitlets.Dict().tag(sync=True)
    mesh_glb = traitlets.Bytes().tag(sync=True)
    params_adp = traitlets.Bytes().tag(sync=True)
    #: every layer's GLB and .adp by file name (a scene of several layers); empty for one mesh
    files = traitlets.Dict().tag(sync=True)
    _sources = traitlets.Dict().tag(sync=True)
    status = traitlets.Dict().tag(sync=True)
    #: the masks the brush saved beside the scene file (paths)
    masks_saved = traitlets.List()

    def __init__(self, scene, params=None, *, size=(640, 480), up: str = "y", quantize: bool = True, look=None,
                 **kwargs):
        sources = {key: vendor_file(rel).decode("utf-8") for key, rel in VENDOR_FILES.items()}
        sources["app"] = page_source("app.js")
        sources["module"] = {name: module_source(name) for name in MODULE_FILES}  # axialdeform-three: app.js imports it
        self._quantize = bool(quantize)
        scene = Scene.of(scene, params, up=up)  # the one mesh-or-scene check
        self._scene_path = scene.path
        self._generated = [x.name for x in scene.layers if getattr(x, "generate", None) is not None]
        if scene.path is not None or len(scene.layers) != 1 or scene.terrain is not None:
            self._mesh = None  # several layers: set_params has no one mesh to act on
            web = build_scene_file(scene, page=PageOptions(size=size, quantize=quantize), look=look)
            first = web.config["layers"][0]
            super().__init__(config=web.config, mesh_glb=web.files[first["mesh"]["file"]],
                             params_adp=web.files.get(first.get("params_file"), b""), files=dict(web.files), _sources=sources,
                             status={}, **kwargs)
            self.on_msg(self._on_mask)
            return
        self._mesh, params = scene.layers[0].mesh, scene.layers[0].params
        self._look, self._up = look, up
        web = build_scene(self._mesh, params, page=PageOptions(size=size, quantize=quantize, all_shaders=True),
                          options=RenderOptions(up=up), look=look)
        super().__init__(config=web.config, mesh_glb=web.glb, params_adp=web.adp, files={}, _sources=sources,
                         status={}, **kwargs)
        self.on_msg(self._on_mask)

    def _on_mask(self, _widget, content, buffers) -> None:
        """A mask the page's brush saved (M): checked as an image of grey levels, then written beside the scene
        file, atomically.  A bad one changes nothing and is reported in ``status``."""
        if not isinstance(content, dict) or content.get("type") != "mask":
            return
        layer = str(content.get("layer", ""))
        try:
            if self._scene_path is None:
                raise AxialDeformError("brush: the masks are saved beside a scene file; this widget shows no scene file")
            if layer not in self._generated:
                raise AxialDeformError(f"brush: layer: expected a generated layer ({', '.join(self._generated) or 'none'}), "
                                       f"found {layer!r}")
            if len(buffers) != 1:
                raise AxialDeformError(f"brush: {layer}: expected one PNG with the mask, found {len(buffers)} buffers")
            path = mask_path(self._scene_path, layer)
            with atomic_path(path, suffix=".png") as tmp:
                Path(tmp).write_bytes(bytes(buffers[0]))
                load_mask(tmp)  # a grey image, or the library's error naming it: nothing replaced
        except AxialDeformError as exc:
            self.status = {**self.status, "mask_error": str(exc)}
            return
        self.masks_saved = [*self.masks_saved, str(path)]

    def set_params(self, params) -> None:
        """Draw ``params`` ((m, 16) float32, any count) instead; the camera stays, the ground and the key light's
        shadow camera are fitted to them again (as a new page of them would have them), and the camera's near and far
        planes widen where they would cut them.  (A widget of one mesh; a
        scene's layers are its file's.)"""
        if self._mesh is None:
            raise AxialDeformError("set_params: this widget shows a scene of several layers; expected a widget of "
                                   "one mesh (SceneWidget(mesh, params))")
        params = as_params(params, axes=self._mesh.axis_count)
        adp = encode_binary(params, axis=self._mesh, mesh_fingerprint=self._mesh.fingerprint, quantize=self._quantize)
        ground, shadow = fit_ground_and_shadow(self._mesh, params, self._look, self._up)
        lo, hi = scene_box(self._mesh, params)  # the camera's depth range widens to hold them (the page's refit)
        reach = {"center": ((lo + hi) / 2).tolist(), "radius": float(np.linalg.norm(hi - lo) / 2)}
        with self.hold_sync():  # one update message to the front end, not two
            self.params_adp = adp
            self.config = {**self.config, "instances": int(len(params)), "ground": ground, "shadow": shadow,
                           "reach": reach}

"""The viewer's brush (``axialdeform view``; docs/learn.md, "Set the range"): paint where a scene's
generated layers grow, or erase.

Each stroke paints the layer's mask (:mod:`axialdeform.core.brush`), folds it into the density the
generator reads, gives the GPU generator the new density texture and lets the viewer make the tiles within
reach again on its next frame.  :meth:`Brush.save` writes each painted mask beside the scene file
(``SCENE-LAYER-mask.png``, 16-bit grey, atomically), where the scene finds it when it is loaded again.  In
a window: B brush on/off (a drag then paints instead of orbiting), E paint/erase, [ and ] the radius, M save;
headless: ``view SCENE --paint LAYER:X,Z,R[:erase]``.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from PIL import Image

from .core.brush import Stroke, fold, mask_path, new_mask, paint
from .core.errors import ParamError
from .core.generate_ground import GroundMaps, density_area, ground_height
from .core.io.atomic import atomic_path
from .core.surface import load_density, load_mask

__all__ = ["Brush", "Stroke"]


class Brush:
    """Painting a viewer's generated layers.

    viewer : the viewer (its ``generate``, ``layers``, ``_gpu`` and ``_tiles``); scene_file : Path or None (where
    masks are saved); first : the name of the viewer's own layer; terrain : the scene's height-map terrain or None.
    """

    def __init__(self, viewer, scene_file, first: str, terrain=None):
        self.viewer = viewer
        self.scene_file = None if scene_file is None else Path(scene_file)
        self.first = first
        self.terrain = terrain
        self.on = False  # a drag paints (True) or orbits
        self.erase = False
        self.radius = 2.0
        self.masks = {}  # layer name -> the mask painted, (rows, cols) float32
        self._density = {}  # layer name -> the density map's own grey levels (None: none)

    def layers(self) -> dict:
        """Every generated layer the viewer draws: name -> (key of the viewer's tiles, its GenerateRecipe)."""
        out = {}
        if self.viewer.generate is not None:
            out[self.first] = ("", self.viewer.generate)
        for layer, _, _ in self.viewer.layers:
            if getattr(layer, "generate", None) is not None:
                out[layer.name] = (layer.name, layer.generate)
        return out

    def stroke(self, stroke: Stroke) -> bool:
        """Paint ``stroke``; whether the layer's mask changed (its tiles are then made again)."""
        found = self.layers()
        if stroke.layer not in found:
            raise ParamError(f"brush: layer: expected a generated layer ({', '.join(found) or 'none'}), found {stroke.layer!r}")
        key, gen = found[stroke.layer]
        if stroke.layer not in self._density:
            self._density[stroke.layer] = load_density(gen.density).astype(np.float32) if gen.density is not None else None
        mask = self.masks.get(stroke.layer)
        if mask is None:
            mask = load_mask(gen.mask) if gen.mask is not None else new_mask(self._density[stroke.layer])
            self.masks[stroke.layer] = mask
        if not paint(mask, density_area(self.terrain, gen.extent)[0], stroke):  # where GroundMaps places the map
            return False
        maps = GroundMaps.of(self.terrain, fold(self._density[stroke.layer], mask), gen.extent)
        if gen.maps is not None and gen.maps.heights is None:  # a flat ground keeps its repeated map
            maps = replace(maps, d_wrap=True)
        gen = replace(gen, maps=maps)
        if key == "":
            self.viewer.generate = gen
        else:
            next(layer for layer, _, _ in self.viewer.layers if layer.name == key).generate = gen
        gpu = self.viewer._gpu.get(key)
        if gpu is not None:
            gpu.generator.set_density(maps, gpu.mesh)
        self.viewer._tiles.pop(key, None)  # made again on the next frame
        return True

    def at(self, x: float, y: float) -> tuple[float, float] | None:
        """The ground point under window pixel (x, y) (from the top left): the camera's ray marched to the first
        point below the ground (the painted layer's height map, or y = 0); None where it meets none."""
        view, proj = self.viewer.matrices()  # pyrr layout: clip = world @ view @ proj (row vectors)
        w, h = self.viewer.wnd.buffer_size
        inv = np.linalg.inv(np.asarray(view, np.float64) @ np.asarray(proj, np.float64))
        ndc = (2.0 * x / w - 1.0, 1.0 - 2.0 * y / h)
        near, far = ((p[:3] / p[3]) for p in (np.array([ndc[0], ndc[1], z, 1.0]) @ inv for z in (-1.0, 1.0)))
        t = np.linspace(0.0, 1.0, 4097)
        ray = near[None, :] + t[:, None] * (far - near)[None, :]
        maps = next((gen.maps for _, gen in self.layers().values() if gen.maps is not None), None)
        ground = np.zeros(len(ray))
        if maps is not None and maps.heights is not None:
            ground = ground_height(maps, ray[:, [0, 2]].astype(np.float32))[0].astype(np.float64)
        below = np.nonzero(ray[:, 1] <= ground)[0]
        return None if not len(below) else (float(ray[below[0], 0]), float(ray[below[0], 2]))

    def save(self) -> list[Path]:
        """Each painted mask beside the scene file (16-bit grey PNG, atomically); the paths written."""
        if self.scene_file is None:
            raise ParamError("brush: the masks are saved beside a scene file; expected a scene (view SCENE.toml)")
        written = []
        for name, mask in self.masks.items():
            path = mask_path(self.scene_file, name)
            with atomic_path(path, suffix=".png") as tmp:
                Image.fromarray(np.round(np.clip(mask, 0, 1) * 65535).astype(np.uint16)).save(tmp, format="PNG")
            written.append(path)
        return written

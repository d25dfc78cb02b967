"""Where a generated layer grows, painted: a layer's **mask** (docs/learn.md, "Set the range").

A mask is a grey image over the same ground as the layer's density map (the terrain's ground, or on flat
ground the layer's ``extent``): white grows, black does not.  It multiplies the density map (no density map:
it is one), so painting never adds instances a recipe would not make, and erasing removes them.  A layer's
mask lives beside its scene file as ``SCENE-LAYER-mask.png`` (:func:`mask_path`): the scene reads it again
whenever it is loaded.  :func:`paint` is a round brush; :func:`fold` the density the generator reads.  Pure
numpy: no GL here.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ParamError

__all__ = ["MASK_SIZE", "Stroke", "mask_path", "new_mask", "paint", "fold"]

#: pixels a side of a new mask
MASK_SIZE = 512


@dataclass(frozen=True)
class Stroke:
    """One dab of the brush.

    Attributes
    ----------
    layer : str
        The generated layer painted.
    x, z : float
        The brush's centre on the ground (world units).
    radius : float
        Its radius (world units), > 0.
    erase : bool
        Erase (black) instead of paint (white).
    """

    layer: str
    x: float
    z: float
    radius: float
    erase: bool = False

    def __post_init__(self) -> None:
        if not (np.isfinite([self.x, self.z, self.radius]).all() and self.radius > 0):
            raise ParamError(f"brush: layer {self.layer}: expected a finite x, z and a radius > 0, found "
                             f"{self.x!r}, {self.z!r}, {self.radius!r}")


def mask_path(scene_file, layer: str) -> Path:
    """The mask file of layer ``layer`` of scene file ``scene_file``: ``SCENE-LAYER-mask.png`` beside it."""
    scene_file = Path(scene_file)
    return scene_file.with_name(f"{scene_file.stem}-{layer}-mask.png")


def new_mask(density: np.ndarray | None = None) -> np.ndarray:
    """A mask where everything grows: (MASK_SIZE, MASK_SIZE) ones, or the density map's size where that is larger."""
    rows, cols = (MASK_SIZE, MASK_SIZE) if density is None else (max(MASK_SIZE, density.shape[0]), max(MASK_SIZE, density.shape[1]))
    return np.ones((rows, cols), np.float32)


def paint(mask: np.ndarray, area, stroke: Stroke) -> bool:
    """Paint (or erase) ``stroke`` into ``mask`` ((rows, cols) float32 over ``area`` (x0, z0, x1, z1): row 0 at
    z0), in place: every pixel whose centre lies within the radius.  Whether any pixel changed."""
    rows, cols = mask.shape
    x0, z0, x1, z1 = (float(v) for v in area)
    px, pz = (x1 - x0) / cols, (z1 - z0) / rows
    c0, c1 = int(np.floor((stroke.x - stroke.radius - x0) / px)), int(np.ceil((stroke.x + stroke.radius - x0) / px))
    r0, r1 = int(np.floor((stroke.z - stroke.radius - z0) / pz)), int(np.ceil((stroke.z + stroke.radius - z0) / pz))
    c0, c1, r0, r1 = max(c0, 0), min(c1, cols), max(r0, 0), min(r1, rows)
    if c0 >= c1 or r0 >= r1:
        return False
    cx = x0 + (np.arange(c0, c1) + 0.5) * px
    cz = z0 + (np.arange(r0, r1) + 0.5) * pz
    inside = (cx[None, :] - stroke.x) ** 2 + (cz[:, None] - stroke.z) ** 2 <= stroke.radius ** 2
    value = np.float32(0.0 if stroke.erase else 1.0)
    block = mask[r0:r1, c0:c1]
    changed = bool((block[inside] != value).any())
    block[inside] = value
    return changed


def fold(density: np.ndarray | None, mask: np.ndarray | None) -> np.ndarray | None:
    """The density the generator reads: ``density`` times ``mask`` (both over the same ground), on the mask's
    grid (the density map's nearest pixel under each mask pixel); None when there is neither."""
    if mask is None:
        return density
    if density is None:
        return np.ascontiguousarray(mask, np.float32)
    rows, cols = mask.shape
    r = np.minimum((np.arange(rows) + 0.5) * density.shape[0] / rows, density.shape[0] - 1).astype(np.int64)
    c = np.minimum((np.arange(cols) + 0.5) * density.shape[1] / cols, density.shape[1] - 1).astype(np.int64)
    return np.ascontiguousarray(np.asarray(density, np.float32)[r[:, None], c[None, :]] * mask, np.float32)

"""Pictures: PNG files written atomically (Pillow)."""

from __future__ import annotations

import os

import numpy as np
from PIL import Image

from .atomic import atomic_path

__all__ = ["save_png"]


def save_png(path: str | os.PathLike, image: np.ndarray) -> None:
    """Write an image as PNG, atomically.

    Parameters
    ----------
    path : str or PathLike
    image : (h, w, 3) or (h, w, 4) uint8
        First row at the top.
    """

    with atomic_path(path, suffix=".png") as tmp:
        Image.fromarray(np.ascontiguousarray(image)).save(tmp, format="PNG")

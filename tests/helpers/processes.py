"""Point patterns with known answers for the learning tests: a synthetic terrain (its height map as an array,
a 16-bit PNG and a scene file), and Poisson, inhomogeneous Poisson and Matern cluster patterns on it."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from PIL import Image

from axialdeform.core.generate_ground import GroundMaps
from axialdeform.core.ground_features import GroundFeatures

SIZE = (200.0, 120.0)  # width (x) and depth (z) of the synthetic terrain, centred on the origin
HEIGHT = 20.0


def hills(cols: int = 161, rows: int = 97, phase: float = 0.0) -> np.ndarray:
    """Grey levels (rows, cols) in [0, 1] of rolling hills whose slope and altitude vary independently."""
    x, z = np.meshgrid(np.linspace(0, 1, cols), np.linspace(0, 1, rows))
    h = 0.5 + 0.25 * np.sin(2 * math.pi * (1.3 * x + phase)) * np.cos(2 * math.pi * 0.8 * z) + 0.2 * (x - 0.5) + 0.15 * z
    return np.clip(h, 0, 1)


def ground(grey: np.ndarray | None = None) -> tuple[GroundMaps, GroundFeatures]:
    """The maps and features of a terrain of ``grey`` (default :func:`hills`) over SIZE, HEIGHT high."""
    grey = hills() if grey is None else grey
    rows, cols = grey.shape
    maps = GroundMaps(heights=(grey * HEIGHT).astype(np.float32), h_lo=np.array([-SIZE[0] / 2, -SIZE[1] / 2], np.float32),
                      h_inv=np.array([(cols - 1) / SIZE[0], (rows - 1) / SIZE[1]], np.float32))
    return maps, GroundFeatures.of(maps)


def window() -> tuple:
    return (-SIZE[0] / 2, -SIZE[1] / 2, SIZE[0] / 2, SIZE[1] / 2)


def write_terrain(folder: Path, grey: np.ndarray | None = None, name: str = "hills") -> Path:
    """A scene file with the terrain of ``grey`` as a 16-bit height map; its path."""
    grey = hills() if grey is None else grey
    Image.fromarray(np.round(grey * 65535).astype(np.uint16)).save(folder / f"{name}.png")
    scene = folder / f"{name}.toml"
    scene.write_text(f'[terrain]\nheightmap = "{name}.png"\nheight_scale = {HEIGHT}\nextent = [{SIZE[0]}, {SIZE[1]}]\n')
    return scene


def inhomogeneous(rng, feats: GroundFeatures, coef: dict, base: float) -> np.ndarray:
    """An inhomogeneous Poisson pattern of ``log lambda = log(base) + sum coef[f] f`` over window()."""
    x0, z0, x1, z1 = window()
    gx, gz = np.meshgrid(np.linspace(x0, x1, 300), np.linspace(z0, z1, 200))
    names = list(coef)
    c = np.array([coef[n] for n in names])
    top = base * math.exp(float((feats.at(np.stack([gx.ravel(), gz.ravel()], 1), names) @ c).max())) * 1.05
    n = rng.poisson(top * (x1 - x0) * (z1 - z0))
    xz = np.stack([rng.uniform(x0, x1, n), rng.uniform(z0, z1, n)], 1)
    lam = base * np.exp(feats.at(xz, names) @ c)
    return xz[rng.uniform(0, top, n) < lam]


def matern_cluster(rng, kappa: float, radius: float, mu: float) -> np.ndarray:
    """A Matern cluster pattern over window(): parents ``kappa`` a square unit (beyond the window by ``radius``
    too), Poisson(mu) children uniform in a disc of ``radius``."""
    return matern_cluster_in(rng, window(), kappa, radius, mu)


def matern_cluster_in(rng, box, kappa: float, radius: float, mu: float, core: tuple = (0.0, 0.0)) -> np.ndarray:
    """A Matern cluster pattern over ``box`` (x0, z0, x1, z1); with ``core`` (share, radius) that share of the
    children in a disc of the smaller radius (clumps within clumps)."""
    x0, z0, x1, z1 = box
    n = rng.poisson(kappa * (x1 - x0 + 2 * radius) * (z1 - z0 + 2 * radius))
    parents = np.stack([rng.uniform(x0 - radius, x1 + radius, n), rng.uniform(z0 - radius, z1 + radius, n)], 1)
    k = rng.poisson(mu, n)
    at = np.repeat(parents, k, axis=0)
    reach = np.where(rng.uniform(0, 1, k.sum()) < core[0], core[1], radius) if core[0] > 0 else radius
    a, r = rng.uniform(0, 2 * math.pi, k.sum()), reach * np.sqrt(rng.uniform(0, 1, k.sum()))
    xz = at + np.stack([r * np.cos(a), r * np.sin(a)], 1)
    return xz[(xz[:, 0] >= x0) & (xz[:, 0] <= x1) & (xz[:, 1] >= z0) & (xz[:, 1] <= z1)]

"""Scene files of generated layers (hills with stones and grass, trees over stones and grass, a glTF
generated form) the page and WebGPU tests both draw, and the comparison of their record arrays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from axialdeform.core.brush import Stroke, mask_path, new_mask, paint

ROOT = Path(__file__).resolve().parents[2]
LANDSCAPE = ROOT / "examples" / "landscape"

HILLS = """
background = [0.80, 0.87, 0.95]
[terrain]
heightmap = "terrain.png"
height_scale = 6.0
extent = [40.0, 30.0]
color = [0.42, 0.40, 0.30]
[camera]
elevation = 28.0
azimuth = 25.0
fov = 30.0
[[layer]]
name = "stones"
mesh = "stone"
color = [0.58, 0.55, 0.5]
[layer.generate]
rate = 1.2
tile = 8.0
min_distance = 0.4
seed = 4
bend = 0.15
scale = [0.2, 0.45]
scale_quartiles = [0.22, 0.27, 0.36]
scale_octiles = [0.21, 0.24, 0.31, 0.40]
density = "stone_density.png"
altitude = [0.0, 2.5]
align_to_normal = 0.8
anchor = "center"
extent = [-20, -15, 20, 15]
reach = 40.0
[[layer]]
name = "grass"
mesh = "grass.obj"
[layer.generate]
rate = 3.0
tile = 8.0
min_distance = 0.2
seed = 2
bend = 0.25
slope = [0, 25]
altitude = [1.5, 6]
tint = 0.5
tint_color = [0.4, 0.7, 0.25]
extent = [-20, -15, 20, 15]
reach = 40.0
"""

TREES = """
background = [0.80, 0.87, 0.95]
[camera]
elevation = 20
azimuth = 30
[[layer]]
name = "trees"
mesh = "tree"
axes = "tree-axes.toml"
[layer.generate]
rate = 0.02
tile = 16.0
min_distance = 3.0
seed = 5
bend = [0.03, 0.25]
scale = [0.8, 1.2]
extent = [-24, -24, 24, 24]
reach = 30.0
[[layer]]
name = "ground"
mesh = ["stone", "grass.obj"]
[layer.generate]
rate = 0.5
tile = 16.0
seed = 6
weights = [1, 3]
extent = [-24, -24, 24, 24]
reach = 30.0
"""

GLTF_SCENE = """
[[layer]]
name = "stones"
mesh = "stone.obj"
[layer.generate]
rate = 0.5
tile = 4.0
min_distance = 0.6
seed = 8
bend = 0.15
scale = [0.5, 0.9]
extent = [-4, -4, 4, 4]
reach = 7.0
"""


def close(got, want) -> float:
    """The largest difference of two record arrays, relative to max(1, |want|)."""
    got, want = np.asarray(got, np.float64), np.asarray(want, np.float64)
    assert got.shape == want.shape, (got.shape, want.shape)
    return float((np.abs(got - want) / np.maximum(1.0, np.abs(want))).max()) if want.size else 0.0


def learned_clumps(folder: Path, hills: Path) -> Path:
    """A scene learned (``learn``'s library calls) from a clumped survey on ``hills``' terrain: stones in clumps
    with a core (0.4 of each clump within 0.25 of its parent), with a clearing painted into its mask."""
    from axialdeform.core.io.example import learn_layer, write_learned
    from axialdeform.core.learn import Example

    from .processes import matern_cluster_in

    xz = matern_cluster_in(np.random.default_rng(5), (-20.0, -15.0, 20.0, 15.0), 0.25, 1.0, 8.0, core=(0.4, 0.25))
    layers = learn_layer(Example(xz, (-20.0, -15.0, 20.0, 15.0)), hills)
    assert layers[0].spacing.pattern == "cluster" and layers[0].spacing.core is not None, layers[0].spacing
    out = folder / "learned.toml"
    write_learned(out, layers, hills, mesh="stone", size=0.2)
    mask = new_mask()  # a clearing painted with the brush: the mask beside the scene file
    paint(mask, (-20.0, -15.0, 20.0, 15.0), Stroke("learned", 0.0, 0.0, 4.0, erase=True))
    Image.fromarray((mask * 65535).astype(np.uint16)).save(mask_path(out, "learned"))
    return out

"""Write the small committed inputs of examples/05_landscape.py into
examples/landscape/: a height map (a river valley between two hills), the
grass and stone density maps, a grass blade and a trunk-like mesh.

    python tools/make_landscape_assets.py

Deterministic: the same files every run (the scene file itself,
examples/landscape/landscape.toml, is written by hand).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from PIL import Image

OUT = Path(__file__).resolve().parent.parent / "examples" / "landscape"


def valley(cols: int, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """Heights in [0, 1] (rows along +z, columns along +x) and the river's distance field."""
    x = np.linspace(-1.0, 1.0, cols)[None, :]
    z = np.linspace(-1.0, 1.0, rows)[:, None]
    river_x = 0.25 * np.sin(2.2 * z + 0.4)  # the river winds along z
    d = np.abs(x - river_x)  # distance to the river, across
    h = 0.12 + 0.75 * np.clip(d / 0.9, 0, 1) ** 1.5 + 0.08 * np.sin(5 * x + 3 * z) * np.cos(4 * z)
    # the river bed, blended into the banks: a step here, sampled on the grid, stair-stepped the winding
    # banks into regular streaks in the shading (and dark smudges on the forest's hillside)
    s = np.clip((d - 0.05) / 0.09, 0, 1)
    h = 0.06 + (h - 0.06) * s * s * (3 - 2 * s)
    return np.clip(h, 0, 1), d


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    h, _ = valley(64, 48)
    # 16 bits a height: 8 would step the gentle river bed into terraces (streaks in its shading)
    Image.fromarray(np.round(h * 65535).astype(np.uint16)).save(OUT / "terrain.png", optimize=True)
    _, d = valley(32, 24)
    rng = np.random.default_rng(5)
    # grass: on the slopes away from the river, patchy
    grass = np.clip((d - 0.25) / 0.25, 0, 1) * (0.4 + 0.6 * (rng.random(d.shape) > 0.3))
    Image.fromarray(np.round(grass * 255).astype(np.uint8)).save(OUT / "grass_density.png", optimize=True)
    # stones: on the banks only, just beside the bed
    stones = ((d > 0.08) & (d < 0.22)).astype(np.float64)
    Image.fromarray(np.round(stones * 255).astype(np.uint8)).save(OUT / "stone_density.png", optimize=True)
    # falling leaves: over the terrain's inner part only (a leaf lifted over the edge hangs in the air
    # beside the terrain in the picture), thinning out over the outer sixth
    rows, cols = d.shape
    inner = np.minimum.outer(np.minimum(np.arange(rows), np.arange(rows)[::-1]) / rows,
                             np.minimum(np.arange(cols), np.arange(cols)[::-1]) / cols)
    leaves = np.clip((inner - 0.08) / 0.1, 0, 1)
    Image.fromarray(np.round(leaves * 255).astype(np.uint8)).save(OUT / "leaf_density.png", optimize=True)

    # a grass blade: a thin strip along +y, tapering to a point, 6 segments
    t = np.linspace(0.0, 1.0, 7)
    width = 0.06 * (1 - t) + 0.004
    left = np.stack([-width, t, 0.01 * np.sin(3 * t)], axis=1)
    right = np.stack([width, t, 0.01 * np.sin(3 * t)], axis=1)
    verts = np.concatenate([left, right])
    n = len(t)
    faces = []
    for i in range(n - 1):  # a handful of faces for a file written once: not a hot path
        faces += [[i, n + i, i + 1], [i + 1, n + i, n + i + 1]]
    faces = np.array(faces)
    blade = trimesh.Trimesh(verts, np.concatenate([faces, faces[:, ::-1]]), process=False)  # two-sided
    blade.export(OUT / "grass.obj")

    # a trunk: a tapered 10-sided cylinder, base at y = 0, 3 units tall, with a few rings
    trunk = trimesh.creation.cylinder(radius=0.18, height=3.0, sections=10)
    trunk = trimesh.Trimesh(*trimesh.remesh.subdivide_to_size(trunk.vertices, trunk.faces, 0.6), process=True)
    v = trunk.vertices.copy()
    v = v[:, [0, 2, 1]]  # cylinder along z -> along y
    v[:, 2] *= -1  # keep the handedness (outward faces)
    v[:, 1] += 1.5
    v[:, [0, 2]] *= (1.0 - 0.45 * v[:, 1:2] / 3.0)
    trunk = trimesh.Trimesh(v, trunk.faces, process=False)
    trunk.export(OUT / "trunk.obj")
    print(f"wrote {', '.join(sorted(p.name for p in OUT.iterdir()))} to {OUT}")


if __name__ == "__main__":
    main()

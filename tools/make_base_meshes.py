"""Regenerate the two bundled base meshes (axialdeform/meshes/*.obj).

    python tools/make_base_meshes.py

* stone.obj: 58 vertices like the thesis's stone — a UV sphere of 8 rings x 8
  segments (7 x 8 + 2 poles), squashed into a pebble and roughened with a
  fixed seed; longest along x.
* leaf.obj: a single-sided leaf blade with a midrib, slightly cupped, longest
  along y (the stalk at y = 0).
"""

from pathlib import Path

import numpy as np
import trimesh

OUT = Path(__file__).resolve().parent.parent / "axialdeform" / "meshes"


def stone() -> trimesh.Trimesh:
    rings, segments = 8, 8
    rng = np.random.Generator(np.random.PCG64(2003))
    verts = [(0.0, 0.0, 1.0)]
    for r in range(1, rings):
        theta = np.pi * r / rings
        for s in range(segments):
            phi = 2 * np.pi * (s + 0.5 * (r % 2)) / segments
            verts.append((np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)))
    verts.append((0.0, 0.0, -1.0))
    v = np.array(verts)
    v *= 1.0 + 0.09 * (rng.random((len(v), 1)) - 0.5)
    v *= (1.0, 0.62, 0.42)  # pebble proportions: long along x, flat along z
    v = v[:, [0, 2, 1]] * (1, 1, -1)  # lie flat: thin along y (up)
    faces = []
    n = segments
    for s in range(n):
        faces.append((0, 1 + s, 1 + (s + 1) % n))
    for r in range(rings - 2):
        a0, b0 = 1 + r * n, 1 + (r + 1) * n
        for s in range(n):
            s1 = (s + 1) % n
            faces.append((a0 + s, b0 + s, b0 + s1) if r % 2 == 0 else (a0 + s, b0 + s, a0 + s1))
            faces.append((a0 + s, b0 + s1, a0 + s1) if r % 2 == 0 else (a0 + s1, b0 + s, b0 + s1))
    last = len(v) - 1
    base = 1 + (rings - 2) * n
    for s in range(n):
        faces.append((last, base + (s + 1) % n, base + s))
    m = trimesh.Trimesh(v, np.array(faces), process=False)
    if m.volume < 0:
        m.invert()
    return m


def leaf() -> trimesh.Trimesh:
    stations, across = 11, 5  # along the blade, across it
    ys = np.linspace(0.0, 1.0, stations)
    width = 0.36 * np.sin(np.pi * ys**0.8) ** 0.9  # zero at the stalk and the tip
    us = np.linspace(-1.0, 1.0, across)
    y, u = np.meshgrid(ys, us, indexing="ij")
    x = u * width[:, None]
    z = 0.06 * u**2 - 0.03 * np.sin(np.pi * y)  # cupped across, arched along
    v = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    faces = []
    for i in range(stations - 1):
        for j in range(across - 1):
            a, b = i * across + j, (i + 1) * across + j
            faces.append((a, a + 1, b + 1))
            faces.append((a, b + 1, b))
    m = trimesh.Trimesh(v, np.array(faces), process=False)
    return m


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for name, mesh in (("stone", stone()), ("leaf", leaf())):
        text = trimesh.exchange.obj.export_obj(mesh, include_normals=False, include_texture=False, digits=6,
                                               header=f"axialdeform bundled base mesh '{name}' (tools/make_base_meshes.py)")
        (OUT / f"{name}.obj").write_text(text)
        print(name, len(mesh.vertices), "vertices", len(mesh.faces), "faces, extents", mesh.extents.round(3))


if __name__ == "__main__":
    main()

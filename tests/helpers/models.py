"""Models built here as third-party files are built (a palm whose fronds cross its crown)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh


def palm_file(path: Path, scenery: bool = True) -> Path:
    """A palm as an artist exports it: trunk (radius 0.11, 3 units), seven fronds crossing its top
    (each a flat strip 2.4 units long, a third of it beyond the crown), and optionally a
    flat island and a water plane, as separate glTF nodes with non-ASCII names on two of them."""
    scene = trimesh.Scene()
    trunk = trimesh.creation.cylinder(radius=0.11, height=3.0, sections=10)
    trunk.apply_translation([0.0, 0.0, 1.5])
    trunk.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))  # along +y
    scene.add_geometry(trunk, geom_name="trunk", node_name="trunk")
    for k in range(7):
        az = 2 * np.pi * k / 7
        x = np.linspace(-0.85, 1.55, 25)  # starts 0.85 beyond the trunk's axis, crosses its top
        verts = np.array([[xi, 0.0, z] for xi in x for z in (-0.175, 0.175)])
        faces = np.array([[2 * i, 2 * i + 1, 2 * i + 3] for i in range(24)] + [[2 * i, 2 * i + 3, 2 * i + 2] for i in range(24)])
        frond = trimesh.Trimesh(verts, faces, process=False)  # a flat strip, as fronds are modelled
        frond.apply_transform(trimesh.transformations.rotation_matrix(0.25, [0, 0, 1]))  # rising outwards
        frond.apply_transform(trimesh.transformations.rotation_matrix(az, [0, 1, 0]))
        frond.apply_translation([0.0, 3.0, 0.0])
        scene.add_geometry(frond, geom_name=f"frond{k}" if k else "Wedel-ä", node_name=f"frond{k}" if k else "Wedel-ä")
    if scenery:
        island = trimesh.creation.cylinder(radius=4.0, height=0.3, sections=24)
        island.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))
        scene.add_geometry(island, geom_name="île", node_name="île")
        water = trimesh.creation.box(extents=[60.0, 0.01, 60.0])
        water.apply_translation([0.0, -0.1, 0.0])
        scene.add_geometry(water, geom_name="water", node_name="water")
    scene.export(str(path))
    return path


PALM = ["trunk", "Wedel-ä", *(f"frond{k}" for k in range(1, 7))]


def blended(mesh, seed: int = 3):
    """``mesh`` (of several axes) with about half its vertices blending their own chain with another axis's at a
    random weight (``AxisTree.blend``); the same axes otherwise."""
    import dataclasses

    from axialdeform.core.axes import AxisTree

    rng = np.random.default_rng(seed)
    t = mesh.tree
    v = len(t.vertex_axis)
    blend = np.stack([rng.integers(0, t.count, v), rng.random(v) * (rng.random(v) < 0.5)], axis=1)
    tree = AxisTree(t.axes, t.parents, t.vertex_axis, t.names, t.anchors, blend)
    assert tree.blend is not None and tree.digest != t.digest
    return dataclasses.replace(mesh, _axis=None, tree=tree)

"""Make the bundled low-poly tree (axialdeform/meshes/tree.glb): ONE mesh of
separate parts -- a trunk and its branches, each branch ending in a tuft of
leaves -- for several axes in a hierarchy (``load_mesh("tree", axes="parts",
axis="oriented")``: one axis per part, the trunk the root).

    python tools/make_tree.py

The trunk is a tapered tube along +y (3 units, 10 rings x 8 sides) with a
crown tuft on top; six branches leave it at different heights and azimuths,
rising outwards, each a tapered tube (6 rings) whose tip carries a flattened
icosphere tuft.  Wood and leaves are told apart by vertex colour (glTF
``COLOR_0``, linear), so each branch is one part with one material and one
axis.  A branch's first ring sits on the trunk's centre line, so its root
end is the one nearer the trunk's axis (``t = 0`` there).  The hierarchy to
load it with is ``axialdeform.core.axes.TREE_AXES`` (a test holds the two
together).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

OUT = Path(__file__).resolve().parent.parent / "axialdeform" / "meshes" / "tree.glb"
WOOD = (0.45, 0.30, 0.18, 1.0)  # sRGB-encoded vertex colours (uint8)
LEAVES = (0.32, 0.56, 0.16, 1.0)


def tube(a, b, r0: float, r1: float, rings: int = 6, sides: int = 8) -> trimesh.Trimesh:
    """A tapered tube from ``a`` (radius ``r0``) to ``b`` (``r1``), ``rings``
    rings of ``sides`` vertices, closed at the far end."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    axis = (b - a) / np.linalg.norm(b - a)
    side = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    up = np.cross(axis, side)
    s = np.linspace(0.0, 1.0, rings)
    ang = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    radius = r0 + (r1 - r0) * s
    ring = np.cos(ang)[:, None] * side + np.sin(ang)[:, None] * up  # (sides, 3)
    verts = (a + s[:, None, None] * (b - a) + radius[:, None, None] * ring[None]).reshape(-1, 3)
    faces = []
    for i in range(rings - 1):
        for j in range(sides):
            p, q = i * sides + j, i * sides + (j + 1) % sides
            faces += [[p, q, p + sides], [q, q + sides, p + sides]]
    tip = len(verts)
    verts = np.vstack([verts, b])
    last = (rings - 1) * sides
    faces += [[last + j, last + (j + 1) % sides, tip] for j in range(sides)]
    return trimesh.Trimesh(verts, np.array(faces), process=False)


def tuft(center, radius: float, squash: float = 0.7) -> trimesh.Trimesh:
    """A flattened icosphere of leaves."""
    blob = trimesh.creation.icosphere(subdivisions=1, radius=radius)
    blob.vertices[:, 1] *= squash
    blob.vertices += np.asarray(center, float)
    return blob


def coloured(pieces) -> trimesh.Trimesh:
    """Pieces ``(mesh, rgba)`` as one mesh with vertex colours."""
    meshes = []
    for mesh, rgba in pieces:
        m = mesh.copy()
        rgba8 = np.round(np.array(rgba) * 255).astype(np.uint8)  # uint8: floats would be read as 0..1
        m.visual = trimesh.visual.ColorVisuals(m, vertex_colors=np.tile(rgba8, (len(m.vertices), 1)))
        meshes.append(m)
    return trimesh.util.concatenate(meshes)


def tree_scene(branches: int = 6, seed: int = 3) -> trimesh.Scene:
    """The tree: parts ``trunk``, ``branch1``.. and ``twig1``.. (a twig grows
    from the middle of every second branch)."""
    rng = np.random.default_rng(seed)
    scene = trimesh.Scene()
    trunk = coloured([(tube([0, 0, 0], [0, 3.0, 0], 0.16, 0.07, rings=10), WOOD),
                      (tuft([0, 3.2, 0], 0.45), LEAVES)])
    scene.add_geometry(trunk, geom_name="trunk", node_name="trunk")
    heights = np.linspace(1.0, 2.6, branches)
    twigs = 0
    for k in range(branches):
        az = 2 * np.pi * (k * 0.382 + 0.1 * rng.random())  # golden-angle spread
        out = np.array([np.cos(az), 0.0, np.sin(az)])
        length = 1.3 - 0.35 * (heights[k] - 1.0)
        start = np.array([0.0, heights[k], 0.0])
        direction = 0.8 * out + np.array([0.0, 0.6, 0.0])
        end = start + length * direction
        branch = coloured([(tube(start, end, 0.06, 0.025, rings=6, sides=6), WOOD),
                           (tuft(end + 0.25 * direction, 0.3, squash=1.0), LEAVES)])
        scene.add_geometry(branch, geom_name=f"branch{k + 1}", node_name=f"branch{k + 1}")
        if k % 2 == 0:  # a twig from the branch's middle, turned sideways and up
            twigs += 1
            side = np.cross([0.0, 1.0, 0.0], out)
            root = start + 0.5 * length * direction
            tip = root + 0.5 * length * (0.7 * side + 0.7 * np.array([0.0, 1.0, 0.0]))
            twig = coloured([(tube(root, tip, 0.03, 0.015, rings=4, sides=5), WOOD),
                             (tuft(tip + 0.1 * (tip - root), 0.18, squash=1.0), LEAVES)])
            scene.add_geometry(twig, geom_name=f"twig{twigs}", node_name=f"twig{twigs}")
    return scene


def main() -> None:
    OUT.parent.mkdir(parents=True, exist_ok=True)
    tree_scene().export(OUT)
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")


if __name__ == "__main__":
    main()

"""A tree whose wood is ONE welded piece (trunk and branches unioned, as an asset pack's wood comes),
made at test time with manifold3d: the axes="skeleton" tests' model, with the branches it must find."""

from __future__ import annotations

import numpy as np

import axialdeform as ad

#: (turn about the trunk in radians, height on the trunk, length) of each branch
BRANCHES = ((0.0, 0.9, 1.0), (2.1, 1.2, 0.9), (4.2, 1.5, 0.8), (1.0, 1.75, 0.7))
TRUNK = ((0.0, 0.0, 0.0), (0.0, 2.6, 0.0), 0.12)


def branch_tips() -> np.ndarray:
    """(4, 3): where each branch ends."""
    tips = []
    for turn, height, length in BRANCHES:
        d = np.array([np.cos(turn) * 0.8, 0.6, np.sin(turn) * 0.8])
        tips.append(np.array([0.0, height, 0.0]) + length * d / np.linalg.norm(d))
    return np.array(tips)


def _limb(a, b, radius: float, step: float):
    import manifold3d as mf

    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    d = b - a
    length = float(np.linalg.norm(d))
    z = d / length
    axis = np.cross([0.0, 0.0, 1.0], z)
    if np.linalg.norm(axis) < 1e-9:
        turn = np.eye(3)
    else:
        axis /= np.linalg.norm(axis)
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        angle = np.arccos(np.clip(z[2], -1.0, 1.0))
        turn = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
    tube = mf.Manifold.cylinder(length, radius, radius, 16).refine_to_length(step)
    return tube.transform(np.hstack([turn, a[:, None]])) + mf.Manifold.sphere(radius, 16).refine_to_length(step).translate(tuple(b))


def one_piece_tree(step: float = 0.05) -> ad.BaseMesh:
    """The trunk and :data:`BRANCHES` as one closed, welded surface (about 7 000 triangles)."""
    a, b, r = TRUNK
    wood = _limb(a, b, r, step)
    for (_turn, height, _length), tip in zip(BRANCHES, branch_tips()):
        wood = wood + _limb((0.0, height, 0.0), tip, 0.05, step)
    m = wood.to_mesh()
    positions = np.asarray(m.vert_properties, dtype=np.float32)[:, :3]
    return ad.BaseMesh.from_arrays(positions, np.asarray(m.tri_verts, dtype=np.uint32), name="one-piece tree")


def crowned_tree(step: float = 0.05) -> ad.BaseMesh:
    """:func:`one_piece_tree` with a crown blob (a sphere of radius 0.3) on each branch, the branch's tip just
    inside it, as an asset pack models crowns, and eight bark marks (small plates just off the trunk's surface)."""
    import trimesh

    wood = one_piece_tree(step)
    pieces = []
    a = np.array(TRUNK[0])
    for (_turn, height, _length), tip in zip(BRANCHES, branch_tips()):
        d = tip - np.array([a[0], height, a[2]])
        blob = trimesh.creation.icosphere(subdivisions=3, radius=0.3)
        blob.apply_translation(tip + 0.25 * d / np.linalg.norm(d))  # the branch ends just inside it
        pieces.append(blob)
    for k in range(8):
        turn, height = 2 * np.pi * k / 8, 0.3 + 0.2 * k
        plate = trimesh.creation.box(extents=[0.01, 0.08, 0.05])
        plate.apply_translation([0.125, height, 0.0])
        plate.apply_transform(trimesh.transformations.rotation_matrix(turn, [0, 1, 0]))
        pieces.append(plate)
    extra = trimesh.util.concatenate(pieces)
    positions = np.vstack([wood.positions, np.asarray(extra.vertices, dtype=np.float32)])
    faces = np.vstack([wood.faces, np.asarray(extra.faces) + wood.vertex_count]).astype(np.uint32)
    return ad.BaseMesh.from_arrays(positions, faces, name="crowned tree")


def pierced_tree(step: float = 0.05) -> ad.BaseMesh:
    """:func:`one_piece_tree` with one crown blob (a sphere) that the first two branches both pierce: their tips
    lie inside it, 0.1 from its surface."""
    import trimesh

    wood = one_piece_tree(step)
    a, b = branch_tips()[:2]
    blob = trimesh.creation.icosphere(subdivisions=3, radius=float(np.linalg.norm(a - b)) / 2 + 0.1)
    blob.apply_translation((a + b) / 2)
    positions = np.vstack([wood.positions, np.asarray(blob.vertices, dtype=np.float32)])
    faces = np.vstack([wood.faces, np.asarray(blob.faces) + wood.vertex_count]).astype(np.uint32)
    return ad.BaseMesh.from_arrays(positions, faces, name="pierced tree")

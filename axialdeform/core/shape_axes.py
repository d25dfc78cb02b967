"""Which axes a model gets from its own shape (``axes="skeleton"`` and ``axes="auto"``): the skeleton's
(:mod:`axialdeform.core.skeleton`), or its parts' when they are its limbs; cached by the mesh's fingerprint."""

from __future__ import annotations

import numpy as np

from .axes import AxisTree, tree_from_parts
from .errors import MeshError
from .skeleton import MIN_BRANCH, RULES_DIGEST, SKELETON_VERSION, skeleton_branches, skeleton_tree, tree_from_branches

__all__ = ["shape_tree", "parts_are_limbs", "skeleton_and_branches"]


def shape_tree(mesh, rule: str = "skeleton", frame="auto", up: int = 1) -> AxisTree:
    """``axes="skeleton"`` or ``axes="auto"`` (``BaseMesh.with_axes``): :func:`skeleton_tree` with its
    defaults, cached by the mesh's fingerprint (``core.io.axes_cache``); for ``"auto"``, ``axes="parts"``
    (each axis ``frame``) instead when the mesh's parts are its limbs (:func:`parts_are_limbs`; the choice
    cached too)."""
    from .io.axes_cache import cached_tree  # core.io reads meshes: imported once core.mesh is

    key = _skeleton_key(up)
    tree = cached_tree(mesh, key, lambda: skeleton_tree(mesh, up=up))
    if rule != "auto" or sum(1 for p in mesh.parts if p.count) < 2:
        return tree
    decide = lambda: tree_from_parts(mesh, frame, up) if parts_are_limbs(mesh, tree, up) else tree  # noqa: E731
    return cached_tree(mesh, f"auto-{frame}-{key}", decide) if isinstance(frame, str) else decide()


def _skeleton_key(up: int) -> str:
    """The cache key of ``axes="skeleton"``'s tree: the rules' version and digest, the branch threshold, up."""
    return f"skeleton{SKELETON_VERSION}-{RULES_DIGEST}-{MIN_BRANCH:g}-{up}"


def skeleton_and_branches(mesh, up: int = 1) -> tuple[AxisTree, list[dict]]:
    """``axes="skeleton"``'s tree of ``mesh`` and the branches it is made of (an axes file's, to edit by hand),
    the skeleton computed once: the tree is :func:`tree_from_branches` of the branches, read from the cache
    when it holds it and cached as ``axes="skeleton"`` caches it otherwise."""
    from .io.axes_cache import cached_tree

    branches = skeleton_branches(mesh, up=up)
    return cached_tree(mesh, _skeleton_key(up), lambda: tree_from_branches(mesh, branches, up=up)), branches


def parts_are_limbs(mesh, tree: AxisTree, up: int = 1) -> bool:
    """Whether ``mesh``'s parts are its limbs (``axes="auto"`` takes ``"parts"``): no part branches.  A part branches
    when the whole model's skeleton ``tree`` puts it on several axes and it holds the trunk's (a one-piece wood)
    or, skeletonized alone, is more than one branch; a palm's frond hung on the trunk where it crosses the crown,
    and split there, is one branch alone: a limb."""
    # a carried piece's points blend two axes (AxisTree.blend): they do not make their part a branching one
    whole = np.ones(len(tree.vertex_axis), bool) if tree.blend is None else tree.blend[:, 1] == 0
    for p in (p for p in mesh.parts if p.count):
        used = np.unique(mesh.faces[p.start:p.start + p.count])
        own = np.unique(tree.vertex_axis[used[whole[used]]])
        try:
            if len(own) > 1 and (0 in own or len(skeleton_branches(mesh.with_parts([p.name]), up=up)) > 1):
                return False
        except MeshError:  # a part with no skeleton of its own: the whole model's stands
            return False
    return True

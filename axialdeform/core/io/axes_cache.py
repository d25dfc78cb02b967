"""The cache of axes found from a model's shape (``axes="skeleton"``, core/skeleton.py): one small
``.npz`` a mesh, named by its fingerprint and the rules' version, in ``$AXIALDEFORM_CACHE`` (default
``$XDG_CACHE_HOME/axialdeform/axes``, else ``~/.cache/axialdeform/axes``; ``AXIALDEFORM_CACHE=off``
keeps nothing).  A cache file that cannot be read, or that does not fit the mesh, is computed again
and written anew (atomically); a cache folder that cannot be written leaves the result uncached."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from ..axes import AxisTree
from ..axis import ControlAxis
from ..errors import AxialDeformError
from .atomic import atomic_write_bytes

__all__ = ["cache_folder", "cached_tree"]

#: the largest cache file read (a tree of 64 axes over a few million vertices is well below)
MAX_BYTES = 64 << 20


def cache_folder() -> Path | None:
    """Where the axes cache lives, or None when ``AXIALDEFORM_CACHE=off``."""
    given = os.environ.get("AXIALDEFORM_CACHE")
    if given is not None:
        return None if given.strip().lower() in ("", "off", "0", "none") else Path(given)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "axialdeform" / "axes"


def _tree_bytes(tree: AxisTree) -> bytes:
    out = io.BytesIO()
    np.savez(out, frames=np.array([a.matrix for a in tree.axes], dtype=np.float64),
             lo=np.array([a.lo for a in tree.axes]), length=np.array([a.length for a in tree.axes]),
             center=np.array([a.center for a in tree.axes], dtype=np.float64), parents=np.array(tree.parents),
             anchors=np.array(tree.anchors), names=np.array(tree.names, dtype=str), vertex_axis=tree.vertex_axis,
             **({} if tree.blend is None else {"blend": tree.blend}))
    return out.getvalue()


def _read_tree(path: Path, vertex_count: int) -> AxisTree | None:
    try:
        if path.stat().st_size > MAX_BYTES:
            return None
        with np.load(path, allow_pickle=False) as z:
            k = len(z["lo"])
            axes = tuple(ControlAxis(index=-1, lo=float(z["lo"][i]), length=float(z["length"][i]),
                                     center=tuple(float(c) for c in z["center"][i]),
                                     frame=tuple(map(tuple, z["frames"][i])), kind="matrix") for i in range(k))
            va = np.asarray(z["vertex_axis"])
            if va.shape != (vertex_count,):
                return None
            return AxisTree(axes, tuple(int(p) for p in z["parents"]), va, tuple(str(n) for n in z["names"]),
                            tuple(float(t) for t in z["anchors"]), np.asarray(z["blend"]) if "blend" in z else None)
    except (OSError, ValueError, KeyError, TypeError, IndexError, AxialDeformError, EOFError):
        return None  # not there, or not ours: computed again


def cached_tree(mesh, key: str, compute) -> AxisTree:
    """``compute()``'s tree for ``mesh``, read from the cache when it holds one for this mesh
    (its fingerprint) and ``key`` (the rule and its settings), else computed and kept there."""
    folder = cache_folder()
    if folder is None:
        return compute()
    path = folder / f"{mesh.fingerprint.hex()[:32]}-{key}.npz"
    tree = _read_tree(path, mesh.vertex_count)
    if tree is not None:
        return tree
    tree = compute()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, _tree_bytes(tree))
    except (OSError, AxialDeformError):
        pass  # a cache that cannot be written: the tree is still right
    return tree

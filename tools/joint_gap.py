"""How far a tree's joints open: each child part's own bend near where it meets its parent.

    python3 tools/joint_gap.py MESH [--axes parts|FILE.toml] [--parts A,B] [--bend 0.3] [-n 200] [--seed 1]

For every child axis ``j``: the joint ``J`` is the point of ``j``'s axis at its anchor (where
its part meets its parent, ``AxisTree.anchors``); ``r`` is the parent part's radius (the median
distance of its vertices from its axis line); the vertices of part ``j`` within ``2 r`` of ``J``
are the joint's.  Each moves by its own axis's bend ``|D_j(t_j(V))|`` (and by its ancestors',
which move the parent with it: that does not open the joint).  Over ``-n`` random instances
with every child level bent by ``--bend`` (a fraction of the child's length), the tool prints the
median and the largest of that motion in units of ``r``, for the offsets drawn as before (``d₁ =
0``) and as now (clamped at the anchor, ``core.axes.child_offsets``), from the same random
numbers.  The goal: median at most 0.25 ``r`` at a bend of 0.3.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import axialdeform as ad
from axialdeform.core.axes import bernstein4, child_offsets


def own_bend(axis, positions: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """``|D(t(V))|`` of ``positions`` (v, 3) for ``offsets`` (n, 5, 2): (n, v)."""
    local = positions.astype(np.float64) @ np.asarray(axis.matrix, dtype=np.float64).T
    t = np.clip((local[:, 0] - axis.lo) / axis.length, 0.0, 1.0)
    b, _ = bernstein4(t)  # (v, 5)
    return np.linalg.norm(np.einsum("vi,nic->nvc", b, offsets), axis=-1)


def radius(axis, positions: np.ndarray) -> float:
    local = positions.astype(np.float64) @ np.asarray(axis.matrix, dtype=np.float64).T
    mid = np.asarray(axis.center if hasattr(axis, "center") else np.zeros(3), dtype=np.float64)
    line = mid @ np.asarray(axis.matrix, dtype=np.float64).T  # the axis line in local coordinates
    return float(np.median(np.linalg.norm(local[:, 1:] - line[1:], axis=1)))


def axis_distance(mesh, ids: np.ndarray) -> np.ndarray:
    """(len(ids),): each vertex's distance from its own axis's line -- the LOCAL radius of the part there."""
    tree = mesh.tree
    out = np.empty(len(ids))
    for k in np.unique(tree.vertex_axis[ids]):
        mine = tree.vertex_axis[ids] == k
        m = np.asarray(tree.axes[k].matrix, dtype=np.float64)
        local = mesh.positions[ids[mine]].astype(np.float64) @ m.T
        line = np.asarray(tree.axes[k].center, dtype=np.float64) @ m.T
        out[mine] = np.linalg.norm(local[:, 1:] - line[1:], axis=1)
    return out


#: two pieces touch where a vertex of one lies within this fraction of the other's local radius of it
TOUCH = 0.25


def contact_gaps(mesh, bend: float, count: int, seed: int, wind=None, time: float = 0.7, pairs_from=None) -> dict:
    """Where two pieces of the mesh touch (welded by position; a vertex of one within :data:`TOUCH` of the
    other's local radius of a vertex of the other), how far apart the bent pair moves, in units of that
    local radius: ``{"pairs", "median", "p95", "max"}`` over ``count`` instances bent by ``bend`` on every
    level (and pushed by ``wind`` at ``time``).  ``pairs_from``: the mesh whose axes give the local radius (the
    same mesh bound without blends, so that the pairs and units do not depend on the binding measured)."""
    from scipy.spatial import cKDTree

    from axialdeform.core.skeleton import pieces, weld
    from axialdeform.core.wind import apply_wind

    points, faces, inverse = weld(mesh.positions, mesh.faces)
    piece = pieces(len(points), faces)[inverse]
    out = {"pairs": 0, "median": 0.0, "p95": 0.0, "max": 0.0}
    near = cKDTree(mesh.positions.astype(np.float64))
    pairs = []
    for a in range(mesh.vertex_count):  # a tool, not a hot path: the pairs of a few thousand vertices
        for b in near.query_ball_point(mesh.positions[a], r=float(0.05 * mesh.axis.length)):
            if piece[b] != piece[a]:
                pairs.append((a, b))
    if not pairs:
        return out
    pairs = np.array(pairs)
    rest = np.linalg.norm(mesh.positions[pairs[:, 0]] - mesh.positions[pairs[:, 1]], axis=1)
    local = axis_distance(pairs_from or mesh, pairs[:, 1])
    touch = (rest <= TOUCH * local) & (local > 0)
    pairs, rest, local = pairs[touch], rest[touch], local[touch]
    if not len(pairs):
        return out
    params = ad.random_params(mesh, count, seed=seed, variation=ad.Variation(bend=(bend,) * mesh.tree.depth.max(initial=0) + (bend,)))
    if wind is not None:
        params = apply_wind(wind, mesh.tree, params, time)
    bent, _ = ad.deform(mesh, params)
    gap = np.abs(np.linalg.norm(bent[:, pairs[:, 0]] - bent[:, pairs[:, 1]], axis=2) - rest) / local
    return {"pairs": int(len(pairs)), "median": float(np.median(gap)), "p95": float(np.percentile(gap, 95)),
            "max": float(gap.max())}


def joint_figures(mesh, bend: float, count: int, seed: int) -> list[dict]:
    tree = mesh.tree
    rng = np.random.default_rng(seed)
    uniform = rng.random((count, tree.count - 1, 5, 2))
    new = child_offsets(tree, (bend,), uniform)
    old = (2.0 * uniform - 1.0) * np.array([bend * a.length for a in tree.axes[1:]])[None, :, None, None]
    old[:, :, 0] = 0.0
    rows = []
    for j in range(1, tree.count):
        axis, parent = tree.axes[j], tree.axes[tree.parents[j]]
        mine = mesh.positions[tree.vertex_axis == j]
        r = radius(parent, mesh.positions[tree.vertex_axis == tree.parents[j]])
        joint = np.asarray(axis.control_points[0], dtype=np.float64) + tree.anchors[j] * (
            np.asarray(axis.control_points[-1], dtype=np.float64) - np.asarray(axis.control_points[0], dtype=np.float64))
        near = mine[np.linalg.norm(mine - joint, axis=1) <= 2 * r]
        if not len(near) or r <= 0:
            rows.append({"axis": tree.names[j], "anchor": tree.anchors[j], "radius": r, "vertices": 0})
            continue
        before = own_bend(axis, near, old[:, j - 1]) / r
        after = own_bend(axis, near, new[:, j - 1]) / r
        rows.append({"axis": tree.names[j], "anchor": tree.anchors[j], "radius": r, "vertices": len(near),
                     "before": (float(np.median(before)), float(before.max())),
                     "after": (float(np.median(after)), float(after.max()))})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh")
    ap.add_argument("--axes", default="parts")
    ap.add_argument("--parts", default=None, help="comma-separated parts to keep (load_mesh parts=)")
    ap.add_argument("--axis", default="oriented", help="the frame rule of each part's axis (default: %(default)s)")
    ap.add_argument("--bend", type=float, default=0.3)
    ap.add_argument("-n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-blend", action="store_true", help="with --axes skeleton: measure the binding that carries "
                    "each piece whole on one branch (no AxisTree.blend), on the same pairs")
    args = ap.parse_args(argv)
    kwargs = {"parts": args.parts.split(",")} if args.parts else {}
    mesh = ad.load_mesh(args.mesh, axes=args.axes, axis=args.axis, **kwargs)
    if mesh.tree is None:
        print(f"{args.mesh}: one axis ({mesh.axis.describe()}): no joints and no pieces on other axes to measure")
        return 0
    print(f"{args.mesh}: {mesh.tree.describe()}")
    # where pieces touch and the parent's local radius there: from each piece bound whole (no blends), so the
    # pairs and units do not depend on the binding measured
    whole = None
    if args.axes == "skeleton":
        from axialdeform.core.skeleton import skeleton_tree

        plain = ad.load_mesh(args.mesh, axis=args.axis, **kwargs)
        whole = plain.with_axes(skeleton_tree(plain, blend=False))
        if args.no_blend:
            mesh = whole
            print("measured: each carried piece whole on one branch (--no-blend)")
    for label, wind in (("still", None), ("in the wind", ad.Wind(direction=(1.0, 0.0, 0.4), strength=0.3, gustiness=0.5))):
        c = contact_gaps(mesh, args.bend, args.n, args.seed, wind, pairs_from=whole)
        print(f"where pieces touch ({label}): {c['pairs']} vertex pairs, gap median {c['median']:.3f}, 95th percentile "
              f"{c['p95']:.3f}, largest {c['max']:.3f} (x the local radius)")
    rows = joint_figures(mesh, args.bend, args.n, args.seed)
    print("| child axis | anchor t | parent radius | joint vertices | before: median / max (x r) | "
          "now: median / max (x r) |\n|---|---|---|---|---|---|")
    for r in rows:
        if not r["vertices"]:
            print(f"| {r['axis']} | {r['anchor']:.2f} | {r['radius']:.3g} | 0 | - | - |")
            continue
        print(f"| {r['axis']} | {r['anchor']:.2f} | {r['radius']:.3g} | {r['vertices']} | "
              f"{r['before'][0]:.2f} / {r['before'][1]:.2f} | {r['after'][0]:.2f} / {r['after'][1]:.2f} |")
    measured = [r for r in rows if r["vertices"]]
    if measured:
        print(f"all joints (median of the medians): before {np.median([r['before'][0] for r in measured]):.2f} r, "
              f"now {np.median([r['after'][0] for r in measured]):.2f} r (bend {args.bend}, {args.n} instances)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

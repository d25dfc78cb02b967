"""The marks of an example: what each object carries beside its place -- its size, its turn about up and how
far it leans toward the ground's normal, and,
where the example holds the library's records (a parameter file, a scene file's layer, this library's glTF), its
bend, twist, taper and tint -- learned as the numbers of a generated layer's recipe (docs/learn.md, "The marks").
Pure numpy: no GL here.

The recipe draws each mark from uniform numbers of the instance (``core/generate.py``): the offsets
``d = bend L (2u - 1)`` (then all shifted alike, so the anchor stays put), ``tw = twist (2u - 1)``,
``tp = taper u`` and the tint ``color (1 - amount (u_r + hue (u_c - u_r)))``.  Each is fitted by its moments,
in forms that a shift shared by the five control points (the anchor's, or the canonical zero mean) leaves alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .generate import MAX_BEND
from .record import OFFSETS, TAPER, TINT, TWIST, WIDTHS, split_record, tree_shape

__all__ = ["Marks", "learn_marks", "standard_records", "bend_amplitude", "joint_amplitude", "offset_differences",
           "tint_of_records", "turn_and_up", "lean_amount", "LEAN_FLOOR"]

#: a learned lean below this fraction of the ground's slope is no lean: the recipe's ``align_to_normal`` is left
#: at its default 0 (objects stand upright)
LEAN_FLOOR = 0.01


@dataclass(frozen=True)
class Marks:
    """The marks of one kind, as a recipe draws them.

    Attributes
    ----------
    scale : (2,) float or None
        The sizes as scales, median 1: the smallest and the largest (None: no sizes).
    scale_quartiles, scale_octiles : (3,) and (4,) float, or None
        The scales at 1/4, 1/2, 3/4 and at 1/8, 3/8, 5/8, 7/8: the generator draws a scale piecewise linear
        through these nine knots.
    yaw : (2,) float
        The turn about up, [lo, hi] radians ([0, 2 pi] without turns).
    align : float or None
        How far the objects lean toward the ground's normal, a fraction of its slope (the recipe's
        ``align_to_normal``; None: no turns, or level ground under every object).
    bend : float or None
        The offsets' amplitude ``A`` in the records' own units: offsets uniform in ``[-A, A]`` (the recipe's
        ``bend`` is ``A / L``, L the layer's mesh's axis length; None: the example has no records).
    child_bends : tuple of float or None
        A tree's records: each child axis's amplitude ``A_j`` likewise (the recipe's ``bend`` of its level is
        ``A_j / L_j``, on a mesh of as many axes; None: records of one axis).
    twist, taper : float or None
        Twists uniform in ``[-twist, twist]`` radians, tapers in ``[0, taper]`` (None: no extended records).
    tint : (amount, (r, g, b), hue) or None
        The recipe's ``tint``, ``tint_color`` and ``tint_hue`` (None: no tinted records).
    record_scale : float or None
        The median size of an example of records (None: no records, or no sizes): its sizes are scales already
        (the records' own, or a glTF's under its nodes' transforms), so this is the scale of an object of the
        median size.
    """

    scale: tuple | None = None
    scale_quartiles: tuple | None = None
    scale_octiles: tuple | None = None
    yaw: tuple = (0.0, 2.0 * math.pi)
    bend: float | None = None
    child_bends: tuple | None = None
    twist: float | None = None
    taper: float | None = None
    tint: tuple | None = None
    record_scale: float | None = None
    align: float | None = None

    def recipe(self, mesh=None) -> dict:
        """The recipe's keys of these marks (``scale`` and its quantiles, ``yaw``, ``align_to_normal`` (from
        :data:`LEAN_FLOOR` up), ``twist``, ``taper``, ``tint``, ``tint_color``, ``tint_hue``, and ``bend`` when
        ``mesh``, the layer's BaseMesh, is given: ``A / L`` -- or, for a tree's records on a mesh of as many axes,
        one amplitude a level of its hierarchy, the root mean square of ``A_j / L_j`` over its axes)."""
        keys: dict = {"yaw": list(self.yaw)}
        if self.scale is not None:
            keys["scale"] = list(self.scale)
        if self.scale_quartiles is not None:
            keys["scale_quartiles"] = list(self.scale_quartiles)
            keys["scale_octiles"] = list(self.scale_octiles)
        if self.bend is not None and mesh is not None:
            keys["bend"] = _level_bends(self.bend, self.child_bends, mesh)
        if self.align is not None and self.align >= LEAN_FLOOR:
            keys["align_to_normal"] = float(self.align)
        if self.twist:  # none or 0: the recipe's own default, 0
            keys["twist"] = float(self.twist)
        if self.taper:
            keys["taper"] = float(self.taper)
        if self.tint is not None:
            amount, color, hue = self.tint
            keys.update(tint=float(amount), tint_color=[float(c) for c in color], tint_hue=float(hue))
        return keys


def _level_bends(bend: float, children: tuple | None, mesh) -> float | list:
    """The recipe's ``bend`` of amplitudes ``bend`` (axis 0) and ``children`` (the child axes') on ``mesh``: one
    number, or one a level of its hierarchy where the records have its child axes."""
    root = min(bend / mesh.axis.length, MAX_BEND)
    tree = getattr(mesh, "tree", None)
    if not children or tree is None or len(tree.axes) != len(children) + 1:
        return float(root)
    depth = np.asarray(tree.depth[1:])
    ratio = np.asarray(children) / np.array([a.length for a in tree.axes[1:]])
    levels = [root] + [float(min(math.sqrt(np.mean(ratio[depth == d] ** 2)), MAX_BEND)) for d in range(1, int(depth.max()) + 1)]
    return [float(b) for b in levels]


def standard_records(params: np.ndarray) -> np.ndarray:
    """Axis 0's standard record ``(n, 16|19|22)`` float64 of records of any number of axes (a tree's child axes'
    offsets left out: they stand between axis 0's offsets and its position); ValueError for a width that is no
    record's."""
    params = np.asarray(params, np.float64)
    axes, _ = tree_shape(params.shape[1])
    return split_record(params, axes)[0].astype(np.float64) if axes > 1 else params


def offset_differences(offsets: np.ndarray) -> np.ndarray:
    """The differences ``d_p - d_q`` (p < q) of each instance's five control points' offsets ``(n, 10)``, each
    component: ``(n, 20)``.  A shift shared by the five (the anchor kept in place, the canonical zero mean)
    cancels, so they are the generator's draws' differences whatever shift was made."""
    d = np.asarray(offsets, np.float64).reshape(-1, 5, 2)
    p, q = np.triu_indices(5, 1)
    return (d[:, p] - d[:, q]).reshape(len(d), -1)


def bend_amplitude(offsets: np.ndarray) -> float:
    """``A`` of offsets ``(n, 10)`` drawn uniform in ``[-A, A]``: two such draws differ by ``2 A^2 / 3`` in
    mean square, so ``A = sqrt(3/2 mean (d_p - d_q)^2)`` over the pairs of control points."""
    return float(math.sqrt(1.5 * np.mean(offset_differences(offsets) ** 2)))


def joint_amplitude(offsets: np.ndarray) -> float:
    """``A`` of a child axis's offsets ``(n, 5, 2)``: drawn uniform in ``[-A, A]``, then projected orthogonally
    onto the offsets that keep its joint closed, value and slope (``core/axes.py``'s ``anchor_projection``, of
    rank 3 of 5), so their squares sum to ``A^2 trace(P) / 3 = A^2`` a component in the mean:
    ``A = sqrt(5 mean d^2)``."""
    return float(math.sqrt(5.0 * np.mean(np.asarray(offsets, np.float64) ** 2)))


def tint_of_records(tint: np.ndarray) -> tuple[float, tuple, float]:
    """The recipe's ``(tint, tint_color, tint_hue)`` of tints ``(n, 3)``: the colour is each channel's brightest;
    each object's tint over it, ``r_c = 1 - amount m_c``, has the first channel's ``m`` uniform (mean 1/2: the
    amount is twice the mean shortfall) and the others ``m_r + hue (u_c - u_r)`` (``var(r_c - r_r) = amount^2
    hue^2 / 6``).  Amount and hue within [0, 1]; a colour of one value gives amount 0."""
    t = np.clip(np.asarray(tint, np.float64), 0.0, None)
    color = np.clip(t.max(axis=0), 0.0, 1.0)
    lit = color > 0
    if not lit.any():
        return 0.0, tuple(float(c) for c in color), 0.0
    ratio = t[:, lit] / color[lit]
    amount = float(np.clip(2.0 * (1.0 - ratio[:, 0].mean()), 0.0, 1.0))
    hue = 0.0
    if amount > 1e-6 and ratio.shape[1] > 1:
        spread = np.mean(np.var(ratio[:, 1:] - ratio[:, :1], axis=0))
        hue = float(np.clip(math.sqrt(6.0 * spread) / amount, 0.0, 1.0))
    return amount, tuple(float(c) for c in color), hue


def turn_and_up(rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each object's turn about up and its up, of its rotation ``rot`` (n, 3, 3) (columns: its x, y, z in the
    world; any scale of a column is taken off): ``up`` (n, 3) is its y; the turn ``yaw`` (n,) radians is
    measured with its lean undone -- the least rotation that takes the world's up to ``up`` (about their cross
    product), as the generator leans an object turned about up toward the ground's normal -- so a leaning
    object's turn is the one it was turned by before it leant."""
    r = np.asarray(rot, np.float64)
    r = r / np.maximum(np.linalg.norm(r, axis=1, keepdims=True), 1e-300)
    up, z = r[:, :, 1], r[:, :, 2]
    k = np.column_stack([up[:, 2], np.zeros(len(up)), -up[:, 0]])  # the world's up x up: the lean's axis
    sin = np.linalg.norm(k, axis=1)
    k = k / np.where(sin > 0, sin, 1.0)[:, None]
    cos = up[:, 1]
    # z turned back about k by the lean's angle (Rodrigues' formula, the angle negated)
    back = (z * cos[:, None] - np.cross(k, z) * sin[:, None]
            + k * np.einsum("ij,ij->i", k, z)[:, None] * (1.0 - cos)[:, None])
    return np.arctan2(back[:, 0], back[:, 2]), up


def lean_amount(up: np.ndarray, normal: np.ndarray) -> float | None:
    """The recipe's ``align_to_normal`` of objects whose up is ``up`` (n, 3), standing on ground of unit
    normals ``normal`` (n, 3): the generator tilts an object toward its ground's normal by ``a theta``
    (``theta = atan2(|n_xz|, n_y)``, the ground's slope), so each object's tilt toward the normal's side,
    ``phi = atan2(up . n_xz / |n_xz|, up_y)``, is fitted as ``a theta`` by least squares (``a`` within [0, 1]).
    None where the ground is level under every object (objects of no finite turn are left out)."""
    up, n = np.asarray(up, np.float64), np.asarray(normal, np.float64)
    ok = np.isfinite(up).all(axis=1) & np.isfinite(n).all(axis=1) & (np.linalg.norm(up, axis=1) > 0)
    up, n = up[ok], n[ok]
    up = up / np.linalg.norm(up, axis=1, keepdims=True)
    side = np.linalg.norm(n[:, [0, 2]], axis=1)
    theta = np.arctan2(side, n[:, 1])
    if not (theta > 1e-6).any():
        return None
    toward = np.einsum("ij,ij->i", up[:, [0, 2]], n[:, [0, 2]]) / np.where(side > 0, side, 1.0)
    phi = np.arctan2(toward, up[:, 1])
    return float(np.clip(np.sum(phi * theta) / np.sum(theta * theta), 0.0, 1.0))


def learn_marks(size: np.ndarray | None, yaw: np.ndarray | None, records: np.ndarray | None,
                up: np.ndarray | None = None, normal: np.ndarray | None = None) -> Marks:
    """The :class:`Marks` of one kind's objects: ``size`` (n,) (any unit, or None), ``yaw`` (n,) radians (or
    None), ``records`` (n, 10 K + 6 (+3, +6)): the library's records, of any number of axes (or None), and
    ``up`` (n, 3) with the ground's ``normal`` (n, 3) under each object (or None): how far they lean."""
    scale = quartiles = octiles = None
    if size is not None and len(size):
        s = np.asarray(size, np.float64) / np.median(size)  # median 1; the generator draws through nine quantiles
        q = [float(x) for x in np.quantile(s, np.arange(9) / 8)]
        scale, quartiles, octiles = (q[0], q[8]), (q[2], q[4], q[6]), (q[1], q[3], q[5], q[7])
    turn = (0.0, 2.0 * math.pi)
    if yaw is not None and len(yaw) > 1:
        a = np.mod(yaw, 2.0 * math.pi)
        if np.ptp(a) < math.pi:  # turned one way, within half a turn: that range
            turn = (float(a.min()), float(a.max()))
    bend = children = twist = taper = tint = record_scale = None
    if records is not None and len(records):
        full = np.asarray(records, np.float64)
        r, axes = standard_records(full), tree_shape(full.shape[1])[0]
        bend = bend_amplitude(r[:, OFFSETS])
        if axes > 1:  # a tree's child axes: each one's amplitude
            child = split_record(full, axes)[1].astype(np.float64)  # (n, K - 1, 5, 2)
            children = tuple(joint_amplitude(child[:, j]) for j in range(axes - 1))
        if size is not None and len(size):
            record_scale = float(np.median(size))
        if r.shape[1] >= WIDTHS[1]:
            twist = float(math.sqrt(3.0 * np.mean(r[:, TWIST] ** 2)))
            taper = float(np.clip(2.0 * np.mean(r[:, TAPER]), 0.0, 0.999))
        if r.shape[1] >= WIDTHS[2]:
            tint = tint_of_records(r[:, TINT])
    align = None if up is None or normal is None or not len(up) else lean_amount(up, normal)
    return Marks(scale, quartiles, octiles, turn, bend, children, twist, taper, tint, record_scale, align)

"""Scatter instances ON a surface: area-uniform, with a minimum spacing and a density map.

``scatter(surface, mesh, n, ...)`` returns ``(n, 16) float32`` parameters (or
``(n, 19)`` with a per-instance scale, the extended layout ``... s tw tp``).

* **Surface**: a mesh file (a terrain), a grey height-map image (Pillow), a
  ``trimesh.Trimesh``, or a 2-D array of heights in [0, 1].  Only its faces
  that face up (normal · up > 0) receive instances.
* **Area-uniform**: candidates are drawn as ``trimesh.sample.sample_surface``
  draws them weighted by face area -- the same points for the same seed --
  but gathering only the picked faces (:meth:`Surface.sample`: a height map
  of 1 500 x 1 500 pixels stays within a few hundred MB).
* **Minimum spacing D** (Poisson disk): the candidates, in their random order,
  are kept greedily -- a candidate is kept when no earlier kept one lies within
  D (3-D distance) -- which is dart throwing.  It is computed without a Python
  loop per candidate: the conflicting pairs come from a KD-tree
  (``scipy.spatial.cKDTree.query_pairs``) and the greedy result is found
  in a few vectorized rounds (a candidate is decided *in* once every earlier
  neighbour is decided *out*; this gives exactly the sequential result).
  Rounds of fresh candidates fill the gaps until ``n`` are kept or the
  surface is full.
* **Density map**: a grey image over the surface's bounding box: columns along
  the first ground axis (+x for ``up="y"``), rows along the second (+z), the
  top row at the smallest coordinate; a candidate survives with probability
  equal to its pixel's grey level (black = none, white = all).
* **Anchor**: which point of the base mesh sits on the surface point:
  ``bottom`` (centre of the bounding-box face at the lowest ``up``
  coordinate), ``center`` (bounding-box centre) or ``origin`` (the model's
  origin: ``p`` is exactly the surface point).  The offsets of every instance
  are shifted (a shift shared by all five control points) so that the axis
  does not move at the anchor: the bent shape still stands on its point.
* **Orientation**: a random turn about the up axis, then a tilt of the up
  axis towards the surface normal by the fraction ``align_to_normal``
  (``T · Rot(up, φ)``, which is the tilt followed by a turn about the tilted
  axis: ``Rot(T up, φ) · T``); stored as angles of ``R = Rz·Ry·Rx``
  (``core.transforms``).

Seeded: one PCG64 stream; the same arguments and seed give the same bytes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .axes import child_offsets, droop_offsets, sag_offsets
from .axis import AXIS_NAMES
from .deform import bernstein
from .errors import ScatterError, TooFewError
from .io.mesh import load_mesh
from .mesh import BaseMesh, anchor_point
from .options import warn_field_keywords
from .recipe import ANCHORS
from .record import (
    ANGLES,
    EXTENDED_WIDTH,
    OFFSETS,
    POSITION,
    SCALE,
    TAPER,
    TINT,
    TWIST,
    WIDTHS,
    Instances,
    join_record,
)
from .surface import density_at, load_density, load_surface
from .transforms import angles_from_matrices, matrices_from_rotation_vectors
from .variation import Variation, tint_of

__all__ = ["scatter", "Placement", "ANCHORS", "poisson_greedy"]

#: most candidates drawn in one round (bounds memory: about 200 bytes each)
MAX_CANDIDATES = 4_000_000
#: most instances one call places (76 bytes each as 19 float32)
MAX_INSTANCES = 10_000_000
#: rounds of fresh candidates before giving up on reaching n
MAX_ROUNDS = 12


def poisson_greedy(points: np.ndarray, radius: float, fixed: np.ndarray | None = None) -> np.ndarray:
    """Greedy dart throwing, vectorized: which of ``points`` to keep.

    points : (k, 3) float64 -- candidates in priority order.
    fixed : (m, 3) float64 or None -- points already kept (they win over every candidate).
    Returns (k,) bool: candidate ``i`` is kept iff no point of ``fixed`` and no
    kept candidate ``j < i`` lies closer than ``radius``.  Same result as the
    sequential loop; found in rounds over the conflict pairs of a KD-tree.
    """
    from scipy.spatial import cKDTree

    k = len(points)
    alive = np.ones(k, dtype=bool)
    if k == 0:
        return alive
    if fixed is not None and len(fixed):
        dist, _ = cKDTree(fixed, balanced_tree=False, compact_nodes=False).query(points, k=1, distance_upper_bound=radius)
        alive = ~(dist < radius)
    state = np.where(alive, 0, -1).astype(np.int8)  # 0 undecided, 1 kept, -1 dropped
    idx = np.flatnonzero(alive)
    pairs = cKDTree(points[idx], balanced_tree=False, compact_nodes=False).query_pairs(radius * (1 - 1e-12), output_type="ndarray")
    a, b = idx[pairs[:, 0]], idx[pairs[:, 1]]
    swap = a > b
    a, b = np.where(swap, b, a), np.where(swap, a, b)  # a < b: a has priority
    while True:
        undecided = state == 0
        if not undecided.any():
            break
        live = undecided[a] & undecided[b]
        a, b = a[live], b[live]
        blocked = np.zeros(k, dtype=bool)
        blocked[b] = True
        new = undecided & ~blocked
        state[new] = 1
        state[b[new[a]]] = -1
        state[a[new[b]]] = -1
    return state == 1


def _rotation_about(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues: unit axes (k, 3) and angles (k,) -> (k, 3, 3)."""

    return matrices_from_rotation_vectors(axis * angle[:, None])


@dataclass(frozen=True)
class Placement:
    """Where and how instances stand on a surface (:func:`scatter`; a scene file's ``[layer.scatter]``).

    Attributes
    ----------
    min_distance : float or None
        Least distance between two instances' surface points (Poisson spacing); None: none.
    density : image path, (rows, cols) float in [0, 1] or None
        Over the surface's bounding box: where instances may go, and how densely.
    align_to_normal : float in [0, 1]
        0 upright, 1 along the surface normal.
    anchor : {"bottom", "center", "origin"}
        The point of the mesh that stands on the surface; its axis is pinned there
        (``D(t_anchor) = 0``).
    up : {"x", "y", "z"}
        World up.
    height_scale, extent
        For a height-map surface (see :func:`surface_from_heights`).
    """

    min_distance: float | None = None
    density: object = None
    align_to_normal: float = 0.0
    anchor: str = "bottom"
    up: str = "y"
    height_scale: float = 1.0
    extent: object = None

    def __post_init__(self):
        if self.anchor not in ANCHORS:
            raise ScatterError(f"anchor: expected one of {', '.join(ANCHORS)}, found {self.anchor!r}")
        if not (math.isfinite(self.align_to_normal) and 0.0 <= self.align_to_normal <= 1.0):
            raise ScatterError(f"align-to-normal: expected a fraction in [0, 1], found {self.align_to_normal!r}")
        if self.up not in AXIS_NAMES:
            raise ScatterError(f"up: expected one of x, y, z, found {self.up!r}")


#: Variation fields scatter does not read: the surface decides them (position, and the tilt by align_to_normal)
_SURFACE_DECIDES = {"tilt": (-0.25, 0.25), "height": (0.0, 0.0)}


def scatter(surface, mesh, n: int, variation: Variation | None = None, placement: Placement | None = None, *,
            seed: int = 0, allow_fewer: bool = False, **fields) -> np.ndarray:
    """Place ``n`` instances of ``mesh`` on ``surface``.

    Parameters
    ----------
    surface : mesh path, height-map image path, trimesh.Trimesh, BaseMesh, Surface or (rows, cols) heights
        Instances stand on its upward-facing faces.
    mesh : BaseMesh, a mesh path or a bundled name (``"stone"``, ``"leaf"``)
    n : int
        How many instances.
    variation : Variation, optional
        Their bend (a fraction of L; a mesh of several axes: one per level, each child axis in units
        of its own length, clamped at its anchor), yaw, scale, twist, taper and tint.  The surface decides the
        position and the tilt (``align_to_normal``): a ``tilt`` or ``height`` is refused.
    placement : Placement, optional
        Spacing, density map, alignment, anchor, up, and a height map's scale and extent.
    seed : int >= 0
    allow_fewer : bool
        When fewer than ``n`` fit, return them instead of raising.
    **fields
        Deprecated (still working for one release, with a DeprecationWarning): fields of
        :class:`Variation` or of :class:`Placement` (``bend=0.1, min_distance=0.5``).

    Returns
    -------
    Instances
        ``(n, 16)``, or ``(n, 19)`` with a scale, twist or taper, ``(n, 22)`` with a tint, float32.
        Raises :class:`TooFewError` (with ``.params``, what fits) when fewer than ``n`` fit and not
        ``allow_fewer``.
    """

    place_fields = {k: fields.pop(k) for k in list(fields) if k in Placement.__dataclass_fields__}
    for key in set(fields) & set(_SURFACE_DECIDES):
        raise ScatterError(f"{key}: scatter stands instances on the surface (tilted by align_to_normal); "
                           f"expected no {key}")
    variation = Variation.of(variation, fields, ScatterError, where="scatter")
    warn_field_keywords("scatter", place_fields, "placement", "core.Placement")
    placement = replace(placement or Placement(), **place_fields)
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 0:
        raise ScatterError(f"count: expected a whole number >= 0, found {n!r}")
    n = int(n)
    if n > MAX_INSTANCES:
        raise ScatterError(f"count: expected at most {MAX_INSTANCES} instances, found {n}")
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ScatterError(f"seed: expected a non-negative integer, found {seed!r}")
    min_distance = placement.min_distance
    base = mesh if isinstance(mesh, BaseMesh) else load_mesh(mesh)
    surf = load_surface(surface, up=placement.up, height_scale=placement.height_scale, extent=placement.extent)
    grey = None if placement.density is None else load_density(placement.density)
    if min_distance is not None:
        size = surf.size
        if not (math.isfinite(min_distance) and 0 < min_distance <= size):
            raise ScatterError(f"min-distance: expected a distance > 0 and at most the surface's size "
                               f"({size:.6g}), found {min_distance!r}")

    rng = np.random.Generator(np.random.PCG64(int(seed)))
    weight_cum = np.cumsum(surf.weights)  # as trimesh's sample_surface makes it
    area = float(surf.weights.sum())
    mean_density = 1.0 if grey is None else max(float(grey.mean()), 1e-3)

    points = np.zeros((0, 3))
    faces = np.zeros(0, dtype=np.int64)
    stalled = 0
    for round_ in range(MAX_ROUNDS):
        need = n - len(points)
        if need <= 0:
            break
        want = 2 * need
        if min_distance is not None:
            # Greedy thinning of lam candidates per D² keeps about 0.5 (1 - exp(-1.5 lam)) per D²
            # (measured); the first round asks for what should give n with a margin, later rounds
            # (near the packing limit) cover the whole surface again to fill the gaps left.
            per_d2 = min(area / min_distance / min_distance, float(MAX_CANDIDATES))  # D² cells in the area
            full = math.ceil(3.0 * per_d2)
            if round_ == 0:
                rho = min(0.95, n / per_d2 / 0.5)
                lam = -1.3 * math.log1p(-rho) / 1.5
                want = min(full, max(want, math.ceil(lam * per_d2)))
            else:
                want = full
        count = int(min(MAX_CANDIDATES, math.ceil(want / mean_density) + 16))
        cand, fidx = surf.sample(count, rng, weight_cum)
        if grey is not None:
            keep = rng.random(count) < density_at(grey, cand, surf)
            cand, fidx = cand[keep], fidx[keep]
        if min_distance is not None:
            keep = poisson_greedy(cand, float(min_distance), points)
            cand, fidx = cand[keep], fidx[keep]
        cand, fidx = cand[:need], fidx[:need]
        if len(cand) == 0:
            stalled += 1
            if stalled >= 2:
                break
        else:
            stalled = 0
        points = np.concatenate([points, cand])
        faces = np.concatenate([faces, np.asarray(fidx, dtype=np.int64)])

    if n > 0 and len(points) == 0 and grey is not None:
        raise ScatterError(f"density: no candidate on the upward-facing part of {surf.name} lies under a "
                           f"non-black pixel; expected white where instances may go (columns along "
                           f"+{AXIS_NAMES[surf.ground[0]]}, rows along +{AXIS_NAMES[surf.ground[1]]})")
    params = _instances(base, points, surf.face_normals(faces), surf.up, rng, placement, variation)
    if len(params) < n and not allow_fewer:
        why = f" at spacing {min_distance:g}" if min_distance is not None else ""
        raise TooFewError(f"count: only {len(params)} of {n} instances fit on {surf.name}{why}; "
                          f"expected room for {n} (lower -n or --min-distance, or pass --allow-fewer)", params)
    return Instances.of(params)


def _instances(base, points, normals, u: int, rng, placement: Placement, variation: Variation) -> np.ndarray:
    """Parameters for instances standing on ``points`` (k, 3) with surface ``normals`` (k, 3)."""

    k = len(points)
    anchor, scale, bend = placement.anchor, variation.scale, variation.bends
    cols = WIDTHS[2 if variation.tint is not None else 1 if variation.extended else 0]
    rolls = rng.random((k, 12))
    axis = base.axis
    length = axis.length
    offsets = ((2.0 * rolls[:, :10] - 1.0) * bend[0] * length).reshape(k, 5, 2)

    a = anchor_point(base, anchor, u)
    # pin the axis at the anchor: subtract D(t_anchor) from all five offsets
    t_a = float(axis.parameter(a[None, :])[0])
    offsets -= np.einsum("i,kic->kc", bernstein(np.array(t_a), 4), offsets)[:, None, :]

    e_up = np.zeros(3)
    e_up[u] = 1.0
    yaw = variation.yaw[0] + (variation.yaw[1] - variation.yaw[0]) * rolls[:, 10]
    turn = _rotation_about(np.broadcast_to(e_up, (k, 3)), yaw)
    nrm = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    cross = np.cross(np.broadcast_to(e_up, (k, 3)), nrm)
    sin = np.linalg.norm(cross, axis=1)
    angle = np.arctan2(sin, nrm[:, u]) * placement.align_to_normal
    tilt_axis = np.where(sin[:, None] > 1e-12, cross / np.where(sin > 1e-12, sin, 1.0)[:, None], 0.0)
    rot = _rotation_about(tilt_axis, angle) @ turn

    s = np.ones(k) if scale is None else scale[0] + (scale[1] - scale[0]) * rolls[:, 11]
    out = np.zeros((k, cols), dtype=np.float64)
    out[:, OFFSETS] = offsets.reshape(k, 10)
    out[:, POSITION] = points - s[:, None] * (rot @ a)
    out[:, ANGLES] = angles_from_matrices(rot)
    if variation.droop and getattr(base, "tree", None) is None:  # one axis: it sags from the anchor it stands on
        out[:, OFFSETS] += sag_offsets([axis], [t_a], variation.droop, out[:, ANGLES], u)[:, 0].reshape(k, 10)
    if cols >= EXTENDED_WIDTH:
        out[:, SCALE] = s
    tree = getattr(base, "tree", None)
    children = None if tree is None else rng.random((k, tree.count - 1, 5, 2))
    # twist, taper and tint: drawn after everything else, so the other numbers stay what they are without them
    if variation.twist is not None or variation.taper is not None:
        u_extra = rng.random((k, 2))
        out[:, TWIST] = abs(variation.twist or 0.0) * (2.0 * u_extra[:, 0] - 1.0)
        out[:, TAPER] = (variation.taper or 0.0) * u_extra[:, 1]
    if variation.tint is not None:
        out[:, TINT] = tint_of(rng.random((k, 3)), variation.tint, variation.tint_color, variation.tint_hue)
    if tree is not None:  # several axes: every child axis its level's amplitude, clamped at its anchor (joints stay closed)
        offsets = child_offsets(tree, bend, children)
        if variation.droop:
            offsets = offsets + droop_offsets(tree, variation.droop, out[:, ANGLES], "xyz".index(placement.up))
        out = join_record(out, offsets)
    out = np.ascontiguousarray(out, dtype=np.float32)
    if not np.isfinite(out).all():
        raise ScatterError("scatter: a parameter came out non-finite; expected finite surface and mesh coordinates")
    return out

"""Bounds of deformed instances without deforming them (pure numpy).

The one home of the bounding spheres around each instance and the box
around all of them; the camera framing, the ground plane and the viewer
call these.
"""

from __future__ import annotations

import numpy as np

from .deform import bernstein, deform, deform_local_extended, displace
from .params import as_params
from .record import (
    ANGLES,
    EXTENDED_WIDTH,
    EXTRA,
    OFFSETS,
    POSITION,
    SCALE,
    TAPER,
    TWIST,
    split_record,
)
from .transforms import rotation_matrices

__all__ = [
    "light_box",
    "wind_reach", "child_reach", "instance_bounds", "scene_box", "sphere_box", "stack_spheres", "ground_square",
    "box_corners", "outline_points", "base_radius", "instance_boxes", "frustum_planes", "spheres_visible", "lod_choice",
]


def base_radius(mesh, *extra_positions) -> float:
    """The largest distance of a vertex from the base mesh's bounding-box
    centre ``mesh.axis.center`` (model units), over the mesh and any
    ``extra_positions`` arrays (k, 3) (its LOD levels)."""
    center = np.asarray(mesh.axis.center, dtype=np.float64)
    # over blocks of vertices: no (n, 3) float64 copies of a big mesh (the same maximum)
    return max(float(np.linalg.norm(np.asarray(p[s:s + _RADIUS_BLOCK], dtype=np.float64) - center, axis=1).max())
               for p in (mesh.positions, *extra_positions) for s in range(0, len(p), _RADIUS_BLOCK))


#: vertices handled at once by :func:`base_radius`
_RADIUS_BLOCK = 1 << 16


def wind_reach(mesh, wind) -> float:
    """How far the wind can move a control point, model units: its offset is
    ``c_k u`` with ``c_k <= 1`` and ``|u| <= |strength L (1 + gustiness wave)|``,
    ``|wave| <= 0.6 + 0.4`` (docs/wind.md).  0 without a wind."""
    if wind is None:
        return 0.0
    tree = getattr(mesh, "tree", None)  # several axes: a vertex sums the pushes of its chain
    length = float(mesh.axis.length) if tree is None else float(
        (tree.chain.astype(np.float64) @ np.array([a.length for a in tree.axes])).max())
    return abs(float(wind.strength)) * length * (1.0 + abs(float(wind.gustiness)))


def instance_bounds(mesh, params, wind=None, *, radius: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Bounding spheres of the deformed instances, without deforming them.

    mesh : BaseMesh; params : (n, 16) or (n, 19) float.
    Returns ``centers : (n, 3) float64`` and ``radii : (n,) float64`` (world
    units).  The bend moves no vertex further than the largest offset (the
    Bernstein weights sum to 1), and a rotation keeps distances, so each
    sphere holds its whole instance.  Extended instances: twist keeps each
    vertex's distance from the axis line, taper scales it by at most
    ``max(1, |1 - tp|)``, and ``s`` scales the whole about the model origin
    (so the centre is ``s R c + p``).  ``wind`` (a :class:`axialdeform.Wind`)
    adds its largest control-point movement (:func:`wind_reach`).
    ``radius`` replaces the base mesh's own (:func:`base_radius`; LOD levels
    may reach further).  The same sphere on the GPU: ``glsl/bounds.glsl``
    (``axial_bound_sphere``).
    """
    params, children, _ = _standard(mesh, params)
    center = np.asarray(mesh.axis.center, dtype=np.float64)
    radius = base_radius(mesh) if radius is None else float(radius)
    bend = np.linalg.norm(params[:, OFFSETS].reshape(-1, 5, 2), axis=2).max(axis=1) + wind_reach(mesh, wind)
    bend += child_reach(mesh.tree, children)
    scale = np.ones(len(params))
    grow = np.ones(len(params))
    if params.shape[1] >= EXTENDED_WIDTH:
        scale, grow = params[:, SCALE], np.maximum(1.0, np.abs(1.0 - params[:, TAPER]))
    centers = np.einsum("nij,j->ni", rotation_matrices(params[:, ANGLES]), center) * scale[:, None] + params[:, POSITION]
    return centers, (radius * grow + bend) * np.abs(scale)


def scene_box(mesh, params) -> tuple[np.ndarray, np.ndarray]:
    """The axis-aligned box around every instance's bounding sphere.

    Returns ``lo : (3,) float64`` and ``hi : (3,) float64``; with no
    instances, the box from -1 to 1.
    """
    return sphere_box(*instance_bounds(mesh, params))


def sphere_box(centers, radii) -> tuple[np.ndarray, np.ndarray]:
    """The axis-aligned box around spheres: ``centers : (n, 3)``, ``radii :
    (n,)``.  Returns ``lo, hi : (3,) float64``; the box from -1 to 1 when n = 0."""
    centers = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
    radii = np.broadcast_to(np.asarray(radii, dtype=np.float64), (len(centers),))
    if len(centers) == 0:
        return np.full(3, -1.0), np.full(3, 1.0)
    return (centers - radii[:, None]).min(axis=0), (centers + radii[:, None]).max(axis=0)


def stack_spheres(spheres) -> tuple[np.ndarray, np.ndarray]:
    """``[(centers (n, 3), radii (n,) or a number), ...]`` as one ``centers : (N, 3)``, ``radii : (N,)`` float64."""
    parts = [(np.asarray(c, np.float64).reshape(-1, 3), np.asarray(r, np.float64)) for c, r in spheres]
    if not parts:
        return np.zeros((0, 3)), np.zeros(0)
    return (np.concatenate([c for c, _ in parts]),
            np.concatenate([np.broadcast_to(r, (len(c),)) for c, r in parts]))


def ground_square(centers, radii, up: int = 1, *, margin: float = 1.6, sink: float = 0.35,
                  height: float | None = None) -> tuple[np.ndarray, float]:
    """Where a ground plane under spheres lies: the square centred under them and ``margin`` times as wide as
    they spread, ``sink`` times their typical radius above their lowest point (so instances rest in it rather
    than float over it), or at ``height`` along up where the scene knows it (generated layers stand on 0).

    Parameters
    ----------
    centers : (n, 3) float
    radii : (n,) float
    up : {0, 1, 2}
        The world up axis (the plane is across it).
    margin, sink : float
        How much wider than the spheres' spread, and how far above their lowest point (in median radii).
    height : float, optional
        The plane's height along up.

    Returns
    -------
    center : (3,) float64
    radius : float
        Half the side of the fitted square (what render draws reaches further: ``GroundPlane.EXTENT`` times).
    """
    centers = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
    radii = np.broadcast_to(np.asarray(radii, dtype=np.float64), (len(centers),))
    lo, hi = sphere_box(centers, radii)
    center = (lo + hi) / 2
    others = [i for i in range(3) if i != up]
    middle = float(np.median(radii)) if len(radii) else 0.0
    radius = float(margin * np.linalg.norm((hi - lo)[others]) / 2 + middle)
    if height is not None:
        center[up] = height
    elif len(centers):
        center[up] = np.percentile(centers[:, up] - radii, 5) + sink * middle
    return center, radius


def light_box(spheres, light_dir, size: int) -> tuple[np.ndarray, np.ndarray, float]:
    """The key light's shadow camera over ``spheres`` ((k, 4) ``x, y, z, r``): ``(view, projection, offset)``,
    pyrr-layout (4, 4) float32 matrices of an orthographic camera looking along ``-light_dir`` at a box around
    every sphere, and the normal offset of a lookup (about two texels of a ``size`` map, world units) -- render's
    shadow map (:class:`~axialdeform.gl.shadow.ShadowMap`) and the page's alike."""
    import pyrr

    spheres = np.asarray(spheres, dtype=np.float64).reshape(-1, 4)
    light = np.asarray(light_dir, dtype=np.float64)
    light = light / max(np.linalg.norm(light), 1e-12)
    lo = (spheres[:, :3] - spheres[:, 3:]).min(axis=0)
    hi = (spheres[:, :3] + spheres[:, 3:]).max(axis=0)
    center = (lo + hi) / 2
    radius = float(np.linalg.norm(hi - lo) / 2) or 1.0
    helper = (0.0, 1.0, 0.0) if abs(light[1]) < 0.95 else (1.0, 0.0, 0.0)
    eye = center + light * radius * 2.0
    view = pyrr.matrix44.create_look_at(eye, center, helper, dtype=np.float32)
    projection = pyrr.matrix44.create_orthogonal_projection(-radius, radius, -radius, radius, radius * 0.5, radius * 3.5,
                                                            dtype=np.float32)
    return view, projection, 2.0 * (2.0 * radius / size)


def box_corners(lo, hi) -> np.ndarray:
    """The eight corners of the box ``lo``..``hi``: ``(8, 3) float64``."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    bits = (np.arange(8)[:, None] >> np.arange(3)[::-1]) & 1
    return np.where(bits == 1, hi, lo)


def _standard(mesh, params) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Axis 0's record (n, 16|19|22) float64, the child axes' offsets
    (n, K−1, 5, 2) (None for one axis) and the whole checked record of ``params``."""
    k = getattr(mesh, "axis_count", 1)
    record = as_params(params, axes=k)
    if k == 1:
        return record.astype(np.float64), None, record
    standard, children = split_record(record, k)
    return standard.astype(np.float64), children, record


def child_reach(tree, children) -> np.ndarray | float:
    """(n,) how far each instance's child axes can move a vertex: over the
    axes ``b``, the largest sum of the largest offsets of the child axes on
    ``b``'s chain (a vertex moves by its own chain only); 0 for one axis.

    tree : :class:`~axialdeform.core.axes.AxisTree`; children : (n, K−1, 5, 2)."""
    if children is None or tree is None:
        return 0.0
    largest = np.linalg.norm(np.asarray(children, dtype=np.float64), axis=-1).max(axis=-1)  # (n, K−1)
    return (largest @ tree.chain[:, 1:].T.astype(np.float64)).max(axis=-1)


def instance_boxes(mesh, params) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned world boxes of the deformed instances: ``lo, hi : (n, 3) float64``.

    In model space each offset component of ``D(t)`` is a convex combination
    of the five control-point offsets, so it lies between their minimum and
    maximum: the base mesh's box grows by exactly that range across the
    axis.  The rotated box is then boxed again (half-extents ``|R| h``).
    """
    params, children, record = _standard(mesh, params)
    axis = mesh.axis
    # a chosen frame: the box of the local coordinates F·V, placed by R·Fᵀ
    pos = axis.local(mesh.positions) if axis.framed else mesh.positions.astype(np.float64)
    lo, hi = np.broadcast_to(pos.min(axis=0), (len(params), 3)).copy(), np.broadcast_to(pos.max(axis=0), (len(params), 3)).copy()
    d = params[:, OFFSETS].reshape(-1, 5, 2)
    for k, coord in enumerate((1, 2) if axis.framed else axis.perpendicular):
        lo[:, coord] += d[:, :, k].min(axis=1)
        hi[:, coord] += d[:, :, k].max(axis=1)
    rot = rotation_matrices(params[:, ANGLES])
    if axis.framed:
        rot = rot @ axis.matrix.T
    scale = params[:, SCALE] if params.shape[1] >= EXTENDED_WIDTH else np.ones(len(params))
    center = np.einsum("nij,nj->ni", rot, (lo + hi) / 2) * scale[:, None] + params[:, POSITION]
    half = np.einsum("nij,nj->ni", np.abs(rot), (hi - lo) / 2) * np.abs(scale)[:, None]
    half += (child_reach(mesh.tree, children) * np.abs(scale))[:, None]  # several axes: each child moves a vertex so far
    if params.shape[1] >= EXTENDED_WIDTH:  # twisted or tapered cross-sections: the box around the sphere
        turned = (params[:, TWIST] != 0) | (params[:, TAPER] != 0)
        if turned.any():
            c, r = instance_bounds(mesh, record[turned])  # the whole record (every axis)
            center[turned], half[turned] = c, r[:, None]
    return center - half, center + half


def frustum_planes(view, projection) -> np.ndarray:
    """The six planes of the view frustum in world space: ``(6, 4) float64``,
    rows ``(n, d)`` with unit ``n``; a point ``x`` is inside all of them when
    ``n . x + d >= 0`` (left, right, bottom, top, near, far).

    view, projection : (4, 4) pyrr-layout matrices (``clip = P V x`` in
    column-vector terms is ``x @ view @ projection`` on pyrr's rows).
    """
    view = np.asarray(view, dtype=np.float64).reshape(4, 4)
    projection = np.asarray(projection, dtype=np.float64).reshape(4, 4)
    m = (view @ projection).T  # column-vector clip matrix: rows are clip x, y, z, w
    planes = np.stack([m[3] + m[0], m[3] - m[0], m[3] + m[1], m[3] - m[1], m[3] + m[2], m[3] - m[2]])
    norm = np.linalg.norm(planes[:, :3], axis=1, keepdims=True)
    return planes / np.where(norm > 0, norm, 1.0)


def spheres_visible(centers, radii, planes) -> np.ndarray:
    """``(n,) bool``: False only for a sphere wholly outside one plane (so
    nothing inside it can be drawn); the same test as ``axial_sphere_visible``
    in ``glsl/bounds.glsl``."""
    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64)
    dist = centers @ planes[:, :3].T + planes[:, 3]
    return (dist >= -radii[:, None]).all(axis=1)


def lod_choice(centers, radii, errors, eye, px_scale: float, lod_error: float, ortho: bool = False,
               scale=None) -> np.ndarray:
    """``(n,) int``: the LOD level of each instance, the coarsest whose
    ``errors[k]`` (model units, increasing, ``errors[0] = 0``) projects to at
    most ``lod_error`` pixels at the point of the bounding sphere nearest the
    eye (``px_scale``: pixels per world unit at distance 1, i.e.
    ``P[1][1] * height / 2``); ``scale``: (n,) the instances' ``s`` (errors
    are model units).  The same rule as ``axial_lod_level`` in
    ``glsl/cull.vert``."""
    centers = np.asarray(centers, dtype=np.float64)
    if ortho:
        px = np.full(len(centers), float(px_scale))
    else:
        near = np.linalg.norm(centers - np.asarray(eye, dtype=np.float64), axis=1) - np.asarray(radii, dtype=np.float64)
        px = px_scale / np.maximum(near, 1e-6)
    if scale is not None:
        px = px * np.abs(np.asarray(scale, dtype=np.float64))
    errors = np.asarray(errors, dtype=np.float64)
    fits = errors[None, :] * px[:, None] <= lod_error
    fits[:, 0] = True
    return (np.cumprod(fits, axis=1).sum(axis=1) - 1).astype(np.int64) if len(errors) else np.zeros(len(centers), np.int64)


_SUPPORT_BLOCK = 16384


def _support_indices(positions: np.ndarray, directions: int = 194) -> np.ndarray:
    """Indices of the vertices that lie furthest along ``directions`` spread
    evenly over the sphere (a Fibonacci lattice) and along the six axes:
    the vertices that make a mesh's outline from any side."""
    k = np.arange(directions) + 0.5
    z = 1.0 - 2.0 * k / directions
    phi = np.pi * (1.0 + 5.0**0.5) * k
    r = np.sqrt(1.0 - z * z)
    dirs = np.concatenate([np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1), np.eye(3), -np.eye(3)])
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    if len(p) == 0:
        return np.zeros(0, dtype=np.int64)
    centre = p.mean(axis=0)
    # in blocks of vertices: a (vertices, 200) float64 product of a 10 M-vertex
    # mesh would take 16 GB; a block keeps it to ~26 MB, the result the same
    best = np.full(len(dirs), -np.inf)
    arg = np.zeros(len(dirs), dtype=np.int64)
    for start in range(0, len(p), _SUPPORT_BLOCK):
        proj = (p[start:start + _SUPPORT_BLOCK] - centre) @ dirs.T
        i = np.argmax(proj, axis=0)
        top = proj[i, np.arange(len(dirs))]
        better = top > best  # strictly: the first vertex wins ties, as one argmax over all would
        best[better], arg[better] = top[better], i[better] + start
    return np.unique(arg)


def outline_points(mesh, params, *, budget: int = 100_000) -> tuple[np.ndarray, np.ndarray]:
    """Points (with radii) whose spheres hold the deformed instances, as
    tightly as ``budget`` allows: what a camera must keep in view.

    mesh : BaseMesh; params : (n, 16) float; budget : the most points made.
    Returns ``points : (m, 3) float64`` and ``radii : (m,) float64``:

    * every deformed vertex (radius 0) when ``n * vertices <= budget``
      (exact);
    * else the deformed vertices that are extreme along 200 directions of
      the base mesh (radius 0; an approximation: a bent instance may reach
      a little past them, which the framing's margin covers);
    * else the instance spheres of :func:`instance_bounds` (always hold).
    """
    params = as_params(params, axes=mesh.axis_count)
    n, v = len(params), mesh.vertex_count
    if n == 0:
        return np.zeros((0, 3)), np.zeros(0)
    if mesh.axis_count > 1:  # several axes: every deformed vertex when they fit, else the spheres
        if n * v > budget:
            return instance_bounds(mesh, params)
        world, _ = deform(mesh, params)
        return world.reshape(-1, 3).astype(np.float64), np.zeros(n * v)
    if n * v <= budget:
        idx = np.arange(v)
    else:
        idx = _support_indices(mesh.positions)
        if n * len(idx) > budget:
            return instance_bounds(mesh, params)
    if params.shape[1] >= EXTENDED_WIDTH or mesh.axis.framed:  # the CPU reference places the chosen vertices

        world, _ = deform(mesh.axis, mesh.positions[idx], mesh.normals[idx], params)
        return world.reshape(-1, 3).astype(np.float64), np.zeros(n * len(idx))
    pts = mesh.positions[idx].astype(np.float64)
    p64 = params.astype(np.float64)
    if p64.shape[1] >= EXTENDED_WIDTH:  # extended instances: the whole map of the selected vertices

        moved, _ = deform_local_extended(mesh.axis, pts, pts, p64[:, OFFSETS].reshape(-1, 5, 2), p64[:, EXTRA])
        world = moved @ np.swapaxes(rotation_matrices(p64[:, ANGLES]), 1, 2) + p64[:, None, POSITION]
        return world.reshape(-1, 3), np.zeros(n * len(idx))
    disp = np.einsum("vk,nkc->nvc", bernstein(mesh.axis.parameter(pts), 4), p64[:, OFFSETS].reshape(-1, 5, 2))
    world = displace(mesh.axis, pts, disp) @ np.swapaxes(rotation_matrices(p64[:, ANGLES]), 1, 2)
    world += p64[:, None, POSITION]
    return world.reshape(-1, 3), np.zeros(n * len(idx))

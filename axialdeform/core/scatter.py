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
import os
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from PIL import Image

from .axes import child_offsets
from .axis import AXIS_NAMES, PERPENDICULAR
from .deform import bernstein
from .errors import MeshError, ScatterError, TooFewError
from .io import safeio
from .io.mesh import load_mesh
from .io.safeio import _gb, open_regular
from .material import AssetWarning
from .mesh import BaseMesh
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
from .transforms import angles_from_matrices, matrices_from_rotation_vectors
from .variation import Variation

__all__ = [
    "scatter", "Placement", "Surface", "load_surface", "sample_faces", "face_areas", "load_density", "surface_from_heights",
    "ANCHORS", "IMAGE_SUFFIXES", "poisson_greedy",
]

ANCHORS = ("bottom", "center", "origin")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".gif", ".webp")
#: most candidates drawn in one round (bounds memory: about 200 bytes each)
MAX_CANDIDATES = 4_000_000
#: most instances one call places (76 bytes each as 19 float32)
MAX_INSTANCES = 10_000_000
#: rounds of fresh candidates before giving up on reaching n
MAX_ROUNDS = 12


#: faces handled at once when a surface's face areas, normals and bounds are
#: computed (bounds the temporaries: about 250 bytes a face, ~16 MB a block)
FACE_BLOCK = 1 << 16


@dataclass(eq=False)
class Surface:
    """A surface to scatter on, kept as plain arrays (no ``trimesh.Trimesh``
    and its caches: a 1 500 x 1 500 height map is 4.5 M faces).

    vertices : (n, 3) float64 -- world units.
    faces : (f, 3) uint32 (int64 where given so) -- every face.
    up : int -- 0, 1, 2 for x, y, z.
    name : str -- for messages.
    weights : (f,) float64 -- each face's area where it faces up (its normal has
        a ``up`` component > 1e-9, trimesh's face normal and area), else 0:
        what sampling is weighted by.
    """

    vertices: np.ndarray
    faces: np.ndarray
    up: int
    name: str
    weights: np.ndarray
    #: ``(rows, cols)`` of a height map's grid (its edges are known), else None
    grid: tuple | None = None

    @property
    def upward(self) -> np.ndarray:
        """(f,) bool: the faces that face up (and have an area)."""
        return self.weights > 0

    @property
    def mesh(self):
        """A ``trimesh.Trimesh`` of every face, built on each call (costly on
        a big surface: the library itself never asks for it)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)

    @property
    def ground(self) -> tuple[int, int]:
        """The two other axes in increasing order: density columns, density rows."""
        return PERPENDICULAR[self.up]

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) float64: the bounding box of the vertices the faces use (as trimesh's ``bounds``)."""
        if "_bounds" not in self.__dict__:
            self.__dict__["_bounds"] = _used_bounds(self.vertices, self.faces)
        return self.__dict__["_bounds"]

    @property
    def size(self) -> float:
        """Largest extent of the bounding box of the upward-facing faces."""
        lo, hi = _used_bounds(self.vertices, self.faces, self.weights > 0)
        return float((hi - lo).max())

    def face_normals(self, index: np.ndarray) -> np.ndarray:
        """(k, 3) float64 unit normals of the faces ``index`` (k,) -- trimesh's
        ``face_normals`` of those faces (zero where a face has no area)."""
        return _trimesh_normals(self.vertices[self.faces[index]])

    def sample(self, count: int, rng: np.random.Generator, weight_cum: np.ndarray | None = None):
        """``count`` points, area-uniform over the upward faces: ``(points (count, 3)
        float64, face_index (count,) int64)``.

        The same draws from ``rng``, in the same order, and the same arithmetic
        as ``trimesh.sample.sample_surface(mesh, count, face_weight=weights,
        seed=rng)`` -- the same points and faces, bit for bit (pinned by
        ``tests/app/test_scatter.py::test_sample_is_trimesh_sample_surface``) --
        but trimesh builds an origin and two edge vectors for EVERY face
        ((f, 3, 3) float64: 324 MB on a 1 500 x 1 500 height map) before
        picking; this gathers only the picked faces' vertices.
        ``weight_cum`` : ``np.cumsum(self.weights)`` if already at hand."""
        if weight_cum is None:
            weight_cum = np.cumsum(self.weights)
        return sample_faces(self.vertices, self.faces, weight_cum, count, rng)


def sample_faces(vertices: np.ndarray, faces: np.ndarray, weight_cum: np.ndarray, count: int, rng):
    """``count`` points on the triangles ``faces`` (f, 3) of ``vertices`` (n, 3),
    a face picked with probability in proportion to its weight (``weight_cum``
    (f,): the running sum of the weights), uniform within it: ``(points (count, 3)
    float64, face_index (count,) int64)``.

    Exactly ``trimesh.sample.sample_surface(mesh, count, face_weight=weights,
    seed=rng)`` -- the same draws from ``rng`` (a numpy Generator, or a seed),
    in the same order, and the same arithmetic, so the same points bit for bit
    (pinned by ``tests/app/test_scatter.py::test_sample_is_trimesh_sample_surface``)
    -- but trimesh builds an origin and two edge vectors for EVERY face
    ((f, 3, 3) float64: 324 MB on a 1 500 x 1 500 height map) before picking;
    this gathers only the picked faces' vertices."""
    random = np.random.default_rng(rng).random
    face_pick = random(count) * weight_cum[-1]
    face_index = np.searchsorted(weight_cum, face_pick)
    f = faces[face_index]
    tri_origins = vertices[f[:, 0]]
    tri_vectors = vertices[f[:, 1:]]
    tri_vectors -= np.tile(tri_origins, (1, 2)).reshape((-1, 2, 3))
    random_lengths = random((len(tri_vectors), 2, 1))
    random_test = random_lengths.sum(axis=1).reshape(-1) > 1.0
    random_lengths[random_test] -= 1.0
    random_lengths = np.abs(random_lengths)
    sample_vector = (tri_vectors * random_lengths).sum(axis=1)
    return sample_vector + tri_origins, face_index


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(f,) float64: each face's area, trimesh's ``area_faces`` computed with
    trimesh's own functions over blocks of faces (no (f, 3, 3) array of every face)."""
    import trimesh

    areas = np.empty(len(faces))
    for b in _blocks(len(faces)):
        areas[b] = trimesh.triangles.area(vertices[faces[b]])
    return areas


def _blocks(count: int):
    for start in range(0, count, FACE_BLOCK):
        yield slice(start, min(start + FACE_BLOCK, count))


def _used_bounds(vertices: np.ndarray, faces: np.ndarray, which: np.ndarray | None = None) -> np.ndarray:
    """(2, 3) float64 min and max of the vertices used by ``faces`` (those with ``which`` (f,) bool)."""
    used = np.zeros(len(vertices), dtype=bool)
    for b in _blocks(len(faces)):
        used[(faces[b] if which is None else faces[b][which[b]]).ravel()] = True
    return np.array([[vertices[used, c].min() for c in range(3)], [vertices[used, c].max() for c in range(3)]])


def _upward_areas(vertices: np.ndarray, faces: np.ndarray, u: int) -> np.ndarray:
    """(f,) float64: each face's area (trimesh's ``area_faces``) where its unit normal
    (trimesh's ``face_normals``) has a ``u`` component > 1e-9, else 0 -- computed
    with trimesh's own functions over blocks of faces, so that no (f, 3, 3) or
    (f, 3) array of every face is ever held."""
    import trimesh

    weights = np.empty(len(faces))
    for b in _blocks(len(faces)):
        crosses = trimesh.triangles.cross(vertices[faces[b]])
        area = trimesh.triangles.area(crosses=crosses)
        unit, valid = trimesh.util.unitize(crosses, check_valid=True)
        nu = np.zeros(len(area))
        nu[valid] = unit[:, u]
        weights[b] = np.where((nu > 1e-9) & (area > 0), area, 0.0)
    return weights


def _up_index(up) -> int:
    if up not in AXIS_NAMES:
        raise ScatterError(f"up: expected one of x, y, z, found {up!r}")
    return AXIS_NAMES.index(up)


#: peak bytes a height-map SURFACE costs per pixel (float64 grid 24, uint32 faces 24,
#: area weights 16 and their running sum 16, blocks of temporaries; as a scene's terrain
#: also its float32 drawing copy and normals): measured on a 1 500 x 1 500 map, peak RSS
#: less a tiny map's, ~96 for `axialdeform scatter big.png stone -n 200 -o p.adp` and
#: ~150 for a scene with it as [terrain] up to its first draw (tracemalloc on 600 x 600:
#: up to 218; tests/app/test_scatter.py::test_height_map_memory_is_bounded_per_pixel) --
#: with a margin, the pixel bound checked before decoding (was 500)
SURFACE_BYTES_PER_PIXEL = 260
#: bytes a density map costs per pixel (the float64 grey levels and one copy)
DENSITY_BYTES_PER_PIXEL = 32


def _read_grey(path: Path, what: str, bytes_per_pixel: int = DENSITY_BYTES_PER_PIXEL) -> np.ndarray:
    """A grey image as float64 in [0, 1], shape (rows, cols).

    The file must be a regular file (a FIFO or a device is refused without
    blocking), and its pixel count -- read from the header, before any pixel
    is decoded -- must fit in memory at ``bytes_per_pixel``: a small
    compressed file claiming a huge image (a decompression bomb) is refused
    with the limit, never decoded."""

    if not os.path.lexists(path):
        raise ScatterError(f"{what} {path}: no such file")
    with open_regular(path, f"a grey image ({what})", ScatterError) as (fh, _size):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", Image.DecompressionBombWarning)
                with Image.open(fh) as img:
                    cols, rows = img.size
                    budget = int(0.8 * safeio.memory_available())
                    if cols * rows * bytes_per_pixel > budget:
                        raise ScatterError(
                            f"{what} {path}: an image of {cols}x{rows} pixels needs about "
                            f"{_gb(cols * rows * bytes_per_pixel)}; expected at most {budget // bytes_per_pixel} pixels "
                            f"(what {_gb(budget)} of available memory holds)")
                    img.load()
                    if img.mode in ("I;16", "I;16B", "I;16L", "I"):
                        grey = np.asarray(img, dtype=np.float64) / 65535.0
                    elif img.mode == "F":
                        grey = np.asarray(img, dtype=np.float64)
                    else:
                        grey = np.asarray(img.convert("L"), dtype=np.float64) / 255.0
        except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
            raise ScatterError(f"{what} {path}: refused as a decompression bomb ({exc})") from None
        except (ScatterError, MemoryError):
            raise
        except Exception as exc:  # noqa: BLE001 - UnidentifiedImageError or any decoder failure on a hostile file
            from PIL import UnidentifiedImageError

            why = ("not an image format Pillow recognises" if isinstance(exc, UnidentifiedImageError)
                   else f"{type(exc).__name__}: {exc}")
            raise ScatterError(f"{what} {path}: could not read the image ({why})") from None
    return grey


def _grid(heights, what: str) -> np.ndarray:
    h = np.asarray(heights, dtype=np.float64)
    if h.ndim != 2:
        raise ScatterError(f"{what}: expected a 2-D grey image, found an array of shape {h.shape}")
    if not np.isfinite(h).all():
        raise ScatterError(f"{what}: expected finite grey levels, found a non-finite value")
    return h


def surface_from_heights(heights, *, up: str = "y", height_scale: float = 1.0, extent=None,
                         name: str = "<height map>") -> Surface:
    """A terrain mesh from a height map.

    heights : (rows, cols) float in [0, 1] -- pixel (row, col) is the vertex at
        ``col`` along the first ground axis (+x for ``up="y"``) and ``row``
        along the second (+z), the top row at the smallest coordinate; its
        height along ``up`` is ``value * height_scale``.
    extent : None, W or (W, D) -- the grid's size along the two ground axes
        (default: one unit per pixel; with W alone, D keeps the pixels square).
        The grid is centred on the origin across ``up``.
    """
    h = _grid(heights, name)
    rows, cols = h.shape
    if rows < 2 or cols < 2:
        raise ScatterError(f"{name}: a height map of {cols}x{rows} pixels; expected at least 2x2")
    if not (math.isfinite(height_scale) and height_scale >= 0):
        raise ScatterError(f"height-scale: expected a finite number >= 0, found {height_scale!r}")
    if extent is None:
        width, depth = float(cols - 1), float(rows - 1)
    else:
        ext = [float(extent)] if np.isscalar(extent) else [float(x) for x in extent]
        if len(ext) not in (1, 2) or not all(math.isfinite(x) and x > 0 for x in ext):
            raise ScatterError(f"extent: expected W or W,D with finite sizes > 0, found {extent!r}")
        width = ext[0]
        depth = ext[1] if len(ext) == 2 else width * (rows - 1) / (cols - 1)
    u = _up_index(up)
    g0, g1 = PERPENDICULAR[u]
    # float64 vertices (24 bytes a pixel) and uint32 faces (24 bytes a pixel), written in place
    verts = np.empty((rows * cols, 3))
    verts[:, g0] = np.tile((np.arange(cols) / (cols - 1) - 0.5) * width, rows)
    verts[:, g1] = np.repeat((np.arange(rows) / (rows - 1) - 0.5) * depth, cols)
    verts[:, u] = h.ravel() * height_scale
    dtype = np.uint32 if rows * cols < 2**32 else np.int64
    k = (np.arange(rows - 1, dtype=dtype)[:, None] * dtype(cols) + np.arange(cols - 1, dtype=dtype)).ravel()
    half = len(k)
    corners = ((k, k + cols, k + 1), (k + 1, k + cols, k + cols + 1))
    # every face's projection on the ground has the same turn, so the first face says
    # whether the grid faces up; else wind it the other way (as trimesh.Trimesh(verts, faces[:, ::-1]))
    first = np.array([[c[0] for c in corners[0]]])
    flip = _trimesh_normals(verts[first])[0, u] < 0
    faces = np.empty((2 * half, 3), dtype=dtype)
    for t, tri in enumerate(corners):
        for c, col in enumerate(tri[::-1] if flip else tri):
            faces[t * half:(t + 1) * half, c] = col
    del k, corners
    return _make_surface(verts, faces, u, name, grid=(rows, cols))


def _trimesh_normals(triangles: np.ndarray) -> np.ndarray:
    """(k, 3) float64 unit normals of ``triangles`` (k, 3, 3) as trimesh's ``face_normals`` (zero where degenerate)."""
    import trimesh

    unit, valid = trimesh.triangles.normals(triangles=triangles)
    out = np.zeros((len(triangles), 3))
    out[valid] = unit
    return out


def _make_surface(vertices, faces, u: int, name: str, grid=None) -> Surface:
    """A Surface of (n, 3) vertices and (f, 3) faces (not copied when already float64 / an integer type)."""
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    if len(faces) == 0:
        raise ScatterError(f"{name}: the surface has no faces; expected a triangle mesh")
    if not all(np.isfinite(vertices[:, c]).all() for c in range(3)):
        raise ScatterError(f"{name}: the surface has a non-finite vertex; expected finite coordinates")
    weights = _upward_areas(vertices, faces, u)
    if not (weights > 0).any():
        raise ScatterError(f"{name}: no face of the surface faces up (+{AXIS_NAMES[u]}); "
                           f"expected a surface facing up somewhere (or choose --up)")
    return Surface(vertices=vertices, faces=faces, up=u, name=name, weights=weights, grid=grid)


def load_surface(source, *, up: str = "y", height_scale: float = 1.0, extent=None) -> Surface:
    """A :class:`Surface` from a mesh file, a height-map image, a ``trimesh.Trimesh``,
    a :class:`~axialdeform.core.mesh.BaseMesh` or a 2-D height array."""
    import trimesh

    u = _up_index(up)
    if isinstance(source, Surface):
        return source
    if isinstance(source, trimesh.Trimesh):
        return _make_surface(source.vertices.view(np.ndarray), source.faces.view(np.ndarray), u, "<surface>")
    if hasattr(source, "positions") and hasattr(source, "faces"):  # a BaseMesh
        return _make_surface(source.positions, source.faces, u, source.name)
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if path.suffix.lower() in IMAGE_SUFFIXES:
            return surface_from_heights(_read_grey(path, "SURFACE", SURFACE_BYTES_PER_PIXEL), up=up, height_scale=height_scale,
                                        extent=extent, name=f"SURFACE {path}")

        try:
            with warnings.catch_warnings():  # only the faces are used: a missing texture does not matter here
                warnings.simplefilter("ignore", AssetWarning)
                base = load_mesh(path)
        except MeshError as exc:
            raise ScatterError(f"SURFACE {exc}") from None
        return _make_surface(base.positions, base.faces, u, str(path))
    return surface_from_heights(source, up=up, height_scale=height_scale, extent=extent)


def load_density(source, name: str = "<array>") -> np.ndarray:
    """A density map: (rows, cols) float64 in [0, 1] from an image path or an array."""
    if isinstance(source, (str, os.PathLike)):
        name = str(source)
        grey = _read_grey(Path(source), "density")
    else:
        grey = _grid(source, name)
    if grey.size == 0:
        raise ScatterError(f"density {name}: the image has no pixels; expected a grey image")
    if grey.min() < 0 or grey.max() > 1:
        raise ScatterError(f"density {name}: grey levels must lie in [0, 1], found {grey.min():g}..{grey.max():g}")
    if not (grey > 0).any():
        raise ScatterError(f"density {name}: every pixel is black; expected some non-black pixel (black = none, white = full)")
    return grey


def _density_at(grey: np.ndarray, points: np.ndarray, surface: Surface) -> np.ndarray:
    """Nearest-pixel grey level under each point: (k, 3) -> (k,)."""
    rows, cols = grey.shape
    lo, hi = surface.bounds
    g0, g1 = surface.ground
    span = np.where(hi - lo > 0, hi - lo, 1.0)
    c = np.clip(np.floor((points[:, g0] - lo[g0]) / span[g0] * cols), 0, cols - 1).astype(np.int64)
    r = np.clip(np.floor((points[:, g1] - lo[g1]) / span[g1] * rows), 0, rows - 1).astype(np.int64)
    return grey[r, c]


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
        of its own length, ``d₁ = 0``), yaw, scale, twist, taper and tint.  The surface decides the
        position and the tilt (``align_to_normal``): a ``tilt`` or ``height`` is refused.
    placement : Placement, optional
        Spacing, density map, alignment, anchor, up, and a height map's scale and extent.
    seed : int >= 0
    allow_fewer : bool
        When fewer than ``n`` fit, return them instead of raising.
    **fields
        Fields of :class:`Variation` or of :class:`Placement` (``bend=0.1, min_distance=0.5``).

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
    variation = Variation.of(variation, fields, ScatterError)
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
            keep = rng.random(count) < _density_at(grey, cand, surf)
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

    lo, hi = base.positions.min(axis=0), base.positions.max(axis=0)
    if anchor == "origin":
        a = np.zeros(3)
    else:
        a = (lo + hi) / 2
        if anchor == "bottom":
            a[u] = lo[u]
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
        out[:, TINT] = np.asarray(variation.tint_color) * (1.0 - variation.tint * rng.random((k, 3)))
    if tree is not None:  # several axes: every child axis its level's amplitude, d1 = 0 (joints stay closed)
        out = join_record(out, child_offsets(tree, bend, children))
    out = np.ascontiguousarray(out, dtype=np.float32)
    if not np.isfinite(out).all():
        raise ScatterError("scatter: a parameter came out non-finite; expected finite surface and mesh coordinates")
    return out

"""The surfaces instances are scattered on: a terrain mesh, a grey height-map image (Pillow) or an
array of heights as plain arrays (:class:`Surface`: no ``trimesh.Trimesh`` and its caches, so a
1 500 x 1 500 height map stays within a few hundred MB), sampled area-uniformly where they face
up, and density maps over them."""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from .axis import AXIS_NAMES, PERPENDICULAR
from .errors import MeshError, ScatterError
from .io import safeio
from .io.mesh import load_mesh
from .io.safeio import format_gb, open_regular
from .material import AssetWarning, max_texture_pixels

__all__ = ["Surface", "load_surface", "surface_from_heights", "load_density", "density_at", "sample_faces",
           "face_areas", "IMAGE_SUFFIXES", "SURFACE_BYTES_PER_PIXEL", "DENSITY_BYTES_PER_PIXEL"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".gif", ".webp")


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


#: the largest height map (a SURFACE image, a scene's [terrain] heightmap), in pixels: 2048 x 2048, at most
#: about 1.1 GB at SURFACE_BYTES_PER_PIXEL; ``AXIALDEFORM_MAX_HEIGHTMAP_PIXELS`` raises (or lowers) it, and
#: ``resample`` (``[terrain] resample = true``, ``--resample``) reads a larger one at a lower resolution
MAX_HEIGHTMAP_PIXELS = 2048 * 2048
#: the largest density map, in pixels: 4096 x 4096 (about 540 MB at DENSITY_BYTES_PER_PIXEL; the glTF
#: generated form's maps have the same bound); ``AXIALDEFORM_MAX_DENSITY_PIXELS`` raises (or lowers) it
MAX_DENSITY_PIXELS = 4096 * 4096


def pixel_limit(kind: str) -> int:
    """The pixel bound of a ``"heightmap"`` or ``"density"`` image (its constant, or the environment variable)."""
    name, default = {"heightmap": ("AXIALDEFORM_MAX_HEIGHTMAP_PIXELS", MAX_HEIGHTMAP_PIXELS),
                     "density": ("AXIALDEFORM_MAX_DENSITY_PIXELS", MAX_DENSITY_PIXELS)}[kind]
    raw = os.environ.get(name, "").strip()
    if not raw:
        return default
    if not raw.isdigit() or int(raw) < 4:
        raise ScatterError(f"{name}: expected a whole number of pixels >= 4, found {raw[:40]!r}")
    return int(raw)


def _read_grey(path: Path, what: str, bytes_per_pixel: int = DENSITY_BYTES_PER_PIXEL, *, kind: str = "density",
               resample: bool = False) -> np.ndarray:
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
                    limit = pixel_limit(kind)
                    env = "AXIALDEFORM_MAX_HEIGHTMAP_PIXELS" if kind == "heightmap" else "AXIALDEFORM_MAX_DENSITY_PIXELS"
                    if cols * rows > limit and not (resample and cols * rows <= max_texture_pixels()):
                        hint = (" or let it be read at a lower resolution ([terrain] resample = true, --resample)"
                                if kind == "heightmap" else "")
                        raise ScatterError(f"{what} {path}: an image of {cols}x{rows} pixels; expected at most {limit} "
                                           f"pixels (raise {env}{hint})")
                    budget = int(0.8 * safeio.memory_available())
                    if min(cols * rows, limit) * bytes_per_pixel + cols * rows * 4 > budget:
                        raise ScatterError(
                            f"{what} {path}: an image of {cols}x{rows} pixels needs about "
                            f"{format_gb(cols * rows * bytes_per_pixel)}; expected at most {budget // bytes_per_pixel} pixels "
                            f"(what {format_gb(budget)} of available memory holds)")
                    img.load()
                    if cols * rows > limit:  # resample: the largest size within the limit, the same aspect
                        f = math.sqrt(limit / (cols * rows))
                        size = (max(2, int(cols * f)), max(2, int(rows * f)))
                        div = 65535.0 if img.mode in ("I;16", "I;16B", "I;16L", "I") else 1.0 if img.mode == "F" else 255.0
                        src = img if img.mode in ("I;16", "I;16B", "I;16L", "I", "F", "L") else img.convert("L")
                        small = src.convert("F").resize(size, Image.Resampling.BOX)
                        grey = np.asarray(small, dtype=np.float64) / div
                    elif img.mode in ("I;16", "I;16B", "I;16L", "I"):
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


def load_surface(source, *, up: str = "y", height_scale: float = 1.0, extent=None, resample: bool = False) -> Surface:
    """A :class:`Surface` from a mesh file, a height-map image, a ``trimesh.Trimesh``,
    a :class:`~axialdeform.core.mesh.BaseMesh` or a 2-D height array.  A height-map image has at most
    :func:`pixel_limit` ``("heightmap")`` pixels (checked before decoding); ``resample`` reads a larger one at
    the largest resolution within it."""
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
            grey = _read_grey(path, "SURFACE", SURFACE_BYTES_PER_PIXEL, kind="heightmap", resample=resample)
            return surface_from_heights(grey, up=up, height_scale=height_scale,
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
        grey = _read_grey(Path(source), "density", kind="density")
    else:
        grey = _grid(source, name)
    if grey.size == 0:
        raise ScatterError(f"density {name}: the image has no pixels; expected a grey image")
    if grey.min() < 0 or grey.max() > 1:
        raise ScatterError(f"density {name}: grey levels must lie in [0, 1], found {grey.min():g}..{grey.max():g}")
    if not (grey > 0).any():
        raise ScatterError(f"density {name}: every pixel is black; expected some non-black pixel (black = none, white = full)")
    return grey


def load_mask(path) -> np.ndarray:
    """A generated layer's painted mask (:mod:`~axialdeform.core.brush`): (rows, cols) float32 grey levels in
    [0, 1] from an image path; unlike a density map it may be all black (everything erased)."""
    grey = _read_grey(Path(path), "mask", kind="density")
    if grey.size == 0:
        raise ScatterError(f"mask {path}: the image has no pixels; expected a grey image")
    return grey.astype(np.float32)


def density_at(grey: np.ndarray, points: np.ndarray, surface: Surface) -> np.ndarray:
    """Nearest-pixel grey level under each point: (k, 3) -> (k,)."""
    rows, cols = grey.shape
    lo, hi = surface.bounds
    g0, g1 = surface.ground
    span = np.where(hi - lo > 0, hi - lo, 1.0)
    c = np.clip(np.floor((points[:, g0] - lo[g0]) / span[g0] * cols), 0, cols - 1).astype(np.int64)
    r = np.clip(np.floor((points[:, g1] - lo[g1]) / span[g1] * rows), 0, rows - 1).astype(np.int64)
    return grey[r, c]

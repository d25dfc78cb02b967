"""Step 2 of the data flow: the control axis of a base mesh.

Conventions (``docs/method.md``, "The control axis"; thesis §2.2.1):

* the axis ``a`` is the coordinate with the longest bounding-box extent;
  ties go to the first of x, y, z;
* ``lo``/``hi`` are the min/max of that coordinate and ``L = hi - lo``;
  ``L == 0`` is an error;
* five control points split the segment into four equal parts;
* each control point moves only perpendicular to the axis; its 2-component
  offset is in the other two coordinates in increasing order
  (x -> (y, z), y -> (x, z), z -> (x, y)).

A chosen axis frame (``docs/method.md``, "A chosen axis frame"): a 3×3
orthogonal matrix ``F`` whose rows are ``e_a, e_u, e_v``; the bend happens
in the local coordinates ``ℓ = F·V`` exactly as for axis x and goes back by
``Fᵀ``.  ``auto`` (the rule above), ``x``, ``y`` and ``z`` are permutation
frames and keep the index path bit for bit; ``oriented`` (the minimum-volume
oriented box) and a user's matrix give a *framed* axis (``index == -1``).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

from .errors import ArgumentError, MeshError

#: a digest hashes numbers as whole multiples of this (of a unit vector, or of a length relative to the
#: mesh's axis length): far above float64 noise, far below any change that matters
DIGEST_STEP = 1e-9


def stable_bytes(values) -> bytes:
    """``values`` (any shape of numbers of order 1: unit vectors, lengths relative to L) rounded to whole
    multiples of :data:`DIGEST_STEP`, as little-endian int64: what a digest hashes, so that numbers
    computed a last bit differently on another machine (another BLAS kernel, another numpy) give the same
    digest."""
    flat = np.asarray(values, dtype=np.float64).ravel()
    return np.round(flat / DIGEST_STEP).astype("<i8").tobytes()

__all__ = ["ControlAxis", "AXIS_NAMES", "PERPENDICULAR", "FRAME_NAMES", "axis_frame_matrix"]

AXIS_NAMES = ("x", "y", "z")
#: the two coordinates an offset moves, per axis index, in increasing order
PERPENDICULAR = ((1, 2), (0, 2), (0, 1))
#: supported range of the axis length L (model units): float32 keeps full
#: precision for the deformation of meshes of this size (see docs/reliability.md)
MIN_LENGTH = 1e-30
MAX_LENGTH = 1e36
#: the named frames ``load_mesh(axis=...)`` takes (or a 3×3 matrix)
FRAME_NAMES = ("auto", "x", "y", "z", "oriented")
#: how far from orthogonal a given frame may be: ``|FᵀF − I| <= FRAME_TOLERANCE``
FRAME_TOLERANCE = 1e-6


def _permutation(index: int) -> np.ndarray:
    """The frame of an axis-aligned axis: rows ``e_a, e_u, e_v`` (3, 3) float64."""
    return np.eye(3)[[index, *PERPENDICULAR[index]]]


def axis_frame_matrix(frame, name: str = "axis") -> np.ndarray:
    """A user's frame as a checked (3, 3) float64 matrix (rows ``e_a, e_u, e_v``):
    finite, orthogonal to :data:`FRAME_TOLERANCE`, determinant ±1; else :class:`ArgumentError`."""
    try:
        f = np.asarray(frame, dtype=np.float64)
    except (TypeError, ValueError):
        raise ArgumentError(f"{name}: expected one of {', '.join(FRAME_NAMES)} or a 3×3 matrix, found {frame!r}") from None
    if f.shape != (3, 3):
        raise ArgumentError(f"{name}: expected one of {', '.join(FRAME_NAMES)} or a 3×3 matrix of finite numbers "
                            f"(rows e_a, e_u, e_v), found shape {f.shape}")
    if not np.isfinite(f).all():
        row, col = (int(x) for x in np.argwhere(~np.isfinite(f))[0])
        raise ArgumentError(f"{name}: row {row + 1}, column {col + 1} of the frame is {f[row, col]}; expected a 3×3 "
                            "matrix of finite numbers (rows e_a, e_u, e_v)")
    err = float(np.abs(f @ f.T - np.eye(3)).max())
    if err > FRAME_TOLERANCE:
        raise ArgumentError(f"{name}: the frame is not orthogonal (|F·Fᵀ − I| = {err:.3g}); expected orthonormal rows "
                            f"e_a, e_u, e_v to {FRAME_TOLERANCE:g}")
    return f


def _oriented_frame(points: np.ndarray, name: str = "<mesh>") -> np.ndarray:
    """The frame of the minimum-volume oriented bounding box (trimesh): ``e_a``
    its longest edge, ``e_u``, ``e_v`` the others in decreasing length, each
    row's largest-magnitude component made positive."""
    import trimesh  # only this frame needs it

    p = np.asarray(points, dtype=np.float64)
    centred = p - p.mean(axis=0)
    _, sv, basis = np.linalg.svd(centred, full_matrices=False)  # sv descending; rows of basis: principal axes
    sv = np.concatenate([sv, np.zeros(3 - len(sv))])
    # float32 coordinates carry ~6e-8 relative rounding: a spread below 1e-6 of the length is rounding
    if not sv[0] > 0 or sv[1] <= 1e-6 * sv[0]:  # a point or a line: no box has a second side
        raise MeshError(f"{name}: axis: 'oriented' needs points spanning an area or a volume; these lie on a line "
                            "(use 'auto', 'x', 'y', 'z' or a frame of three rows)")
    if sv[2] <= 1e-6 * sv[0]:
        # flat: the minimum-area rectangle in the points' plane (trimesh's 2-D rule), the normal third
        plane = basis[:2] if len(basis) >= 2 else basis
        to_origin2, extents2 = trimesh.bounds.oriented_bounds_2D(centred @ plane.T)
        across = np.asarray(to_origin2, dtype=np.float64)[:2, :2] @ plane  # the rectangle's sides, 3-D rows
        normal = np.cross(across[0], across[1])
        rows = np.vstack([across, normal / np.linalg.norm(normal)])
        extents = np.array([*np.asarray(extents2, dtype=np.float64), 0.0])
    else:
        try:
            to_origin, extents = trimesh.bounds.oriented_bounds(p)
        except Exception as exc:  # noqa: BLE001  qhull, or trimesh's repair of a sliver hull (networkx)
            raise MeshError(f"{name}: axis: 'oriented' found no box for these points ({type(exc).__name__}: "
                            f"{str(exc).splitlines()[0][:120] if str(exc) else 'no message'}); use 'auto', 'x', "
                            "'y', 'z' or a frame of three rows") from None
        rows = np.asarray(to_origin, dtype=np.float64)[:3, :3]  # box axes (model space) as rows
    rows = rows[np.argsort(-np.asarray(extents), kind="stable")]
    sign = np.sign(rows[np.arange(3), np.argmax(np.abs(rows), axis=1)])
    rows = rows * sign[:, None]
    # exactly orthonormal in float64 (trimesh's matrix is, to rounding)
    u, _, vt = np.linalg.svd(rows)
    return u @ vt


@dataclass(frozen=True)
class ControlAxis:
    """The straight control axis of a base mesh.

    Attributes
    ----------
    index : int
        0, 1 or 2 for x, y, z; -1 for a framed axis (``frame``).
    lo : float
        Smallest coordinate of the mesh along the axis (model units; for a
        framed axis, of the local coordinate ``(F·V)₀``).
    length : float
        ``L = hi - lo`` (model units), > 0.
    center : (3,) tuple of float
        Centre of the mesh's bounding box; the straight axis runs through it
        (where it runs does not change the deformation, only ``index``,
        ``lo`` and ``length`` do).  For a framed axis, the centre of the
        box of the local coordinates, in model space (``Fᵀ·c``).
    frame : (3, 3) tuple of float or None
        The rows ``e_a, e_u, e_v`` of a chosen frame; None for an
        axis-aligned axis (its frame is the permutation :attr:`matrix`).
    kind : str
        How the frame was chosen: ``auto``, ``x``, ``y``, ``z``, ``oriented``
        or ``matrix`` (informative; equality compares the numbers).
    """

    index: int
    lo: float
    length: float
    center: tuple = (0.0, 0.0, 0.0)
    frame: tuple | None = None
    kind: str = field(default="auto", compare=False)

    def __post_init__(self) -> None:
        if self.frame is not None:
            f = axis_frame_matrix(self.frame)
            object.__setattr__(self, "frame", tuple(tuple(float(x) for x in row) for row in f))
            if self.index != -1:
                raise MeshError(f"a framed axis has index -1, found {self.index!r}")
        elif self.index not in (0, 1, 2):
            raise MeshError(f"axis index must be 0, 1 or 2 (x, y, z), found {self.index!r}")
        if not (np.isfinite(self.lo) and np.isfinite(self.length) and self.length > 0):
            raise MeshError(f"axis length must be a finite number > 0, found L={self.length!r} (lo={self.lo!r})")

    @classmethod
    def from_positions(cls, positions: np.ndarray, name: str = "<mesh>", frame="auto") -> ControlAxis:
        """The axis of a vertex set; ``positions`` is (n, 3); ``frame`` one of
        :data:`FRAME_NAMES` or a 3×3 matrix (rows ``e_a, e_u, e_v``)."""
        p = np.asarray(positions, dtype=np.float64)
        kind = frame if isinstance(frame, str) else "matrix"
        if isinstance(frame, str):
            if frame not in FRAME_NAMES:
                raise ArgumentError(f"{name}: axis: expected one of {', '.join(FRAME_NAMES)} or a 3×3 matrix, found {frame!r}")
            if frame == "oriented":
                matrix = _oriented_frame(p, name)
            else:
                matrix = None
        else:
            matrix = axis_frame_matrix(frame, f"{name}: axis")
        if matrix is not None:  # a permutation frame is an aligned axis: the index path, bit for bit
            for index in range(3):
                if np.array_equal(matrix, _permutation(index)):
                    matrix, frame = None, AXIS_NAMES[index]
                    break
        if matrix is not None:
            local = p @ matrix.T
            mins, maxs = local.min(axis=0), local.max(axis=0)
            length = float(maxs[0] - mins[0])
            cls._check_length(length, name, kind)
            center = matrix.T @ ((mins + maxs) / 2)
            return cls(index=-1, lo=float(mins[0]), length=length, center=tuple(float(c) for c in center),
                       frame=tuple(map(tuple, matrix)), kind=kind)
        mins, maxs = p.min(axis=0), p.max(axis=0)
        extents = maxs - mins
        if frame == "auto":
            index = int(np.argmax(extents))  # argmax returns the first of equal maxima: x, then y, then z
        else:
            index = AXIS_NAMES.index(frame)
        length = float(extents[index])
        cls._check_length(length, name, AXIS_NAMES[index], auto=frame == "auto")
        return cls(index=index, lo=float(mins[index]), length=length, center=tuple(float(c) for c in (mins + maxs) / 2),
                   kind=kind)

    @staticmethod
    def _check_length(length: float, name: str, which: str, auto: bool = False) -> None:
        if not length > 0:
            extent = "longest extent" if auto else f"extent along its axis ({which})"
            raise MeshError(f"{name}: the mesh's {extent} is {length}; expected a mesh that is not a single point"
                            + ("" if auto else " nor flat across that axis"))
        # the GPU works in float32: below MIN_LENGTH the curve terms (offsets x weights)
        # become subnormal and are flushed to zero; above MAX_LENGTH positions overflow
        if not (MIN_LENGTH <= length <= MAX_LENGTH):
            raise MeshError(
                f"{name}: the mesh's longest extent L={length:.6g} ({which}) is outside the supported range "
                f"{MIN_LENGTH:g}..{MAX_LENGTH:g} model units (float32 on the GPU); expected a mesh rescaled into it"
            )

    @property
    def framed(self) -> bool:
        """True for a chosen frame that is not axis-aligned (``index == -1``)."""
        return self.frame is not None

    @property
    def matrix(self) -> np.ndarray:
        """(3, 3) float64: the frame's rows ``e_a, e_u, e_v`` (a permutation for an aligned axis)."""
        return np.array(self.frame, dtype=np.float64) if self.frame is not None else _permutation(self.index)

    @property
    def direction(self) -> np.ndarray:
        """(3,) float64: the axis direction ``e_a`` in model space."""
        return self.matrix[0]

    @property
    def line(self) -> tuple[float, float]:
        """The axis line: the box centre across the axis, in offset order
        (``(F·c)₁, (F·c)₂``); twist and taper turn about it."""
        c = self.matrix @ np.asarray(self.center, dtype=np.float64)
        return float(c[1]), float(c[2])

    @property
    def frame_digest(self) -> bytes:
        """16 bytes identifying the frame: SHA-256 of its rows rounded to 1e-9
        (:func:`stable_bytes`: the same on every machine, where the float64 rows' last bits depend on the
        BLAS kernel that computed them); all zero for an aligned axis (files record it,
        ``docs/parameter-files.md``)."""
        if self.frame is None:
            return bytes(16)
        return hashlib.sha256(stable_bytes(self.frame)).digest()[:16]

    @property
    def legacy_frame_digest(self) -> bytes:
        """The digest files written before 0.2 record (SHA-256 of the float64 rows' bits): still read."""
        if self.frame is None:
            return bytes(16)
        return hashlib.sha256(np.asarray(self.frame, dtype="<f8").tobytes()).digest()[:16]

    def local(self, positions: np.ndarray) -> np.ndarray:
        """``ℓ = F·V``: (..., 3) -> (..., 3) float64 local coordinates (axis first)."""
        return np.asarray(positions, dtype=np.float64) @ self.matrix.T

    def local_axis(self) -> ControlAxis:
        """This axis in its own local coordinates: axis x, the same ``lo``, ``L``
        (for an aligned axis, itself)."""
        if self.frame is None:
            return self
        return ControlAxis(index=0, lo=self.lo, length=self.length,
                           center=tuple(float(c) for c in self.matrix @ np.asarray(self.center)))

    def across(self, vectors: np.ndarray) -> np.ndarray:
        """The two components across the axis, in offset order: (..., 3) -> (..., 2)
        (the inverse of :meth:`embed` on vectors across the axis)."""
        v = np.asarray(vectors)
        if self.frame is None:
            i, j = self.perpendicular
            return np.stack([v[..., i], v[..., j]], axis=-1)
        return v @ self.matrix[1:].T

    @property
    def name(self) -> str:
        return AXIS_NAMES[self.index] if self.frame is None else self.kind

    @property
    def hi(self) -> float:
        return self.lo + self.length

    @property
    def perpendicular(self) -> tuple[int, int]:
        """The two coordinates an offset ``(u, v)`` moves, e.g. ``(0, 2)`` for y
        (an aligned axis only: a framed one moves along ``e_u, e_v``, :meth:`embed`)."""
        if self.frame is not None:
            raise MeshError(f"a framed axis ({self.kind}) has no perpendicular coordinates; use embed()/across()")
        return PERPENDICULAR[self.index]

    @property
    def control_points(self) -> np.ndarray:
        """(5, 3) float64: the undeformed control points P1..P5 on the straight axis."""
        pts = np.repeat((self.matrix @ np.asarray(self.center, dtype=np.float64))[None, :], 5, axis=0)
        pts[:, 0] = self.lo + self.length * np.linspace(0.0, 1.0, 5)
        return pts @ self.matrix

    def parameter(self, positions: np.ndarray) -> np.ndarray:
        """``t = ((F·V)₀ - lo) / L`` clamped to [0, 1] (aligned: ``V[a]``);
        ``positions`` (n, 3) -> (n,) float64."""
        p = np.asarray(positions, dtype=np.float64)
        if p.ndim == 0 or p.shape[-1] != 3:

            raise ArgumentError(f"positions: expected an array of shape (n, 3), found {p.shape}")
        along = p[..., self.index] if self.frame is None else p @ self.matrix[0]
        return np.clip((along - self.lo) / self.length, 0.0, 1.0)

    def embed(self, uv: np.ndarray) -> np.ndarray:
        """Place 2-component offsets ``(..., 2)`` into 3D ``(..., 3)`` (the map
        ``E``; framed: ``u·e_u + v·e_v``)."""
        uv = np.asarray(uv)
        if self.frame is not None:
            return uv @ self.matrix[1:]
        out = np.zeros(uv.shape[:-1] + (3,), dtype=uv.dtype)
        i, j = self.perpendicular
        out[..., i] = uv[..., 0]
        out[..., j] = uv[..., 1]
        return out

    def describe(self) -> str:
        if self.frame is not None:
            rows = "; ".join(" ".join(f"{x:.6g}" for x in row) for row in self.frame)
            return f"axis frame {self.kind} [{rows}], lo={self.lo:.9g}, L={self.length:.9g}"
        return f"axis {self.name}, lo={self.lo:.9g}, L={self.length:.9g}"

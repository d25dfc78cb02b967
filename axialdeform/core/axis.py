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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ArgumentError, MeshError

__all__ = ["ControlAxis", "AXIS_NAMES", "PERPENDICULAR"]

AXIS_NAMES = ("x", "y", "z")
#: the two coordinates an offset moves, per axis index, in increasing order
PERPENDICULAR = ((1, 2), (0, 2), (0, 1))
#: supported range of the axis length L (model units): float32 keeps full
#: precision for the deformation of meshes of this size (see docs/reliability.md)
MIN_LENGTH = 1e-30
MAX_LENGTH = 1e36


@dataclass(frozen=True)
class ControlAxis:
    """The straight control axis of a base mesh.

    Attributes
    ----------
    index : int
        0, 1 or 2 for x, y, z.
    lo : float
        Smallest coordinate of the mesh along the axis (model units).
    length : float
        ``L = hi - lo`` (model units), > 0.
    center : (3,) tuple of float
        Centre of the mesh's bounding box; the straight axis runs through it
        (where it runs does not change the deformation, only ``index``,
        ``lo`` and ``length`` do).
    """

    index: int
    lo: float
    length: float
    center: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if self.index not in (0, 1, 2):
            raise MeshError(f"axis index must be 0, 1 or 2 (x, y, z), found {self.index!r}")
        if not (np.isfinite(self.lo) and np.isfinite(self.length) and self.length > 0):
            raise MeshError(f"axis length must be a finite number > 0, found L={self.length!r} (lo={self.lo!r})")

    @classmethod
    def from_positions(cls, positions: np.ndarray, name: str = "<mesh>") -> "ControlAxis":
        """The axis of a vertex set; ``positions`` is (n, 3)."""
        p = np.asarray(positions, dtype=np.float64)
        mins, maxs = p.min(axis=0), p.max(axis=0)
        extents = maxs - mins
        index = int(np.argmax(extents))  # argmax returns the first of equal maxima: x, then y, then z
        length = float(extents[index])
        if not length > 0:
            raise MeshError(f"{name}: the mesh's longest extent is {length}; expected a mesh that is not a single point")
        # the GPU works in float32: below MIN_LENGTH the curve terms (offsets x weights)
        # become subnormal and are flushed to zero; above MAX_LENGTH positions overflow
        if not (MIN_LENGTH <= length <= MAX_LENGTH):
            raise MeshError(
                f"{name}: the mesh's longest extent L={length:.6g} ({AXIS_NAMES[index]}) is outside the supported range "
                f"{MIN_LENGTH:g}..{MAX_LENGTH:g} model units (float32 on the GPU); expected a mesh rescaled into it"
            )
        return cls(index=index, lo=float(mins[index]), length=length, center=tuple(float(c) for c in (mins + maxs) / 2))

    @property
    def name(self) -> str:
        return AXIS_NAMES[self.index]

    @property
    def hi(self) -> float:
        return self.lo + self.length

    @property
    def perpendicular(self) -> tuple[int, int]:
        """The two coordinates an offset ``(u, v)`` moves, e.g. ``(0, 2)`` for y."""
        return PERPENDICULAR[self.index]

    @property
    def control_points(self) -> np.ndarray:
        """(5, 3) float64: the undeformed control points P1..P5 on the straight axis."""
        pts = np.repeat(np.asarray(self.center, dtype=np.float64)[None, :], 5, axis=0)
        pts[:, self.index] = self.lo + self.length * np.linspace(0.0, 1.0, 5)
        return pts

    def parameter(self, positions: np.ndarray) -> np.ndarray:
        """``t = (V[a] - lo) / L`` clamped to [0, 1]; ``positions`` (n, 3) -> (n,) float64."""
        p = np.asarray(positions, dtype=np.float64)
        if p.ndim == 0 or p.shape[-1] != 3:

            raise ArgumentError(f"positions: expected an array of shape (n, 3), found {p.shape}")
        return np.clip((p[..., self.index] - self.lo) / self.length, 0.0, 1.0)

    def embed(self, uv: np.ndarray) -> np.ndarray:
        """Place 2-component offsets ``(..., 2)`` into 3D ``(..., 3)`` (the map ``E``)."""
        uv = np.asarray(uv)
        out = np.zeros(uv.shape[:-1] + (3,), dtype=uv.dtype)
        i, j = self.perpendicular
        out[..., i] = uv[..., 0]
        out[..., j] = uv[..., 1]
        return out

    def describe(self) -> str:
        return f"axis {self.name}, lo={self.lo:.9g}, L={self.length:.9g}"

"""A camera that frames every instance, with pyrr matrices.

Matrix convention (pyrr's): matrices are ``(4, 4) float32`` as pyrr builds
them (``pyrr.matrix44.create_look_at`` / ``create_perspective_projection``);
their bytes are uploaded to GLSL ``mat4`` uniforms unchanged, and the shader
computes ``clip = u_proj * u_view * world``.
"""

from __future__ import annotations

import numpy as np
import pyrr

from ..core.params import ANGLES, OFFSETS, POSITION, as_params
from ..core.deform import rotation_matrices

__all__ = ["Camera", "instance_bounds", "frame_instances", "UP_VECTORS", "as_matrix"]

UP_VECTORS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def as_matrix(m, name: str = "matrix", invertible: bool = False) -> np.ndarray:
    """``m`` as a ``(4, 4) float32`` matrix of finite numbers, else
    :class:`~axialdeform.core.errors.ParamError`; with ``invertible`` a
    singular one (an all-zero view matrix) is refused too."""
    from ..core.errors import ParamError

    try:
        a = np.asarray(m, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ParamError(f"{name}: expected a (4, 4) matrix of numbers ({exc})") from None
    if a.shape not in ((4, 4), (16,)):
        raise ParamError(f"{name}: expected a (4, 4) matrix, found shape {a.shape}")
    a = a.reshape(4, 4)
    if not np.isfinite(a).all():
        raise ParamError(f"{name}: expected finite numbers, found {a[~np.isfinite(a)][0]}")
    if invertible:
        with np.errstate(all="ignore"):
            cond = np.linalg.cond(a)
        if not np.isfinite(cond) or cond > 1e12:
            raise ParamError(f"{name}: expected an invertible matrix (a camera), found a singular one "
                             f"(condition number {cond:.3g}), e.g. all zeros")
    return a.astype(np.float32)


class Camera:
    """A perspective camera: eye, target, up, vertical field of view (degrees)."""

    def __init__(self, eye, target, up=(0.0, 1.0, 0.0), fovy: float = 35.0, near: float = 0.01, far: float = 100.0):
        self.eye = np.asarray(eye, dtype=np.float64)
        self.target = np.asarray(target, dtype=np.float64)
        self.up = np.asarray(up, dtype=np.float64)
        self.fovy, self.near, self.far = float(fovy), float(near), float(far)

    def view(self) -> np.ndarray:
        """(4, 4) float32 view matrix (pyrr layout)."""
        return pyrr.matrix44.create_look_at(self.eye, self.target, self.up, dtype=np.float32)

    def projection(self, aspect: float) -> np.ndarray:
        """(4, 4) float32 projection matrix (pyrr layout)."""
        return pyrr.matrix44.create_perspective_projection(self.fovy, aspect, self.near, self.far, dtype=np.float32)


def instance_bounds(mesh, params) -> tuple[np.ndarray, np.ndarray]:
    """Bounding spheres of the deformed instances, without deforming them.

    Returns centres (n, 3) and radii (n,) float64 (world units).  The bend
    moves no vertex further than the largest offset (the weights sum to 1),
    and a rotation keeps distances, so each sphere holds its whole instance.
    """
    params = as_params(params).astype(np.float64)
    center = np.asarray(mesh.axis.center, dtype=np.float64)
    radius = float(np.linalg.norm(mesh.positions.astype(np.float64) - center, axis=1).max())
    bend = np.linalg.norm(params[:, OFFSETS].reshape(-1, 5, 2), axis=2).max(axis=1)
    centers = np.einsum("nij,j->ni", rotation_matrices(params[:, ANGLES]), center) + params[:, POSITION]
    return centers, radius + bend


def frame_instances(mesh, params, aspect: float, up: str = "y", fovy: float = 35.0,
                    azimuth: float = 35.0, elevation: float = 35.0, margin: float = 0.03) -> Camera:
    """A camera that sees every instance, looking down at ``elevation`` degrees.

    The eye is placed on the view direction just far enough that all eight
    corners of the box around the instances' bounding spheres project inside
    the picture (with ``margin`` as a fraction of the field of view).
    """
    centers, radii = instance_bounds(mesh, params)
    if len(centers) == 0:
        lo, hi = np.full(3, -1.0), np.full(3, 1.0)
    else:
        lo = (centers - radii[:, None]).min(axis=0)
        hi = (centers + radii[:, None]).max(axis=0)
    target = (lo + hi) / 2
    up_vec = np.asarray(UP_VECTORS[up])
    side = np.roll(up_vec, 1)
    fwd = np.cross(side, up_vec)
    az, el = np.radians(azimuth), np.radians(elevation)
    to_eye = np.cos(el) * (np.cos(az) * fwd + np.sin(az) * side) + np.sin(el) * up_vec
    right = np.cross(up_vec, to_eye)
    right /= np.linalg.norm(right)
    cam_up = np.cross(to_eye, right)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) - target
    tan_y = np.tan(np.radians(fovy) / 2) * (1 - margin)
    tan_x = tan_y * aspect
    depth = corners @ to_eye  # towards the eye
    need = np.maximum(np.abs(corners @ right) / tan_x, np.abs(corners @ cam_up) / tan_y) + depth
    distance = max(float(need.max()), 1e-6)
    extent = float(np.linalg.norm(hi - lo)) / 2 + 1e-9
    eye = target + to_eye * distance
    return Camera(eye, target, up_vec, fovy, near=max(distance - extent * 1.05, distance * 1e-3),
                  far=distance + extent * 1.05)

"""A camera that frames every instance, with pyrr matrices.

Matrix convention (pyrr's): matrices are ``(4, 4) float32`` as pyrr builds
them (``pyrr.matrix44.create_look_at`` / ``create_perspective_projection``);
their bytes are uploaded to GLSL ``mat4`` uniforms unchanged, and the shader
computes ``clip = u_proj * u_view * world``.
"""

from __future__ import annotations

import numpy as np
import pyrr

from ..core.bounds import box_corners, instance_bounds, scene_box

__all__ = ["Camera", "frame_instances", "UP_VECTORS"]

UP_VECTORS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


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


def frame_instances(mesh, params, aspect: float, up: str = "y", fovy: float = 35.0,
                    azimuth: float = 35.0, elevation: float = 35.0, margin: float = 0.03) -> Camera:
    """A camera that sees every instance, looking down at ``elevation`` degrees.

    The eye is placed on the view direction just far enough that all eight
    corners of the box around the instances' bounding spheres project inside
    the picture (with ``margin`` as a fraction of the field of view).
    """
    lo, hi = scene_box(mesh, params)
    target = (lo + hi) / 2
    up_vec = np.asarray(UP_VECTORS[up])
    side = np.roll(up_vec, 1)
    fwd = np.cross(side, up_vec)
    az, el = np.radians(azimuth), np.radians(elevation)
    to_eye = np.cos(el) * (np.cos(az) * fwd + np.sin(az) * side) + np.sin(el) * up_vec
    right = np.cross(up_vec, to_eye)
    right /= np.linalg.norm(right)
    cam_up = np.cross(to_eye, right)
    corners = box_corners(lo, hi) - target
    tan_y = np.tan(np.radians(fovy) / 2) * (1 - margin)
    tan_x = tan_y * aspect
    depth = corners @ to_eye  # towards the eye
    need = np.maximum(np.abs(corners @ right) / tan_x, np.abs(corners @ cam_up) / tan_y) + depth
    distance = max(float(need.max()), 1e-6)
    extent = float(np.linalg.norm(hi - lo)) / 2 + 1e-9
    eye = target + to_eye * distance
    return Camera(eye, target, up_vec, fovy, near=max(distance - extent * 1.05, distance * 1e-3),
                  far=distance + extent * 1.05)

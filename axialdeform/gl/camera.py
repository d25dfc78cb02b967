"""A camera that frames every instance, with pyrr matrices.

Matrix convention (pyrr's): matrices are ``(4, 4) float32`` as pyrr builds
them (``pyrr.matrix44.create_look_at`` / ``create_perspective_projection``);
their bytes are uploaded to GLSL ``mat4`` uniforms unchanged, and the shader
computes ``clip = u_proj * u_view * world``.
"""

from __future__ import annotations

import numpy as np
import pyrr

from ..core.bounds import outline_points, scene_box
from ..core.arrays import as_array
from ..core.errors import ArgumentError

__all__ = ["Camera", "OrbitCamera", "frame_instances", "frame_points", "orbit_axes", "UP_VECTORS"]

UP_VECTORS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


class Camera:
    """A perspective camera: eye, target, up, vertical field of view (degrees)."""

    def __init__(self, eye, target, up=(0.0, 1.0, 0.0), fovy: float = 35.0, near: float = 0.01, far: float = 100.0):
        self.eye = as_array(eye, (3,), "eye")
        self.target = as_array(target, (3,), "target")
        self.up = as_array(up, (3,), "up")
        self.fovy, self.near, self.far = float(fovy), float(near), float(far)

    def view(self) -> np.ndarray:
        """(4, 4) float32 view matrix (pyrr layout)."""
        return pyrr.matrix44.create_look_at(self.eye, self.target, self.up, dtype=np.float32)

    def projection(self, aspect: float) -> np.ndarray:
        """(4, 4) float32 projection matrix (pyrr layout)."""
        return pyrr.matrix44.create_perspective_projection(self.fovy, aspect, self.near, self.far, dtype=np.float32)


def orbit_axes(up: str, azimuth: float, elevation: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The camera's unit axes for an orbit around world ``up`` (``"x"``, ``"y"``
    or ``"z"``) at ``azimuth`` and ``elevation`` degrees: ``to_eye``,
    ``right`` and ``cam_up``, each ``(3,) float64``."""
    if up not in UP_VECTORS:
        raise ArgumentError(f"up: expected one of x, y, z, found {up!r}")
    up_vec = np.asarray(UP_VECTORS[up])
    side = np.roll(up_vec, 1)
    fwd = np.cross(side, up_vec)
    az, el = np.radians(azimuth), np.radians(elevation)
    to_eye = np.cos(el) * (np.cos(az) * fwd + np.sin(az) * side) + np.sin(el) * up_vec
    right = np.cross(up_vec, to_eye)
    right /= max(np.linalg.norm(right), 1e-12)
    return to_eye, right, np.cross(to_eye, right)


def frame_points(points, radii, up: str, azimuth: float, elevation: float, aspect: float, fovy: float = 35.0,
                 margin: float = 0.03) -> tuple[np.ndarray, float]:
    """Target and distance of an orbit camera that just sees every sphere.

    points : (m, 3) float; radii : (m,) float (0 for points).
    The eye looks along ``-to_eye`` (:func:`orbit_axes`); it is placed as
    close as it can be with every sphere inside the picture less ``margin``
    (a fraction of the field of view), and the target is moved sideways so
    that the outline is centred.  Returns ``target : (3,) float64`` and the
    distance.
    """
    pts = as_array(points, (None, 3), "points")
    r = as_array(radii, (len(pts),), "radii")
    if not 0.0 <= margin < 1.0:
        raise ArgumentError(f"margin: expected a fraction in [0, 1), found {margin!r}")
    if aspect <= 0 or not 0 < fovy < 180:
        raise ArgumentError(f"camera: expected aspect > 0 and 0 < fovy < 180, found aspect {aspect!r}, fovy {fovy!r}")
    if len(pts) == 0:
        pts, r = np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]), np.zeros(2)
    to_eye, right, cam_up = orbit_axes(up, azimuth, elevation)
    tan_y = np.tan(np.radians(fovy) / 2) * (1 - margin)
    tan_x = tan_y * aspect
    sin_x, sin_y = tan_x / np.hypot(1.0, tan_x), tan_y / np.hypot(1.0, tan_y)
    target = ((pts - r[:, None]).min(axis=0) + (pts + r[:, None]).max(axis=0)) / 2

    def fit(target):
        rel = pts - target
        x, y, z = rel @ right, rel @ cam_up, rel @ to_eye
        need = z + np.maximum(np.abs(x) / tan_x + r / sin_x, np.abs(y) / tan_y + r / sin_y)
        return x, y, z, max(float(need.max()), 1e-9)

    for _ in range(6):  # centre the projected outline: a few fixed-point steps
        x, y, z, d = fit(target)
        depth = np.maximum(d - z, 1e-12)
        u = ((x - r) / depth).min() + ((x + r) / depth).max()
        v = ((y - r) / depth).min() + ((y + r) / depth).max()
        target = target + (right * u + cam_up * v) * (d / 2)
    return target, fit(target)[3]


def frame_instances(mesh, params, aspect: float, up: str = "y", fovy: float = 35.0,
                    azimuth: float = 35.0, elevation: float = 35.0, margin: float = 0.03) -> Camera:
    """A camera that sees every instance and fills the picture, looking down
    at ``elevation`` degrees.

    The deformed instances' outline (:func:`axialdeform.core.bounds.outline_points`)
    is centred and the eye placed just far enough that it fits the picture's
    width or height less ``margin`` (a fraction of the field of view).
    """
    points, radii = outline_points(mesh, params)
    target, distance = frame_points(points, radii, up, azimuth, elevation, aspect, fovy, margin)
    to_eye = orbit_axes(up, azimuth, elevation)[0]
    eye = target + to_eye * distance
    if len(points):
        depth = (eye - points) @ to_eye
        near, far = float((depth - radii).min()), float((depth + radii).max())
    else:
        near, far = distance * 0.5, distance * 2.0
    return Camera(eye, target, UP_VECTORS[up], fovy, near=max(near * 0.95, distance * 1e-3), far=max(far * 1.05, distance * 1e-3 * 2))


class OrbitCamera:
    """A camera that turns around a target: ``azimuth`` and ``elevation``
    (degrees) about world ``up``, at ``distance``; the viewer's camera.

    ``extent`` (world units, half the size of the scene) sets how far the
    near and far planes reach (three times it) and how far it may zoom.
    """

    def __init__(self, target, distance: float, azimuth: float = 35.0, elevation: float = 35.0, up: str = "y",
                 fovy: float = 35.0, extent: float = 1.0):
        if up not in UP_VECTORS:
            raise ArgumentError(f"up: expected one of x, y, z, found {up!r}")
        self.target = as_array(target, (3,), "target")
        self.distance, self.azimuth, self.elevation = float(distance), float(azimuth), float(elevation)
        self.up, self.fovy, self.extent = up, float(fovy), float(extent)

    @classmethod
    def framing(cls, mesh, params, aspect: float, *, up: str = "y", fovy: float = 35.0, azimuth: float = 35.0,
                elevation: float = 35.0, margin: float = 0.03) -> "OrbitCamera":
        """The orbit that starts where :func:`frame_instances` puts the camera."""
        cam = frame_instances(mesh, params, aspect, up, fovy, azimuth, elevation, margin)
        lo, hi = scene_box(mesh, params)
        return cls(cam.target, float(np.linalg.norm(cam.eye - cam.target)), azimuth, elevation, up, fovy,
                   float(np.linalg.norm(hi - lo)) / 2 + 1e-6)

    @property
    def eye(self) -> np.ndarray:
        """(3,) float64 world position of the eye."""
        return self.target + self.distance * orbit_axes(self.up, self.azimuth, self.elevation)[0]

    def orbit(self, d_azimuth: float, d_elevation: float) -> None:
        """Turn by the given degrees; elevation stays within -5..89."""
        self.azimuth = (self.azimuth + float(d_azimuth)) % 360.0
        self.elevation = float(np.clip(self.elevation + float(d_elevation), -5.0, 89.0))

    def zoom(self, factor: float) -> None:
        """Multiply the distance by ``factor`` (within 0.001..50 extents)."""
        self.distance = float(np.clip(self.distance * float(factor), 1e-3 * self.extent, 50.0 * self.extent))

    def camera(self) -> Camera:
        reach = self.extent * 3.0  # the ground reaches past the instances
        return Camera(self.eye, self.target, UP_VECTORS[self.up], self.fovy,
                      near=max(self.distance - reach, self.distance * 2e-3), far=self.distance + reach)

    def matrices(self, aspect: float) -> tuple[np.ndarray, np.ndarray]:
        """``(view, projection)``, (4, 4) float32 pyrr layout."""
        cam = self.camera()
        return cam.view(), cam.projection(aspect)

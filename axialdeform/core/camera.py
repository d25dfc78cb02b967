"""The camera: one that frames every instance, with pyrr matrices, and what a scene file says of
its camera (:class:`CameraSpec`).  Pure numpy and pyrr: no GL here.

Matrix convention (pyrr's): matrices are ``(4, 4) float32`` as pyrr builds
them (``pyrr.matrix44.create_look_at`` / ``create_perspective_projection``);
their bytes are uploaded to GLSL ``mat4`` uniforms unchanged, and the shader
computes ``clip = u_proj * u_view * world``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyrr

from .arrays import as_array
from .bounds import outline_points, scene_box, sphere_box
from .errors import ArgumentError

__all__ = ["Camera", "CameraSpec", "FOVY", "AZIMUTH", "ELEVATION", "camera_for_points", "OrbitCamera",
           "frame_instances", "frame_points", "orbit_axes", "UP_VECTORS"]

UP_VECTORS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
#: the default vertical field of view, and the orbit's azimuth and elevation, degrees
FOVY = AZIMUTH = ELEVATION = 35.0


@dataclass(frozen=True)
class CameraSpec:
    """What a scene file says of its camera (``[camera]``): an orbit (``elevation``, ``azimuth``,
    degrees) that frames everything, or an explicit ``eye`` and ``target``; ``fov`` either way.

    :func:`axialdeform.gl.scene.scene_camera` turns it into a :class:`Camera` for an aspect.
    """

    elevation: float = ELEVATION
    azimuth: float = AZIMUTH
    fov: float = FOVY
    eye: tuple | None = None
    target: tuple | None = None

    def __post_init__(self):
        if (self.eye is None) != (self.target is None):
            raise ArgumentError("camera: eye and target go together; expected both or neither")


class Camera:
    """A perspective camera: eye, target, up, vertical field of view (degrees).

    Parameters
    ----------
    eye, target : (3,) float
        Where it stands and what it looks at, world units.
    up : (3,) float
        The world's up as the picture shows it.
    fovy : float
        Vertical field of view, degrees (default :data:`FOVY`).
    near, far : float
        The clipping planes' distances.
    """

    def __init__(self, eye, target, up=(0.0, 1.0, 0.0), fovy: float = FOVY, near: float = 0.01, far: float = 100.0):
        self.eye = as_array(eye, (3,), "eye")
        self.target = as_array(target, (3,), "target")
        self.up = as_array(up, (3,), "up")
        self.fovy, self.near, self.far = float(fovy), float(near), float(far)

    def view(self) -> np.ndarray:
        """(4, 4) float32 view matrix (pyrr layout)."""
        return pyrr.matrix44.create_look_at(self.eye, self.target, self.up, dtype=np.float32)

    def projection(self, aspect: float) -> np.ndarray:
        """(4, 4) float32 projection matrix (pyrr layout) for a picture of width / height ``aspect``."""
        return pyrr.matrix44.create_perspective_projection(self.fovy, aspect, self.near, self.far, dtype=np.float32)

    def enclosing_square(self, center, normal, half_side: float, aspect: float) -> Camera:
        """This camera with its near and far planes widened (never narrowed)
        so that the part of a square it sees lies between them.

        Parameters
        ----------
        center, normal : (3,) float
            The square's centre and its plane's normal.
        half_side : float
            Half the square's side; its sides run along the plane's axes
            (a square across a world axis, as :class:`GroundPlane` draws).
        aspect : float
            Width over height of the picture.

        Returns
        -------
        Camera
            A new camera (this one when the plane is not in view).

        Notes
        -----
        The far plane reaches the square's farthest corner; the near plane
        the nearest point where the view frustum's edges meet the plane
        (depth is linear over the plane, so the seen part's nearest point is
        one of those: a lower bound, never a cut).
        """
        center = as_array(center, (3,), "center")
        normal = as_array(normal, (3,), "normal")
        fwd = self.target - self.eye
        fwd /= max(np.linalg.norm(fwd), 1e-300)
        right = np.cross(fwd, self.up)
        right /= max(np.linalg.norm(right), 1e-300)
        cam_up = np.cross(right, fwd)
        ty = np.tan(np.radians(self.fovy) / 2)
        tx = ty * aspect
        # the four corner rays, scaled to unit depth along fwd
        rays = np.array([fwd + sx * tx * right + sy * ty * cam_up for sx in (-1, 1) for sy in (-1, 1)])
        dn = rays @ normal
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((center - self.eye) @ normal) / dn
        hits = t[(np.abs(dn) > 1e-12) & (t > 0)]
        if not len(hits):
            return self  # the plane is not in view
        a = np.argsort(np.abs(normal))[:2]  # the square's two in-plane world axes
        corners = np.array([center + half_side * (su * np.eye(3)[a[0]] + sv * np.eye(3)[a[1]])
                            for su in (-1, 1) for sv in (-1, 1)])
        far = float(((corners - self.eye) @ fwd).max())
        near = float(hits.min())
        return Camera(self.eye, self.target, self.up, self.fovy, near=min(self.near, 0.95 * near),
                      far=max(self.far, 1.05 * far))


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


#: points handled at once by :func:`frame_points` and :func:`camera_for_points`
_FRAME_BLOCK = 1 << 16


def frame_points(points, radii, up: str, azimuth: float, elevation: float, aspect: float, fovy: float = FOVY,
                 margin: float = 0.03) -> tuple[np.ndarray, float]:
    """Target and distance of an orbit camera that just sees every sphere.

    points : (m, 3) float; radii : (m,) float (0 for points).
    The eye looks along ``-to_eye`` (:func:`orbit_axes`).  Each side of the
    picture (less ``margin``, a fraction of the field of view) is a plane
    through the eye; a sphere is inside when it is on the inner side of all
    four by its radius (a negative ``margin`` lets the outline run past the
    edges: a close-up).  That is linear in the eye's position, so the
    closest eye is solved for directly: in the tighter direction the
    outline touches both sides, in the other it has equal room on both.
    Returns ``target : (3,) float64`` (on the view axis, level with the
    outline's centre) and the eye's distance from it.
    """
    sets = _point_sets(points, radii)
    if not margin < 1.0:
        raise ArgumentError(f"margin: expected a fraction below 1 (negative: crop past the edges), found {margin!r}")
    if not aspect > 0 or not 0 < fovy < 180:
        raise ArgumentError(f"camera: expected aspect > 0 and 0 < fovy < 180, found aspect {aspect!r}, fovy {fovy!r}")
    if not any(len(p) for p, _ in sets):
        sets = [(np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]), np.zeros(2))]
    # blocks of points and radii, each kept in its own dtype (float32 terrain
    # vertices are not copied: every product below is taken in float64, and a
    # float32 converts to float64 exactly, so the numbers are the same)
    blocks = [(p[s:s + _FRAME_BLOCK], r[s:s + _FRAME_BLOCK]) for p, r in sets for s in range(0, len(p), _FRAME_BLOCK)]
    count = sum(len(p) for p, _ in blocks)
    to_eye, right, cam_up = orbit_axes(up, azimuth, elevation)
    half_y = np.arctan(np.tan(np.radians(fovy) / 2) * (1 - margin))
    half_x = np.arctan(np.tan(half_y) * aspect)
    cx, sx, cy, sy = np.cos(half_x), np.sin(half_x), np.cos(half_y), np.sin(half_y)
    # inward normals of the right, left, top and bottom planes
    normals = np.stack([-cx * right - sx * to_eye, cx * right - sx * to_eye,
                        -cy * cam_up - sy * to_eye, cy * cam_up - sy * to_eye])
    # a sphere is inside plane k when (p - eye) . n_k >= r, i.e. eye . n_k <= c_k
    # (over blocks of points here and below: the same numbers without (m, 3) or
    # (m, 4) float64 temporaries -- a 1 500 x 1 500 terrain is 2.25 M points)
    c = np.min([(pb @ normals.T - rb[:, None]).min(axis=0) for pb, rb in blocks], axis=0)
    # eye = a right + b cam_up + e to_eye: the smallest e with room for a and b
    ex, ey = -(c[0] + c[1]) / (2 * sx), -(c[2] + c[3]) / (2 * sy)
    e = max(ex, ey)
    a = (c[1] - c[0]) / (2 * cx)
    b = (c[3] - c[2]) / (2 * cy)
    eye = a * right + b * cam_up + e * to_eye
    # the tighter direction touches both sides, so it is centred; the other has
    # equal room measured across the planes, not in the picture: centre it there
    slack_axis, half = (cam_up, half_y) if ex >= ey else (right, half_x)
    r = np.empty(count)
    k = 0
    for _, rb in blocks:
        r[k:k + len(rb)] = rb
        k += len(rb)

    def depth_across(at):
        depth, across = np.empty(count), np.empty(count)
        k = 0
        for pb, _ in blocks:
            rel = pb - at
            depth[k:k + len(pb)] = np.maximum(-(rel @ to_eye), 1e-12)
            across[k:k + len(pb)] = rel @ slack_axis
            k += len(pb)
        return depth, across

    for _ in range(3):
        depth, across = depth_across(eye)
        lo, hi = ((across - r) / depth).min(), ((across + r) / depth).max()
        shift = (lo + hi) / 2 * float(np.median(depth))
        moved = eye + shift * slack_axis
        depth, across = depth_across(moved)
        if ((np.abs(across) + r / np.cos(half)) / depth > np.tan(half) * (1 + 1e-9)).any():
            break  # would cut something off: keep the last placement
        eye = moved
    center = (np.min([(pb - rb[:, None]).min(axis=0) for pb, rb in blocks], axis=0)
              + np.max([(pb + rb[:, None]).max(axis=0) for pb, rb in blocks], axis=0)) / 2
    distance = max(float((eye - center) @ to_eye), 1e-9)
    return eye - distance * to_eye, distance


def _point_sets(points, radii) -> list[tuple[np.ndarray, np.ndarray]]:
    """``[(points (m, 3) float, radii (m,) float), ...]``: one array each, or
    lists of arrays (several sets framed together, never concatenated)."""
    if isinstance(points, (list, tuple)) and (len(points) == 0 or np.ndim(points[0]) == 2):
        if not isinstance(radii, (list, tuple)) or len(radii) != len(points):
            raise ArgumentError("radii: expected one array of radii per array of points")
        pairs = zip(points, radii)
    else:
        pairs = [(points, radii)]
    out = []
    for p, r in pairs:
        p = np.asarray(p)
        p = as_array(p, (None, 3), "points", p.dtype if p.dtype in (np.float32, np.float64) else np.float64)
        r = np.asarray(r)
        r = np.broadcast_to(r.astype(np.float64, copy=False), (len(p),)) if r.ndim == 0 else \
            as_array(r, (len(p),), "radii", r.dtype if r.dtype in (np.float32, np.float64) else np.float64)
        out.append((p, r))
    return out


def frame_instances(mesh, params, aspect: float, up: str = "y", fovy: float = FOVY,
                    azimuth: float = AZIMUTH, elevation: float = ELEVATION, margin: float = 0.03) -> Camera:
    """A camera that sees every instance and fills the picture, looking down at ``elevation`` degrees.

    Parameters
    ----------
    mesh : BaseMesh
    params : (n, 16|19|22) float32
    aspect : float
        The picture's width / height.
    up : {"x", "y", "z"}
    fovy, azimuth, elevation : float
        Degrees (defaults :data:`FOVY`, :data:`AZIMUTH`, :data:`ELEVATION`).
    margin : float
        A fraction of the field of view left free at the edges.

    Returns
    -------
    Camera
        The deformed instances' outline (:func:`axialdeform.core.bounds.outline_points`) centred and
        the eye placed just far enough that it fits the picture's width or height.
    """
    points, radii = outline_points(mesh, params)
    return camera_for_points(points, radii, aspect, up, fovy, azimuth, elevation, margin)


def camera_for_points(points, radii, aspect: float, up: str = "y", fovy: float = FOVY,
                      azimuth: float = AZIMUTH, elevation: float = ELEVATION, margin: float = 0.03) -> Camera:
    """The orbit camera that frames ``points`` (m, 3) with spheres of ``radii`` (m,)
    (:func:`frame_points`; or lists of such arrays, framed together), its near
    and far planes enclosing every sphere."""
    sets = _point_sets(points, radii)
    target, distance = frame_points([p for p, _ in sets], [r for _, r in sets], up, azimuth, elevation, aspect, fovy,
                                    margin)
    to_eye = orbit_axes(up, azimuth, elevation)[0]
    eye = target + to_eye * distance
    if any(len(p) for p, _ in sets):
        near, far = np.inf, -np.inf
        for p, r in sets:
            for s in range(0, len(p), _FRAME_BLOCK):
                depth = (eye - p[s:s + _FRAME_BLOCK]) @ to_eye
                near = min(near, float((depth - r[s:s + _FRAME_BLOCK]).min()))
                far = max(far, float((depth + r[s:s + _FRAME_BLOCK]).max()))
    else:
        near, far = distance * 0.5, distance * 2.0
    return Camera(eye, target, UP_VECTORS[up], fovy, near=max(near * 0.95, distance * 1e-3), far=max(far * 1.05, distance * 2e-3))


class OrbitCamera:
    """A camera that turns around a target: ``azimuth`` and ``elevation``
    (degrees) about world ``up``, at ``distance``; the viewer's camera.

    ``extent`` (world units, half the size of the scene) sets how far the
    near and far planes reach (three times it) and how far it may zoom.
    """

    def __init__(self, target, distance: float, azimuth: float = AZIMUTH, elevation: float = ELEVATION, up: str = "y",
                 fovy: float = FOVY, extent: float = 1.0):
        if up not in UP_VECTORS:
            raise ArgumentError(f"up: expected one of x, y, z, found {up!r}")
        self.target = as_array(target, (3,), "target")
        self.distance, self.azimuth, self.elevation = float(distance), float(azimuth), float(elevation)
        self.up, self.fovy, self.extent = up, float(fovy), float(extent)

    @classmethod
    def framing(cls, mesh, params, aspect: float, *, up: str = "y", fovy: float = FOVY, azimuth: float = AZIMUTH,
                elevation: float = ELEVATION, margin: float = 0.03) -> OrbitCamera:
        """The orbit that starts where :func:`frame_instances` puts the camera."""
        cam = frame_instances(mesh, params, aspect, up, fovy, azimuth, elevation, margin)
        lo, hi = scene_box(mesh, params)
        return cls(cam.target, float(np.linalg.norm(cam.eye - cam.target)), azimuth, elevation, up, fovy,
                   float(np.linalg.norm(hi - lo)) / 2 + 1e-6)

    @classmethod
    def framing_spheres(cls, spheres, aspect: float, *, up: str = "y", fovy: float = FOVY, azimuth: float = AZIMUTH,
                        elevation: float = ELEVATION, margin: float = 0.03) -> OrbitCamera:
        """The orbit that frames ``spheres`` ((n, 4) x, y, z, r): instances known only by their bounds (a
        generated layer's, made on the GPU)."""
        spheres = np.asarray(spheres, dtype=np.float64).reshape(-1, 4)
        cam = camera_for_points(spheres[:, :3], spheres[:, 3], aspect, up, fovy, azimuth, elevation, margin)
        lo, hi = sphere_box(spheres[:, :3], spheres[:, 3])
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

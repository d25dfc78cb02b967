"""Setting uniforms: the camera's (``u_view``, ``u_proj``, ``u_eye``) and any
others, the one loop every program of the library goes through."""

from __future__ import annotations

import numpy as np

from ..core.arrays import as_array
from ..core.errors import ArgumentError

__all__ = ["camera_matrices", "eye_position", "set_uniforms", "set_camera_uniforms"]


def camera_matrices(view, projection) -> tuple[np.ndarray, np.ndarray]:
    """``view`` and ``projection`` checked as ``(4, 4) float32`` (pyrr layout)
    of finite numbers, ``view`` invertible (a camera; an all-zero matrix is
    not); anything else raises :class:`~axialdeform.core.errors.ArgumentError`."""

    out = []
    for m, name in ((view, "view"), (projection, "projection")):
        a = as_array(m, (4, 4), name, np.float64)
        if not np.isfinite(a).all():
            raise ArgumentError(f"{name}: expected finite numbers, found {a[~np.isfinite(a)][0]}")
        out.append(a)
    view = out[0]
    with np.errstate(all="ignore"):
        # an affine view (pyrr layout: last column 0 0 0 1) is invertible when its 3x3 part is;
        # its translation (a camera far from the origin) must not count against it
        affine = np.array_equal(view[:, 3], [0.0, 0.0, 0.0, 1.0])
        cond = np.linalg.cond(view[:3, :3] if affine else view)
    if not np.isfinite(cond) or cond > 1e12:
        raise ArgumentError(f"view: expected an invertible matrix (a camera), found a singular one "
                            f"(condition number {cond:.3g}), e.g. all zeros")
    return tuple(np.ascontiguousarray(a, dtype=np.float32) for a in out)


def set_uniforms(program, values: dict) -> None:
    """Set each ``name: value`` that ``program`` uses (the compiler drops
    unused uniforms); numpy arrays are written as float32 bytes."""
    for name, value in values.items():
        if name not in program:
            continue
        if isinstance(value, np.ndarray):
            program[name].write(np.ascontiguousarray(value, dtype=np.float32).tobytes())
        else:
            program[name].value = value


def eye_position(view) -> np.ndarray:
    """The camera's world position ``(3,) float64`` from a pyrr-layout view matrix."""
    return np.linalg.inv(np.asarray(view, dtype=np.float64).reshape(4, 4))[3, :3]  # pyrr layout: translation is the last row


def set_camera_uniforms(program, view, projection) -> tuple[np.ndarray, np.ndarray]:
    """``u_view``, ``u_proj`` and ``u_eye`` (the eye's world position, from
    the inverse view matrix).  Returns the checked ``(view, projection)``."""
    view, projection = camera_matrices(view, projection)
    eye = eye_position(view)
    set_uniforms(program, {"u_view": view, "u_proj": projection, "u_eye": tuple(eye)})
    return view, projection

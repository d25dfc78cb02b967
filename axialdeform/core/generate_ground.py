"""The ground a generated layer stands on (:class:`GroundMaps`: the height map and the density map) and the
float32 operations of ``glsl/generate.glsl`` that read it, in numpy, operation for operation: the ground's
height on a height map's triangles, a float32 cos/sin and atan2 (Cephes' atanf), and the leaning of an
instance toward the ground's normal -- what :mod:`axialdeform.core.generate` makes its records with, so
that numpy and the GPU write the same bits."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["GroundMaps", "density_area", "ground_height", "cos_sin_f32", "atan2_f32", "lean_angles"]


@dataclass(frozen=True, eq=False)
class GroundMaps:
    """What a generated layer stands on and where it grows: the scene's height map and the layer's density map.

    heights : (rows, cols) float32 or None
        World heights of the terrain's grid (vertex (row, col) at ``h_lo + (col, row) / h_inv``); None: y = 0.
    h_lo, h_inv : (2,) float32
        The grid's first vertex (x0, z0) and ``((cols - 1) / width, (rows - 1) / depth)``.
    density : (rows, cols) float32 or None
        Grey levels in [0, 1]: an instance is kept where ``u16 <`` its nearest pixel.
    d_lo, d_inv : (2,) float32
        The map's corner (x0, z0) and ``(cols / width, rows / depth)``.
    d_wrap : bool
        Repeated beyond the map (a flat endless world), else its edge pixels go on.
    """

    heights: np.ndarray | None = None
    h_lo: np.ndarray = field(default_factory=lambda: np.zeros(2, np.float32))
    h_inv: np.ndarray = field(default_factory=lambda: np.ones(2, np.float32))
    density: np.ndarray | None = None
    d_lo: np.ndarray = field(default_factory=lambda: np.zeros(2, np.float32))
    d_inv: np.ndarray = field(default_factory=lambda: np.ones(2, np.float32))
    d_wrap: bool = False

    @classmethod
    def of(cls, terrain=None, density=None, extent=None) -> GroundMaps:
        """From a height-map terrain (a BaseMesh or Surface with ``grid``) and a density map ((rows, cols) in [0, 1]):
        the density covers the terrain's ground, or without one the ``extent`` (x0, z0, x1, z1), repeated."""
        f32 = np.float32
        kw = {}
        if terrain is not None:
            rows, cols = terrain.grid
            pts = terrain.positions if hasattr(terrain, "positions") else terrain.vertices  # a BaseMesh or a Surface
            v = np.asarray(pts, np.float64).reshape(rows, cols, 3)
            x0, z0, x1, z1 = v[0, 0, 0], v[0, 0, 2], v[0, -1, 0], v[-1, 0, 2]
            kw.update(heights=np.ascontiguousarray(v[:, :, 1], f32), h_lo=np.array([x0, z0], f32),
                      h_inv=np.array([(cols - 1) / (x1 - x0), (rows - 1) / (z1 - z0)], f32))
        if density is not None:
            d = np.ascontiguousarray(density, f32)
            area, wrap = density_area(terrain, extent)
            kw.update(density=d, d_lo=np.array(area[:2], f32), d_wrap=wrap,
                      d_inv=np.array([d.shape[1] / (area[2] - area[0]), d.shape[0] / (area[3] - area[1])], f32))
        return cls(**kw)


def density_area(terrain=None, extent=None) -> tuple[tuple, bool]:
    """The ground a layer's density map (and its painted mask) covers, ``(x0, z0, x1, z1)``, and whether it
    repeats: a height-map terrain's ground (its corner vertices), or without one the ``extent``, repeated."""
    if terrain is not None:
        rows, cols = terrain.grid
        pts = terrain.positions if hasattr(terrain, "positions") else terrain.vertices  # a BaseMesh or a Surface
        v = np.asarray(pts, np.float64).reshape(rows, cols, 3)
        return (float(v[0, 0, 0]), float(v[0, 0, 2]), float(v[0, -1, 0]), float(v[-1, 0, 2])), False
    return tuple(float(e) for e in extent), True


def ground_height(g, xz: np.ndarray):
    """The ground's height (float32) on the height map's triangles, tan^2 of its slope, and whether xz is over it
    (axial_gen_height of glsl/generate.glsl, operation for operation)."""
    f32 = np.float32
    H = g.heights
    last = np.array([H.shape[1] - 1, H.shape[0] - 1], f32)
    gg = (xz - g.h_lo) * g.h_inv
    inside = ((gg >= 0) & (gg <= last)).all(axis=1)
    gg = np.clip(gg, f32(0), last)
    c = np.minimum(np.floor(gg).astype(np.int64), (last - 1).astype(np.int64))
    f = gg - c.astype(f32)
    h00, h01 = H[c[:, 1], c[:, 0]], H[c[:, 1], c[:, 0] + 1]
    h10, h11 = H[c[:, 1] + 1, c[:, 0]], H[c[:, 1] + 1, c[:, 0] + 1]
    lower = f[:, 0] + f[:, 1] <= f32(1)
    one = f32(1)
    h = np.where(lower, h00 + f[:, 0] * (h01 - h00) + f[:, 1] * (h10 - h00),
                 h11 + (one - f[:, 0]) * (h10 - h11) + (one - f[:, 1]) * (h01 - h11))
    gx = np.where(lower, h01 - h00, h11 - h10) * g.h_inv[0]
    gz = np.where(lower, h10 - h00, h11 - h01) * g.h_inv[1]
    return h.astype(f32), (gx * gx + gz * gz).astype(f32), inside, np.column_stack([gx, gz]).astype(f32)


def cos_sin_f32(x):
    """(cos x, sin x) in float32 as axial_cos_sin of glsl/axial.glsl computes them."""
    f32 = np.float32
    x = np.asarray(x, f32)
    q = np.floor(x * f32(0.6366197723675814) + f32(0.5))
    r = (x - q * f32(1.5707963705062866)) - q * f32(-4.371139000186243e-8)
    r2 = r * r
    s = r * (r2 * (r2 * (r2 * (r2 * f32(1.0 / 362880.0) - f32(1.0 / 5040.0)) + f32(1.0 / 120.0)) - f32(1.0 / 6.0)) + f32(1))
    c = r2 * (r2 * (r2 * (r2 * (r2 * f32(-1.0 / 3628800.0) + f32(1.0 / 40320.0)) - f32(1.0 / 720.0)) + f32(1.0 / 24.0))
              - f32(0.5)) + f32(1)
    m = q - f32(4) * np.floor(q * f32(0.25))
    odd = (m == 1) | (m == 3)
    cs, sn = np.where(odd, s, c), np.where(odd, c, s)
    return np.where((m == 1) | (m == 2), -cs, cs).astype(f32), np.where(m >= 1.5, -sn, sn).astype(f32)


def atan2_f32(y, x):
    """atan2 in float32 as axial_gen_atan2 of glsl/generate.glsl (Cephes' atanf)."""
    f32 = np.float32
    y, x = np.asarray(y, f32), np.asarray(x, f32)
    ax, ay = np.abs(x), np.abs(y)
    swap = ay > ax
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(swap, ax / ay, ay / ax).astype(f32)
    t = np.where((ax == 0) & (ay == 0), f32(0), t)
    big = t > f32(0.41421356237309503)
    base = np.where(big, f32(0.7853981633974483), f32(0))
    t = np.where(big, (t - f32(1)) / (t + f32(1)), t).astype(f32)
    z = t * t
    a = (((f32(8.05374449538e-2) * z - f32(1.38776856032e-1)) * z + f32(1.99777106478e-1)) * z
         - f32(3.33329491539e-1)) * z * t + t + base
    a = np.where(swap, f32(1.5707963267948966) - a, a)
    a = np.where(x < 0, f32(3.141592653589793) - a, a)
    a = np.where(y < 0, -a, a)
    return np.where((ax == 0) & (ay == 0), f32(0), a).astype(f32)


def lean_angles(rec: dict, ry, grad):
    """Euler angles ((n, 3) float32) and the anchor's height after the turn ((n,) float32) of instances that
    lean toward the ground's normal (axial_gen_lean of glsl/generate.glsl, operation for operation)."""
    f32 = np.float32
    gx, gz = grad[:, 0], grad[:, 1]
    inv = f32(1) / np.sqrt(gx * gx + f32(1) + gz * gz)
    nx, ny, nz = -gx * inv, inv, -gz * inv
    sn = np.sqrt(nx * nx + nz * nz)
    safe = np.where(sn > f32(1e-12), sn, f32(1))
    kx, kz = np.where(sn > f32(1e-12), nz / safe, f32(0)), np.where(sn > f32(1e-12), -nx / safe, f32(0))
    ca, sa = cos_sin_f32(atan2_f32(sn, ny) * f32(rec["align"]))
    cy_, sy_ = cos_sin_f32(ry)
    c1 = f32(1) - ca
    rt = np.empty((len(gx), 3, 3), f32)  # rows
    rt[:, 0] = np.column_stack([f32(1) - c1 * kz * kz, -sa * kz, c1 * kx * kz])
    rt[:, 1] = np.column_stack([sa * kz, f32(1) - c1 * (kx * kx + kz * kz), -sa * kx])
    rt[:, 2] = np.column_stack([c1 * kx * kz, sa * kx, f32(1) - c1 * kx * kx])
    ryM = np.zeros((len(gx), 3, 3), f32)
    ryM[:, 0, 0], ryM[:, 0, 2], ryM[:, 1, 1], ryM[:, 2, 0], ryM[:, 2, 2] = cy_, sy_, f32(1), -sy_, cy_
    m = np.einsum("nij,njk->nik", rt, ryM).astype(f32)  # R, rows
    cyy = np.sqrt(m[:, 0, 0] * m[:, 0, 0] + m[:, 1, 0] * m[:, 1, 0])
    locked = cyy < f32(1e-9)
    rx = np.where(locked, atan2_f32(-m[:, 1, 2], m[:, 1, 1]), atan2_f32(m[:, 2, 1], m[:, 2, 2]))
    ryy = atan2_f32(-m[:, 2, 0], cyy)
    rz = np.where(locked, f32(0), atan2_f32(m[:, 1, 0], m[:, 0, 0]))
    ax_, az_ = (f32(v) for v in rec["anchor_xz"])
    ay = m[:, 1, 0] * ax_ + m[:, 1, 1] * f32(rec["anchor_y"]) + m[:, 1, 2] * az_
    return np.column_stack([rx, ryy, rz]).astype(f32), ay.astype(f32)

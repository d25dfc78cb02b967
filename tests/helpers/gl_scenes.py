"""GL test helpers: a camera's matrices, one offscreen picture of a renderer, and base meshes whose
axis is x, y and z (and a third-party rock)."""

from __future__ import annotations

import numpy as np
import pyrr
import trimesh

import axialdeform as ad
from axialdeform.gl.context import Offscreen

from conftest import data_mesh

BACKGROUND = (0.93, 0.94, 0.96)


def look(eye, target, fovy=60.0, aspect=4 / 3, near=0.05, far=400.0):
    view = pyrr.matrix44.create_look_at(np.asarray(eye, float), np.asarray(target, float), (0, 1, 0), dtype=np.float32)
    return view, pyrr.matrix44.create_perspective_projection(fovy, aspect, near, far, dtype=np.float32)


def draw(ctx, renderer, view, proj, mode="solid", size=(160, 120)):
    with Offscreen(ctx, size, samples=4) as target:
        target.use(BACKGROUND)
        renderer.render(view, proj, mode)
        return target.read()


def z_axis_ply_off_origin(tmp_path, stone):
    """The stone turned so its long axis is z, moved off the origin, saved as PLY with normals."""
    perm = [1, 2, 0]  # x -> z
    tm = stone.to_trimesh(stone.positions[:, perm] * 3.0 + [5.0, -40.0, 12.5], stone.normals[:, perm])
    path = tmp_path / "stone_z.ply"
    path.write_bytes(trimesh.exchange.ply.export_ply(tm, vertex_normal=True))
    return path


def meshes_for_all_axes(tmp_path, stone, leaf):
    z = ad.load_mesh(z_axis_ply_off_origin(tmp_path, stone))
    assert z.normals_from_file and z.axis.name == "z"
    return {"x": stone, "y": leaf, "z": z, "rock": ad.load_mesh(data_mesh("base/rock_caustics.obj"))}

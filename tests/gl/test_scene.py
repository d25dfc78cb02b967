"""Scene pieces the examples use: per-instance tint, the ground plane, and
``assemble_text`` for the user's own shaders."""

from __future__ import annotations

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.camera import frame_instances


def _draw(ctx, renderer, mesh, params, ground=None, size=(96, 72)):
    cam = frame_instances(mesh, params, size[0] / size[1])
    with ad.Offscreen(ctx, size) as target:
        target.use()
        if ground is not None:
            ground.render(cam.view(), cam.projection(size[0] / size[1]))
        renderer.render(cam.view(), cam.projection(size[0] / size[1]), "solid")
        return target.read().astype(int)


def test_tint_colours_each_instance_in_one_draw(ctx, stone):
    params = ad.random_params(stone, 16, seed=1)
    with ad.AxialRenderer(ctx, stone, params) as r:
        plain = _draw(ctx, r, stone, params)
        r.set_tint(np.tile([[0.9, 0.05, 0.05]], (16, 1)))
        red = _draw(ctx, r, stone, params)
        assert (red[..., 0] - red[..., 2] > 60).sum() > 50
        assert np.abs(plain - red).sum() > 0
        r.set_tint(None)
        assert np.array_equal(_draw(ctx, r, stone, params), plain)
        r.set_tint(np.ones((15, 3)))
        with pytest.raises(ad.core.ParamError, match="15 colours for 16 instances"):
            _draw(ctx, r, stone, params)
        with pytest.raises(ad.core.ParamError):
            r.set_tint(np.ones((16, 4)))


def test_tint_keeps_the_capture_path(ctx, stone):
    params = ad.random_params(stone, 50, seed=1, variation=ad.Variation(bend=0.1))
    with ad.AxialRenderer(ctx, stone, params) as r:
        r.set_tint(np.full((50, 3), 0.5))
        gpu, _ = r.capture()
    cpu, _ = ad.deform(stone.axis, stone.positions, stone.normals, params)
    assert np.abs(gpu - cpu).max() / stone.axis.length <= 1e-5


def test_ground_plane_draws_under_instances(ctx, stone):
    params = ad.random_params(stone, 9, seed=1)
    with ad.AxialRenderer(ctx, stone, params) as r, ad.gl.GroundPlane(ctx, cell=1.0) as g:
        g.fit(stone, params)
        assert g.radius > 0 and g.center[1] < 0.2
        plain = _draw(ctx, r, stone, params)
        grounded = _draw(ctx, r, stone, params, ground=g)
    bg = np.array([0.93, 0.94, 0.96]) * 255
    assert (np.abs(grounded - bg).max(axis=2) > 14).mean() > (np.abs(plain - bg).max(axis=2) > 14).mean() + 0.1
    with pytest.raises(ad.AxialDeformError):
        ad.gl.GroundPlane(ctx, up="w")


def test_assemble_text_expands_include_and_keeps_lines(ctx):
    src = '#version 330 core\n#include "axial.glsl"\nin vec3 p;\nvoid main() { gl_Position = vec4(axial_rotation(p) * p, 1.0); }\n'
    out = ad.gl.assemble_text(src, "mine.vert")
    assert out.source.startswith("#version 330 core\n")
    assert "axial_world" in out.source and out.files == ["mine.vert", "axial.glsl"]
    ctx.program(vertex_shader=out.source).release()
    bad = '#include "axial.glsl"\nvoid main() { nope(); }\n'
    with pytest.raises(Exception) as info:
        ctx.program(vertex_shader=ad.gl.assemble_text(bad, "mine.vert").source)
    assert "0:2" in str(info.value) or "0(2)" in str(info.value)

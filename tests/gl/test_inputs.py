"""errors and inputs."""

from __future__ import annotations

import inspect
import re

import numpy as np
import pytest
import tomllib
import trimesh

import axialdeform as ad
from axialdeform.core.camera import Camera


def _is_ours(exc):
    return isinstance(exc, ad.AxialDeformError) and isinstance(exc, ValueError)


def test_argument_error_is_both():
    assert issubclass(ad.core.ArgumentError, ad.AxialDeformError) and issubclass(ad.core.ArgumentError, ValueError)


@pytest.mark.parametrize("call", [
    lambda m: ad.core.as_params(np.zeros((3, 15))),
    lambda m: ad.deform(m.axis, m.positions[:, :2], m.normals, np.zeros((3, 16))),
    lambda m: ad.deform(m.axis, m.positions, m.normals[:5], np.zeros((3, 16))),
    lambda m: ad.core.make_params(offsets=np.zeros((3, 4, 2))),
    lambda m: ad.core.make_params(offsets=np.zeros((3, 5, 2)), positions=np.zeros((2, 3))),
    lambda m: Camera([0, 0], [0, 0, 0]),
    lambda m: ad.frame_instances(m, np.zeros((2, 16)), -1.0),
    lambda m: ad.bake(m, np.zeros((1, 16)), "fast"),
    lambda m: ad.core.io.bake.write_mesh_folder("/tmp/never", m, (np.zeros((1, 58, 3)), np.zeros((1, 58, 3))), "fbx"),
    lambda m: ad.render_image(m, np.zeros((1, 16)), modes="shiny"),
    lambda m: ad.BaseMesh.from_arrays(np.zeros((4, 2)), [[0, 1, 2]]),
    lambda m: ad.BaseMesh.from_arrays(np.eye(3), [[0, 1, 7]]),
    lambda m: ad.load_mesh(5),
    lambda m: m.axis.parameter(np.zeros((3, 2))),
    lambda m: ad.render_image(m, np.zeros((1, 16)), (0, 10)),
])
def test_wrong_values_and_shapes_get_our_value_error(stone, call):
    with pytest.raises(ValueError) as info:
        call(stone)
    assert _is_ours(info.value), repr(info.value)
    assert "broadcast" not in str(info.value) and "reshape" not in str(info.value)


def test_a_3x3_view_matrix_is_refused_by_renderer_and_ground(ctx, stone):
    params = ad.random_params(stone, 3, seed=1)
    with ad.Offscreen(ctx, (32, 32)) as target, ad.AxialRenderer(ctx, stone, params) as r, \
            ad.gl.GroundPlane(ctx) as ground:
        target.use()
        with pytest.raises(ad.core.ArgumentError, match=r"view: expected an array of shape \(4, 4\), found \(3, 3\)"):
            r.render(np.eye(3), np.eye(4))
        with pytest.raises(ad.core.ArgumentError, match="projection"):
            ground.render(np.eye(4), np.eye(4)[:3])
        with pytest.raises(ad.core.ArgumentError, match="light_dir"):
            r.render(np.eye(4), np.eye(4), look=ad.Look(light_dir=(1, 2)))
        with pytest.raises(ad.core.ArgumentError, match="ground color"):
            ad.gl.GroundPlane(ctx, color=(1, 2))


def test_drawing_without_a_framebuffer_raises(ctx, stone):
    params = ad.random_params(stone, 3, seed=1)
    with ad.AxialRenderer(ctx, stone, params) as r, ad.gl.GroundPlane(ctx) as ground:
        ctx.detect_framebuffer(0).use()  # a windowless context: no default framebuffer
        with pytest.raises(ad.core.ContextError, match="no usable framebuffer"):
            r.render(np.eye(4), np.eye(4))
        with pytest.raises(ad.core.ContextError, match="no usable framebuffer"):
            ground.render(np.eye(4), np.eye(4))
    assert ctx.error == "GL_NO_ERROR"


def test_load_mesh_takes_a_trimesh_and_arrays(stone):
    tm = stone.to_trimesh()
    a = ad.load_mesh(tm)
    assert np.array_equal(a.positions, stone.positions) and np.array_equal(a.faces, stone.faces)
    b = ad.BaseMesh.from_arrays(stone.positions, stone.faces)
    assert b.vertex_count == stone.vertex_count and np.allclose(np.linalg.norm(b.normals, axis=1), 1, atol=1e-5)
    c = ad.BaseMesh.from_arrays(stone.positions, stone.faces, stone.normals)
    assert np.array_equal(c.normals, stone.normals)
    scene = trimesh.Scene(tm)
    assert ad.load_mesh(scene).vertex_count == stone.vertex_count


def test_mesh_repr_is_one_line(stone):
    text = repr(stone)
    assert "\n" not in text and "58 vertices" in text and "112 triangles" in text and len(text) < 200


def test_moderngl_window_version_message_agrees_with_pyproject():
    from pathlib import Path

    from axialdeform import viewer

    project = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text())
    wanted = [d for d in project["project"]["dependencies"] if d.startswith("moderngl-window")][0]
    asks = set(re.findall(r"moderngl-window>=[0-9.]+", inspect.getsource(viewer)))
    assert asks == {wanted.replace(" ", "")}


def test_update_params_error_names_set_params(ctx, stone):
    params = ad.random_params(stone, 4, seed=1)
    with ad.AxialRenderer(ctx, stone, params) as r:
        with pytest.raises(ad.core.ParamError, match=r"^update_params: .*set_params\(\)"):
            r.update_params(params, start=2)
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(quantized=True)) as r:
        big = params[:1].copy()
        big[0, 10] += 1000.0
        with pytest.raises(ad.core.ParamError, match=r"set_params\(\)"):
            r.update_params(big)

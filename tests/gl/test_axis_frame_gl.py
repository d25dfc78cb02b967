"""A chosen axis frame on the GPU (AXIAL_FRAME: u_frame in glsl/scene.vert):
the capture equals the CPU reference, with 16 and 19 numbers, quantized,
with wind and with a normal-mapped material; auto pictures are unchanged."""

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.deform import deform_tangents
from axialdeform.gl.renderer import AxialRenderer

from conftest import data_mesh


def rotation(a=0.6, b=0.5, c=0.3) -> np.ndarray:
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    return (np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]]) @ np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
            @ np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]]))


@pytest.fixture(scope="module")
def diag():
    stone = ad.load_mesh("stone")
    q = rotation()
    turned = ad.BaseMesh(stone.positions.astype(np.float64) @ q.T, stone.normals.astype(np.float64) @ q.T,
                         stone.faces, name="stone turned")
    return ad.load_mesh(turned, axis="oriented")


def _params(mesh, extended):
    p = ad.random_params(mesh, 60, seed=5, variation=ad.Variation(bend=0.2), spacing=2.0)
    if extended:
        rng = np.random.default_rng(1)
        extra = np.stack([rng.uniform(0.5, 1.5, 60), rng.uniform(-1, 1, 60), rng.uniform(-0.5, 0.6, 60)], axis=1)
        p = np.hstack([p, extra]).astype(np.float32)
    return p


@pytest.mark.parametrize("extended", [False, True])
@pytest.mark.parametrize("quantized", [False, True])
def test_gpu_equals_cpu_on_a_framed_axis(ctx, diag, extended, quantized):
    assert diag.axis.framed
    p = _params(diag, extended)
    with AxialRenderer(ctx, diag, p, options=ad.RenderOptions(quantized=quantized)) as r:
        assert "u_frame" in r.program and "u_axis" not in r.program
        gpu_pos, gpu_nrm = r.capture()
        used = r.instances.read()  # the numbers on the GPU (quantized: decoded)
    cpu_pos, cpu_nrm = ad.deform(diag, used)
    L = diag.axis.length
    reach = max(1.0, float(np.abs(p[:, 10:13]).max()) / L)
    assert np.abs(gpu_pos - cpu_pos).max() <= 1e-5 * L * reach
    assert np.abs(gpu_nrm - cpu_nrm).max() <= 1e-5


def test_gpu_wind_equals_cpu_on_a_framed_axis(ctx, diag):
    wind = ad.Wind(direction=(1.0, 0.0, 0.4), strength=0.3, gustiness=0.6, frequency=0.5)
    p = _params(diag, False)
    with AxialRenderer(ctx, diag, p, options=ad.RenderOptions(wind=wind)) as r:
        gpu = r.capture(time=3.5)
        still = r.capture(wind=None)
    cpu = ad.bake(diag, p, "cpu", options=ad.RenderOptions(wind=wind, time=3.5))
    L = diag.axis.length
    reach = max(1.0, float(np.abs(p[:, 10:13]).max()) / L)
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * L * reach
    assert np.abs(gpu[0] - still[0]).max() > 0.05 * L  # the wind moved them


def test_framed_tangents_on_the_gpu_equal_the_cpu(ctx):
    """A normal-mapped asset (the Khronos alpha test: tangents) with a chosen
    frame: the framed tangent program builds and captures the CPU shape, and
    deform_tangents stays unit and in the bent surface (⟂ to n)."""
    mesh = ad.load_mesh(data_mesh("assets/AlphaBlendModeTest.glb"), axis=rotation(0.2, 0.1, 0.05))
    assert mesh.axis.framed and mesh.tangents is not None
    p = ad.random_params(mesh, 8, seed=2, variation=ad.Variation(bend=0.2))
    tan = deform_tangents(mesh.axis, mesh.positions, mesh.tangents, p)
    _, nrm = ad.deform(mesh, p)
    assert np.abs(np.linalg.norm(tan, axis=-1) - 1).max() < 1e-5
    assert np.abs(np.einsum("nvk,nvk->nv", tan, nrm)).max() < 1e-4  # the bent tangent stays in the bent surface
    with AxialRenderer(ctx, mesh, p) as r:
        assert "u_frame" in r.program
        gpu_pos, _ = r.capture()
    assert np.abs(gpu_pos - ad.deform(mesh, p)[0]).max() <= 1e-5 * mesh.axis.length * 10


def test_a_framed_picture_is_the_cpu_shape(ctx, diag):
    """render of a framed mesh == render of its CPU-baked shape drawn without a bend."""
    p = _params(diag, True)
    look = ad.Look(ground=False, shadow=False)
    bent = ad.render_image(diag, p, (200, 150), look=look)
    straight = ad.render_image(diag, np.hstack([p[:, :16] * np.r_[np.zeros(10), np.ones(6)], p[:, 16:]]).astype(np.float32),
                               (200, 150), look=look)
    assert np.abs(bent.astype(int) - straight).max() > 50  # the bend shows
    assert ctx.error == "GL_NO_ERROR"

"""each piece of shared logic has one home that the others call."""

from __future__ import annotations

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core import bake as bake_mod
from axialdeform.core import fit
from axialdeform.core.io import bake as bake_io
from axialdeform.core.io import mesh as mesh_io


def test_instance_names_come_from_one_function(tmp_path, stone):
    from axialdeform.bench import child

    assert bake_mod.instance_name(12) == "instance_000012"
    assert bake_mod.instance_name(3, 2_000_000, ".ply") == "instance_0000003.ply"
    assert child.obj_name(7) == bake_mod.instance_name(7, 0, ".obj")
    params = ad.random_params(stone, 3, seed=1)
    pos, nrm = ad.bake(stone, params)
    files = bake_io.write_mesh_folder(tmp_path / "f", stone, (pos, nrm), "obj")
    assert [f.name for f in files] == [bake_mod.instance_name(i, 3, ".obj") for i in range(3)]


def test_mesh_suffixes_are_one_constant(tmp_path):
    """fit's folder of variants takes exactly the files load_mesh reads."""
    assert fit.MESH_SUFFIXES is mesh_io.MESH_SUFFIXES
    assert ".obj" in mesh_io.MESH_SUFFIXES and ".glb" in mesh_io.MESH_SUFFIXES
    for suffix in (*mesh_io.MESH_SUFFIXES, ".txt", ".png", ".mtl"):
        (tmp_path / f"v{suffix}").write_bytes(b"")
    picked = {p.suffix for p in fit.variant_paths([tmp_path])}
    assert picked == set(mesh_io.MESH_SUFFIXES)


def test_core_bake_needs_no_gl_and_the_gpu_engine_lives_in_gl(stone, ctx):
    from axialdeform.gl import bake as gl_bake

    assert ad.bake is gl_bake.bake  # (that core imports no GL: tests/app/test_layers.py)
    params = ad.random_params(stone, 4, seed=2, variation=ad.Variation(bend=0.2))
    cpu, _ = bake_mod.bake_cpu(stone, params)
    gpu, _ = ad.bake(stone, params, "gpu", ctx=ctx)
    assert np.abs(gpu - cpu).max() < 1e-5 * stone.axis.length
    assert np.array_equal(ad.bake(stone, params)[0], cpu)
    with pytest.raises(ValueError, match="engine"):
        ad.bake(stone, params, "fast")


def test_quantization_has_one_home(stone, tmp_path):
    """core.quantize makes the levels the GPU buffer and the binary file both store: a quantized
    file decodes to dequantize_params(quantize_params(values))."""
    from axialdeform.core import quantize

    values = ad.random_params(stone, 50, seed=3, variation=ad.Variation(bend=0.2))
    lo, step, q = quantize.quantize_params(values)
    assert np.array_equal(quantize.quantize_with_table(values, lo, step), q)
    outside = values[:2].copy()
    outside[1, 10] = values[:, 10].max() + 1.0
    with pytest.raises(ad.core.ParamError, match="instance 1, field 10"):
        quantize.quantize_with_table(outside, lo, step)
    ad.write_params(tmp_path / "q.adp", values, stone, quantize=True)
    assert np.array_equal(ad.read_params(tmp_path / "q.adp", stone), quantize.dequantize_params(lo, step, q))


def test_conventions_are_cited_from_docs_method():
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    method = (root / "docs" / "method.md").read_text(encoding="utf-8")
    for term in ("Rz(rz) · Ry(ry) · Rx(rx)", "V'   = V + E(D(t))", "n' = normalize", "d1u d1v", "s tw tp",
                 "(x, z)", "t = (V[a] − lo) / L"):
        assert term in method, term
    files = [*root.glob("axialdeform/**/*.py"), *root.glob("glsl/*"), *root.glob("docs/*.md")]
    cited = [f for f in files if "axial-deformation.md" in f.read_text(encoding="utf-8", errors="replace")]
    assert not cited, cited
    assert "docs/method.md" in (root / "glsl" / "axial.glsl").read_text()


def test_camera_uniforms_have_one_home(stone, ctx, monkeypatch):
    """The instances, their shadow pass and the ground plane all set their camera through
    gl.uniforms.set_camera_uniforms: a picture with a ground and a shadow calls it for each."""
    from axialdeform.gl import ground, renderer, uniforms

    calls = []

    def spy(prog, view, projection):
        calls.append(prog)
        return uniforms.set_camera_uniforms(prog, view, projection)

    monkeypatch.setattr(renderer, "set_camera_uniforms", spy)
    monkeypatch.setattr(ground, "set_camera_uniforms", spy)
    params = ad.random_params(stone, 20, seed=1)
    image = ad.render_image(stone, params, (64, 48), ctx=ctx, look=ad.Look(samples=0))
    assert image.std() > 0
    programs = {id(p) for p in calls}
    assert len(calls) >= 3 and len(programs) >= 2  # the instances (drawn and shadowed) and the ground


def test_read_pixels_puts_the_top_row_first(ctx):
    from axialdeform.gl.context import release_framebuffer

    fbo = ctx.simple_framebuffer((4, 2))
    try:
        fbo.use()
        ctx.viewport = (0, 0, 4, 2)
        fbo.clear(0.0, 0.0, 0.0, 1.0)
        ctx.scissor = (0, 1, 4, 1)  # GL row 1 = the top row of the picture
        fbo.clear(1.0, 1.0, 1.0, 1.0)
        ctx.scissor = None
        image = ad.gl.read_pixels(ctx, fbo)
        assert image.shape == (2, 4, 3)
        assert (image[0] == 255).all() and (image[1] == 0).all()
        assert np.array_equal(ad.gl.read_pixels(ctx, fbo, resolve=True), image)
    finally:
        release_framebuffer(ctx, fbo)

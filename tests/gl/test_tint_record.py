"""Tinted instances on the GPU: the record's ``tr tg tb`` reach the shader
input the table names (``i_tint``, a float32 buffer of its own), so a
tinted parameter array colours its instances with no other call."""

from __future__ import annotations

import moderngl
import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core import record as R
from axialdeform.core.camera import frame_instances
from axialdeform.core.params import tint_params
from axialdeform.gl.shaders import build_program


def _draw(ctx, renderer, mesh, params, size=(96, 72)):
    cam = frame_instances(mesh, params, size[0] / size[1])
    with ad.Offscreen(ctx, size) as target:
        target.use()
        renderer.render(cam.view(), cam.projection(size[0] / size[1]), "solid")
        return target.read().astype(int)


def test_the_tint_program_declares_the_tables_input(ctx):
    tint = next(a for a in R.SHADER_INPUTS if a.buffer == "tint")
    prog = build_program(ctx, "scene.vert", "scene.frag", defines={"AXIAL_EXTENDED": 1, "AXIAL_TINT": 1})
    try:
        member = prog[tint.name]
        assert isinstance(member, moderngl.Attribute) and member.dimension == tint.size
    finally:
        prog.release()


@pytest.mark.parametrize("quantized", [False, True])
def test_a_tinted_record_draws_as_set_tint_does(ctx, stone, quantized):
    params = ad.random_params(stone, 30, seed=2, variation=ad.Variation(scale=(0.8, 1.2), tint=0.9, tint_color=(1.0, 0.3, 0.1)))
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(quantized=quantized)) as from_record, \
            ad.AxialRenderer(ctx, stone, params[:, :19], options=ad.RenderOptions(quantized=quantized)) as by_hand:
        by_hand.set_tint(params.tint)
        a, b = _draw(ctx, from_record, stone, params), _draw(ctx, by_hand, stone, params)
        assert np.array_equal(a, b)
        assert (a[..., 0] - a[..., 2] > 40).sum() > 100  # reddish: the tint shows
        # the record's tint goes with a record that has none; one set by hand stays
        from_record.set_params(params[:, :19])
        plain = _draw(ctx, from_record, stone, params)
        assert not (plain[..., 0] - plain[..., 2] > 40).any()
        by_hand.set_params(params[:, :19])
        assert np.array_equal(_draw(ctx, by_hand, stone, params), a)


def test_update_params_updates_the_tint_in_place(ctx, stone):
    params = tint_params(ad.random_params(stone, 12, seed=4), (1.0, 1.0, 1.0))
    with ad.AxialRenderer(ctx, stone, params) as r:
        white = _draw(ctx, r, stone, params)
        blue = np.array(params[3:12])
        blue[:, 19:22] = (0.05, 0.1, 1.0)
        r.update_params(blue, start=3)
        after = _draw(ctx, r, stone, params)
        assert (after[..., 2] - after[..., 0] > 40).sum() > 50 and not (white[..., 2] - white[..., 0] > 40).any()
        full = np.array(params)
        full[3:12] = blue
        with ad.AxialRenderer(ctx, stone, full) as whole:
            assert np.array_equal(_draw(ctx, whole, stone, params), after)


def test_render_image_of_a_tinted_file(ctx, tmp_path, stone):
    params = ad.random_params(stone, 20, seed=5, variation=ad.Variation(tint=0.8, tint_color=(0.2, 0.9, 0.2)))
    path = tmp_path / "green.adp"
    ad.write_params(path, params, stone)
    look = ad.Look(ground=False, shadow=False)
    img = ad.render_image(ad.Scene.single(stone, ad.read_params(path, stone)), size=(120, 90), look=look, ctx=ctx)
    plain = ad.render_image(ad.Scene.single(stone, params[:, :19]), size=(120, 90), look=look, ctx=ctx)
    covered = np.abs(plain.astype(int) - img.astype(int)).max(axis=2) > 0
    assert covered.sum() > 500
    g = img.astype(int)
    assert (g[..., 1] - g[..., 0] > 30).sum() > 300

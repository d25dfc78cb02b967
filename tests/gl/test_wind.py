"""Wind on the GPU: control points move from uniforms alone;
the CPU reference (core/wind.py) is the same function of time."""

from __future__ import annotations

import moderngl
import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.deform import deform
from axialdeform.core.params import extend_params
from axialdeform.core.wind import Wind, apply_wind, wind_hash, wind_offsets, wind_phase
from axialdeform.gl import capture as capture_module
from axialdeform.gl.renderer import AxialRenderer

WIND = Wind(direction=(1.0, 0.0, 0.4), strength=0.3, gustiness=0.7, frequency=0.8, wavelength=4.0)


def blades(leaf, n=60, seed=3):
    p = extend_params(ad.random_params(leaf, n, seed=seed, placement="disc"))
    rng = np.random.default_rng(seed)
    p[:, 16] = rng.uniform(0.6, 1.6, n)
    p[:, 17] = rng.uniform(-1, 1, n)
    p[:, 18] = rng.uniform(0, 0.6, n)
    return p


def test_hash_is_bit_exact_on_the_gpu(ctx):
    from axialdeform.gl.shaders import shader_source

    prog = ctx.program(vertex_shader="#version 330 core\n" + shader_source("axial.glsl") + shader_source("wind.glsl") + """
out uint h;
out float ph;
void main() { h = axial_wind_hash(uint(gl_VertexID) * 977u); ph = axial_wind_phase(uint(gl_VertexID) * 977u); }
""", varyings=["h", "ph"])
    n = 4096
    out = ctx.buffer(reserve=n * 8)
    vao = ctx.vertex_array(prog, [])
    from axialdeform.gl.context import bind_framebuffer

    color = ctx.renderbuffer((1, 1))
    fbo = ctx.framebuffer(color)
    previous = ctx.fbo
    fbo.use()
    vao.transform(out, mode=moderngl.POINTS, vertices=n)
    bind_framebuffer(ctx, previous)
    raw = np.frombuffer(out.read(), dtype=np.uint32).reshape(n, 2)
    ids = np.arange(n, dtype=np.uint64) * 977
    np.testing.assert_array_equal(raw[:, 0], wind_hash(ids))
    np.testing.assert_array_equal(raw[:, 1].view(np.float32), wind_phase(ids))
    assert len(np.unique(raw[:, 0])) > n * 0.99
    for obj in (vao, out, prog, fbo, color):
        obj.release()


def test_wind_moves_tips_never_bases(leaf):
    p = blades(leaf)
    off = wind_offsets(WIND, leaf.axis, p, 1.3)
    assert off.shape == (len(p), 5, 2)
    assert not off[:, :2].any()  # P1 and P2 (the base point and tangent) never move
    assert np.abs(off[:, 4]).max() > 0.1 * leaf.axis.length
    still = deform(leaf.axis, leaf.positions, leaf.normals, p)
    windy = deform(leaf.axis, leaf.positions, leaf.normals, apply_wind(WIND, leaf.axis, p, 1.3))
    t = leaf.axis.parameter(leaf.positions)
    assert (t == 0).any() and (t == 1).any()
    np.testing.assert_array_equal(windy[0][:, t == 0], still[0][:, t == 0])
    np.testing.assert_array_equal(windy[1][:, t == 0], still[1][:, t == 0])
    tip = np.linalg.norm(windy[0][:, t == 1] - still[0][:, t == 1], axis=-1)
    assert tip.min() > 0 and tip.max() > 0.1 * leaf.axis.length
    # it changes with time, and goes back to the same shape after a whole number of periods of both sines
    later = wind_offsets(WIND, leaf.axis, p, 1.3 + 0.37)
    assert np.abs(later - off).max() > 1e-3 * leaf.axis.length
    period = 100.0 / WIND.frequency  # 2.31 * 100 = 231 whole cycles too
    np.testing.assert_allclose(wind_offsets(WIND, leaf.axis, p, 1.3 + period), off, atol=1e-9)


def test_wind_follows_direction_in_each_instance_frame(leaf):
    p = ad.random_params(leaf, 20, seed=1, variation=ad.Variation(bend=0.0, tilt=(0, 0), yaw=(0, 0)))  # upright blades, no turn
    steady = Wind(direction=(0.0, 0.0, 2.0), strength=0.2, gustiness=0.0)
    off = wind_offsets(steady, leaf.axis, p, 5.0)
    # axis y: offsets are (x, z); a wind along +z pushes every tip by 0.2 L along z
    np.testing.assert_allclose(off[:, 4], [[0.0, 0.2 * leaf.axis.length]] * 20, atol=1e-12)


@pytest.mark.parametrize("quantized", [False, True])
def test_gpu_wind_equals_cpu(ctx, leaf, monkeypatch, quantized):
    p = blades(leaf, n=200)
    # small capture chunks: the per-instance phase must follow the instance's index across chunks
    monkeypatch.setattr(capture_module, "_CAPTURE_BYTES", leaf.vertex_count * 24 * 37)
    with AxialRenderer(ctx, leaf, p, options=ad.RenderOptions(quantized=quantized, wind=WIND)) as r:
        gpu = r.capture(time=7.25)
        still = r.capture(wind=None)
        on_gpu = r.instances.read()
    cpu = ad.bake(leaf, on_gpu, "cpu", options=ad.RenderOptions(wind=WIND, time=7.25))
    L = leaf.axis.length
    reach = max(1.0, float(np.abs(p[:, 10:13]).max()) / L)
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * L * reach
    assert np.abs(gpu[1] - cpu[1]).max() <= 1e-5
    t = leaf.axis.parameter(leaf.positions)
    np.testing.assert_array_equal(gpu[0][:, t == 0], still[0][:, t == 0])
    assert np.abs(gpu[0][:, t == 1] - still[0][:, t == 1]).max() > 0.05 * L


def test_animating_the_wind_writes_no_buffer(ctx, leaf, monkeypatch):
    p = blades(leaf, n=500)
    writes = []
    original = moderngl.Buffer.write

    def counting(self, data, *args, **kwargs):
        writes.append(len(memoryview(data).cast("B")) if not isinstance(data, (bytes, bytearray)) else len(data))
        return original(self, data, *args, **kwargs)

    import pyrr

    view = pyrr.matrix44.create_look_at((6.0, 4.0, 6.0), (0.0, 0.5, 0.0), (0.0, 1.0, 0.0), dtype=np.float32)
    proj = pyrr.matrix44.create_perspective_projection(40.0, 1.0, 0.1, 100.0, dtype=np.float32)
    with ad.Offscreen(ctx, (64, 64), samples=0) as target, AxialRenderer(ctx, leaf, p) as r:
        target.use()
        r.wind = WIND
        r.render(view, proj, time=0.0)  # first frame: whatever setup it needs
        first = target.read().copy()
        monkeypatch.setattr(moderngl.Buffer, "write", counting)
        frames = []
        for k in range(1, 6):
            target.use()
            r.render(view, proj, time=0.4 * k)
            frames.append(target.read().copy())
        monkeypatch.setattr(moderngl.Buffer, "write", original)
    assert writes == [], f"{len(writes)} buffer writes ({sum(writes)} bytes) while animating the wind"
    assert any(np.abs(f.astype(int) - first).max() > 0 for f in frames)  # the picture does move


def test_wind_parse_and_bad_values():
    w = Wind.parse("0.2,0.5,1.5,8", direction=(0, 0, 1))
    assert (w.strength, w.gustiness, w.frequency, w.wavelength) == (0.2, 0.5, 1.5, 8.0)
    np.testing.assert_array_equal(w.unit_direction, [0, 0, 1])
    with pytest.raises(ad.core.ParamError, match="--wind: gustiness: expected a finite number >= 0"):
        Wind.parse("0.2,-1")
    for bad in ((0, 0, 0), (1, 2), "abc", (1, float("nan"), 0)):
        with pytest.raises(ad.core.ParamError, match="wind direction"):
            Wind(direction=bad)
    with pytest.raises(ad.core.ParamError, match="wind strength"):
        Wind(strength=float("inf"))
    with pytest.raises(ad.core.ParamError, match="time"):
        w.cycles(float("nan"))


def test_viewer_animates_the_wind_and_v_toggles_it(leaf):
    from axialdeform.viewer import Viewer

    p = blades(leaf, n=150)
    v = Viewer.create(leaf, p, headless=True, size=(160, 120), options=ad.RenderOptions(wind=WIND))
    try:
        assert v.renderer.extended and v.renderer.wind is WIND
        v.step(2)
        a = v.screenshot()
        v.step(5, dt=0.2)
        b = v.screenshot()
        assert np.abs(a.astype(int) - b).max() > 0  # the blades moved
        assert "wind 0.3" in v.status()
        v.on_key_event("v", v.wnd.keys.ACTION_PRESS, None)
        assert v.renderer.wind is None
        v.step()
        c = v.screenshot()
        v.step(3, dt=0.2)
        assert np.array_equal(c, v.screenshot())  # still
    finally:
        v.release()
        v.wnd.destroy()


def test_instance_bounds_hold_the_windy_instances(leaf):
    from axialdeform.core.bounds import instance_bounds

    p = blades(leaf, n=80)
    centers, radii = instance_bounds(leaf, p, wind=WIND)
    for time in (0.0, 0.9, 2.7, 13.1):
        pos = ad.bake(leaf, p, "cpu", options=ad.RenderOptions(wind=WIND, time=time))[0]
        dist = np.linalg.norm(pos - centers[:, None], axis=-1).max(axis=1)
        assert (dist <= radii * (1 + 1e-6)).all()
    still_centers, still_radii = instance_bounds(leaf, p)
    assert (radii > still_radii).all()


def test_renderer_refuses_a_wind_that_is_not_a_wind(ctx, leaf):
    with AxialRenderer(ctx, leaf, blades(leaf, n=3)) as r:
        with pytest.raises(ad.core.ParamError, match="wind: expected an axialdeform.Wind"):
            r.capture(wind=0.3)


@pytest.mark.parametrize("culling", [True, False])
def test_a_still_draw_builds_the_wind_out(ctx, leaf, culling):
    """The still build of scene.vert has no wind in it (AXIAL_WIND undefined: the linker drops its uniforms); a wind
    that blows draws with the windy build, and the still picture comes back exactly when it stops (None, or a
    strength of 0)."""
    import pyrr

    view = pyrr.matrix44.create_look_at((6.0, 4.0, 6.0), (0.0, 0.5, 0.0), (0.0, 1.0, 0.0), dtype=np.float32)
    proj = pyrr.matrix44.create_perspective_projection(40.0, 1.0, 0.1, 100.0, dtype=np.float32)
    with ad.Offscreen(ctx, (96, 96), samples=0) as target, AxialRenderer(ctx, leaf, blades(leaf, n=80),
                                                                          options=ad.RenderOptions(culling=culling)) as r:
        def frame(wind):
            r.wind = wind
            target.use()
            r.render(view, proj, time=1.3)
            return target.read().copy()

        still = frame(None)
        assert "u_wind_strength" not in r.program and "u_wind_dir" not in r.program
        windy = frame(WIND)
        assert np.abs(windy.astype(int) - still).max() > 0
        builds = [o for o in r._objects if isinstance(o, moderngl.Program) and "u_wind_strength" in o]
        assert builds, "no windy build was made for the wind"
        np.testing.assert_array_equal(frame(None), still)
        np.testing.assert_array_equal(frame(Wind(strength=0.0)), still)
        np.testing.assert_array_equal(r.capture(wind=None)[0], r.capture(wind=Wind(strength=0.0))[0])

"""bend-aware bounds, GPU per-instance culling, LOD, stats."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import axialdeform as ad
from axialdeform.core.bounds import base_radius, frustum_planes, instance_bounds, instance_boxes, lod_choice, spheres_visible
from axialdeform.core.lod import build_lod_levels
from axialdeform.gl.context import Offscreen

from conftest import make_mesh
from helpers.gl_scenes import BACKGROUND, draw, look, meshes_for_all_axes


def field(mesh, n=3000, seed=4):
    """Stones scattered on a disc (y up), radius about 30 L."""
    return ad.random_params(mesh, n, seed=seed, variation=ad.Variation(bend=0.15), placement="disc", spacing=1.0 * mesh.axis.length)


# ------------------------------------------------------------------ bounds
@pytest.mark.slow
def test_bounds_hold_every_gpu_vertex_and_are_tight(ctx, tmp_path, stone, leaf):
    """Random parameters on meshes whose axis is x, y and z: every vertex the
    GPU computes lies in its instance's sphere and box; on average the sphere
    is at most 1.5x the tight one (the smallest sphere about the same centre
    holding the captured vertices).  The world box (a box around the rotated
    bent model box) may be up to sqrt(3) wider than the vertices' own box
    per axis; on average it is less than 2x."""
    rng = np.random.default_rng(14)
    for name, mesh in meshes_for_all_axes(tmp_path, stone, leaf).items():
        for _ in range(3):
            seed = int(rng.integers(1 << 30))  # drawn before the bend, as always
            variation = ad.Variation(bend=float(rng.uniform(0.02, 0.4)), tilt=(-3, 3))
            params = ad.random_params(mesh, 400, seed=seed, variation=variation, placement="disc")
            with ad.AxialRenderer(ctx, mesh, params) as r:
                world, _ = r.capture()
            centers, radii = instance_bounds(mesh, params)
            dist = np.linalg.norm(world.astype(np.float64) - centers[:, None, :], axis=2)
            tight = dist.max(axis=1)
            L = mesh.axis.length
            assert (tight <= radii * (1 + 1e-6) + 1e-6 * L).all(), name
            assert (radii / tight).mean() <= 1.5, (name, (radii / tight).mean())
            lo, hi = instance_boxes(mesh, params)
            eps = 1e-5 * (L + np.abs(params[:, 10:13]).max())
            assert (world >= lo[:, None, :] - eps).all() and (world <= hi[:, None, :] + eps).all(), name
            tight_extent = world.max(axis=1) - world.min(axis=1)
            assert ((hi - lo) / np.maximum(tight_extent, 1e-3 * L)).mean() <= 2.0, name


@pytest.mark.parametrize("indirect", [True, False], ids=["indirect", "query"])
@pytest.mark.parametrize("kind", ["plain", "extended", "extended+wind", "quantized"])
def test_gpu_culling_agrees_with_the_numpy_spheres(ctx, stone, kind, indirect):
    """The GLSL bound (glsl/bounds.glsl) keeps every instance the numpy
    sphere test keeps, and the few extra ones are within its float margin;
    the compacted records are the originals byte for byte, in order (both
    paths: compute + indirect draws, transform feedback + query)."""
    from axialdeform.core.wind import Wind

    params = extended_field(stone, 3000) if kind.startswith("extended") else field(stone)
    wind = Wind(direction=(1.0, 0.0, 0.2), strength=0.5, gustiness=0.9) if kind.endswith("wind") else None
    view, proj = look((2.0, 1.7, -3.0), (30.0, 0.0, 20.0))
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(wind=wind, quantized=kind == "quantized", indirect=indirect)) as r:
        draw(ctx, r, view, proj)
        cull = r._cull_passes[False]
        assert cull.indirect == indirect and r.stats["indirect"] == indirect
        kept, rec_bytes = r.stats["visible"], r.instances.record_bytes
        rec = np.frombuffer(cull.buffer.read(size=kept * cull.out_bytes), np.uint8).reshape(kept, cull.out_bytes)
        index = rec[:, rec_bytes:rec_bytes + 4].copy().view(np.int32).ravel()
        originals = np.frombuffer(r.instances.buffer.read(size=r.count * rec_bytes), np.uint8).reshape(r.count, -1)
        assert np.array_equal(rec[:, :rec_bytes], originals[index])
        drawn = r.instances.read()
    assert (np.diff(index) > 0).all(), "the compacted records keep their order"
    centers, radii = instance_bounds(stone, drawn, wind=wind)
    planes = frustum_planes(view, proj)
    visible = spheres_visible(centers, radii, planes)
    assert 0 < visible.sum() < len(params) / 2
    assert set(np.flatnonzero(visible)) <= set(index)
    assert spheres_visible(centers[index], radii[index] * 1.001, planes).all()


def test_frustum_planes_contain_what_the_camera_sees():
    view, proj = look((0, 1, 0), (0, 1, -10), fovy=90, aspect=1, near=0.5, far=50)
    planes = frustum_planes(view, proj)
    inside = np.array([[0, 1, -5], [4.9, 1, -5], [0, 1, -49]])
    outside = np.array([[0, 1, 5], [5.2, 1, -5], [0, 1, -51], [0, 1, -0.4]])
    assert spheres_visible(inside, np.zeros(3), planes).all()
    assert not spheres_visible(outside, np.zeros(4), planes).any()
    assert spheres_visible(outside[:1], [5.6], planes).all()  # 5.5 behind the near plane
    assert not spheres_visible(outside[:1], [5.4], planes).any()


# ------------------------------------------------------------------ culling keeps the picture
EDGE = 2.03 * np.sqrt(3000 / np.pi) + 1.5  # the disc of field(stone): spacing * sqrt(n / pi), plus a stone
CAMERAS = {
    "inside the field": ((1.0, 1.7, 0.5), (25.0, 0.2, 12.0)),
    "at its edge, looking in": ((0.0, 2.0, EDGE), (0.0, 0.0, 0.0)),
    "at its edge, looking away": ((0.0, 1.7, EDGE), (0.0, 1.7, EDGE + 50)),
    "above, everything in view": ((0.0, 2.6 * EDGE, 1.7 * EDGE), (0.0, 0.0, 0.0)),
}


@pytest.mark.slow
@pytest.mark.parametrize("indirect", [True, False], ids=["indirect", "query"])
@pytest.mark.parametrize("variant", ["plain", "quantized", "tinted"])
def test_culled_picture_equals_unculled_pixel_for_pixel(ctx, stone, variant, indirect):
    params = field(stone)
    quantized = variant == "quantized"
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(quantized=quantized, indirect=indirect)) as culled, \
            ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(quantized=quantized, culling=False)) as full:
        if variant == "tinted":
            tint = np.random.default_rng(1).uniform(0, 1, (len(params), 3))
            culled.set_tint(tint)
            full.set_tint(tint)
        for name, (eye, target) in CAMERAS.items():
            view, proj = look(eye, target)
            for mode in ("solid", "wireframe") if variant == "plain" else ("solid",):
                a = draw(ctx, full, view, proj, mode)
                b = draw(ctx, culled, view, proj, mode)
                assert full.stats["visible"] == len(params) and not full.stats["culling"]
                assert np.array_equal(a, b), (name, mode, int((a != b).any(axis=2).sum()))
                seen = culled.stats["visible"]
                if name == "at its edge, looking away":
                    assert seen == 0 and (a == np.round(np.array(BACKGROUND) * 255)).all()
                elif name == "above, everything in view":
                    assert seen == len(params)
                else:
                    assert 0 < seen < len(params) * (0.9 if "edge" in name else 0.5), (name, seen)
                    assert (a != np.round(np.array(BACKGROUND) * 255)).any()


def test_capture_is_of_every_instance_with_culling_on(ctx, stone):
    params = field(stone, 50)
    view, proj = look((0.0, 1.7, EDGE), (0.0, 1.7, EDGE + 50))
    with ad.AxialRenderer(ctx, stone, params) as r:
        draw(ctx, r, view, proj)
        assert r.stats["visible"] == 0
        pos, _ = r.capture()
    cpu, _ = ad.deform(stone.axis, stone.positions, stone.normals, params)
    assert pos.shape == cpu.shape and np.abs(pos - cpu).max() <= 1e-5 * stone.axis.length


def test_culling_off_draws_everything_and_stats_count_vertices(ctx, stone):
    params = field(stone, 200)
    view, proj = look((0.0, 1.7, 34.0), (0.0, 1.7, 80.0))
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(culling=False)) as r:
        draw(ctx, r, view, proj)
        assert r.stats == {"submitted": 200, "visible": 200, "levels": [200], "vertices": 200 * stone.vertex_count,
                           "culling": False, "lod": False, "indirect": False}
        assert r._culled == {}, "culling=False builds no culling pass"


# ------------------------------------------------------------------ LOD
@pytest.mark.slow
def test_lod_levels_share_the_base_axis_and_shrink(stone):
    levels = build_lod_levels(stone)
    assert 2 <= len(levels) <= 4
    assert levels[0].positions is stone.positions and levels[0].error == 0
    faces = [len(level.faces) for level in levels]
    assert faces == sorted(faces, reverse=True) and faces[-1] < faces[0] / 2
    errors = [level.error for level in levels]
    assert errors == sorted(errors) and errors[1] > 0
    assert base_radius(stone, *[level.positions for level in levels]) >= base_radius(stone)


@pytest.mark.slow
def test_lod_gpu_vertices_use_the_base_axis(ctx, stone):
    """Drawn at the coarsest level, an instance is that level's vertices bent
    with the BASE mesh's axis: the captured picture equals a render of the
    CPU-deformed level (compared through the renderer's own capture program
    would not show it, so compare silhouettes)."""
    levels = build_lod_levels(stone)
    coarse = levels[-1]
    params = ad.random_params(stone, 1, seed=3, variation=ad.Variation(bend=0.3))
    params[0, 10:13] = (0.0, 0.0, -6.0)
    view, proj = look((0.0, 0.0, 0.0), (0.0, 0.0, -6.0), fovy=30, aspect=1)
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(lod=True, lod_error=1e6)) as r:
        img = draw(ctx, r, view, proj, size=(96, 96))
        assert r.stats["levels"][-1] == 1 and r.stats["vertices"] == coarse.vertex_count
    world, _ = ad.deform(stone.axis, coarse.positions, coarse.normals, params)
    ref_mesh = make_mesh(world[0] - params[0, 10:13], coarse.faces, "coarse")
    rigid = params.copy()
    rigid[:, :10] = 0
    rigid[:, 13:16] = 0
    with ad.AxialRenderer(ctx, ref_mesh, rigid, options=ad.RenderOptions(cull_back_faces=stone.is_volume)) as ref:
        expected = draw(ctx, ref, view, proj, size=(96, 96))
    bg = np.round(np.array(BACKGROUND) * 255)
    mask_a, mask_b = (img != bg).any(axis=2), (expected != bg).any(axis=2)
    assert mask_a.sum() > 200 and (mask_a != mask_b).sum() <= 0.03 * mask_a.sum()


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["plain", "quantized", "extended", "extended+quantized"])
def test_lod_picks_levels_by_screen_error_and_stays_close(ctx, stone, kind):
    params = extended_field(stone, 3000) if kind.startswith("extended") else field(stone)
    quantized = kind.endswith("quantized")
    view, proj = look((1.0, 1.7, 0.5), (25.0, 0.2, 12.0))
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(quantized=quantized)) as full, \
            ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(lod=True, quantized=quantized)) as lod:
        a = draw(ctx, full, view, proj, size=(320, 240))
        b = draw(ctx, lod, view, proj, size=(320, 240))
        levels = lod.stats["levels"]
        assert len(levels) == len(lod.lod_levels) and sum(levels) == lod.stats["visible"]
        assert levels[0] > 0 and sum(levels[1:]) > 0, levels
        assert lod.stats["vertices"] < full.stats["vertices"]
        drawn = lod.instances.read()
        centers, radii = instance_bounds(stone, drawn, radius=lod.bound_radius)
        eye = np.linalg.inv(view.astype(np.float64))[3, :3]
        visible = spheres_visible(centers, radii, frustum_planes(view, proj))
        scale = drawn[visible, 16] if drawn.shape[1] == 19 else None
        cpu = lod_choice(centers[visible], radii[visible], [lv.error for lv in lod.lod_levels], eye,
                         proj[1, 1] * 240 / 2, 1.0, scale=scale)
        assert np.abs(np.bincount(cpu, minlength=len(levels)) - levels).sum() <= 4, (cpu, levels)
    assert np.abs(a.astype(int) - b).mean() / 255 < 0.01


def test_lod_bad_input(ctx, stone):
    for bad in (0, -1, float("nan"), "x"):
        with pytest.raises(ad.core.ParamError, match="lod_error: expected a number of pixels > 0"):
            ad.AxialRenderer(ctx, stone, field(stone, 3), options=ad.RenderOptions(lod=True, lod_error=bad))
    tetra = make_mesh([(0, 0, 0), (2, 0, 0), (0.6, 0.8, 0), (0.6, 0.3, 0.7)], [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)])
    with pytest.warns(UserWarning, match="too few to simplify"):
        with ad.AxialRenderer(ctx, tetra, ad.random_params(tetra, 3), options=ad.RenderOptions(lod=True)) as r:
            assert len(r.lod_levels) == 1


# ------------------------------------------------------------------ extended instances and wind
def extended_field(mesh, n=2000, seed=6):
    return ad.random_params(mesh, n, seed=seed, variation=ad.Variation(bend=0.2, scale=(0.5, 1.8), twist=2.5, taper=0.8, tilt=(-3, 3)),
                            placement="disc", spacing=1.0 * mesh.axis.length)


def test_bounds_cover_scale_twist_taper_and_wind(ctx, tmp_path, stone, leaf):
    """Extended instances (scale, twist, taper) and a gusty wind at several
    moments: every GPU-captured vertex lies in its sphere; the spheres stay
    within 1.5x the tight ones on average without wind."""
    from axialdeform.core.wind import Wind

    wind = Wind(direction=(1.0, 0.0, 0.4), strength=0.3, gustiness=0.7, frequency=0.8, wavelength=4.0)
    for name, mesh in meshes_for_all_axes(tmp_path, stone, leaf).items():
        params = extended_field(mesh, 300, seed=len(name))
        assert params.shape == (300, 19)
        L = mesh.axis.length
        with ad.AxialRenderer(ctx, mesh, params) as r:
            still, _ = r.capture()
            centers, radii = instance_bounds(mesh, params)
            dist = np.linalg.norm(still - centers[:, None, :], axis=2).max(axis=1)
            assert (dist <= radii + 1e-5 * L).all(), name
            assert (radii / dist).mean() <= 1.5, (name, (radii / dist).mean())
            lo, hi = instance_boxes(mesh, params)
            assert (still >= lo[:, None] - 1e-5 * L).all() and (still <= hi[:, None] + 1e-5 * L).all(), name
            wc, wr = instance_bounds(mesh, params, wind=wind)
            assert np.array_equal(wc, centers) and (wr > radii).all()
            for t in (0.0, 0.37, 1.9, 5.2):
                moving, _ = r.capture(time=t, wind=wind)
                assert np.abs(moving - still).max() > 0.05 * L  # the wind really moves them
                assert (np.linalg.norm(moving - wc[:, None, :], axis=2) <= wr[:, None] + 1e-5 * L).all(), (name, t)


@pytest.mark.slow
@pytest.mark.parametrize("quantized, indirect", [(False, True), (True, True), (True, False)])
def test_culled_picture_equals_unculled_extended_and_windy(ctx, stone, quantized, indirect):
    from axialdeform.core.wind import Wind

    params = extended_field(stone, 3000)
    wind = Wind(direction=(0.3, 0.0, 1.0), strength=0.4, gustiness=0.8, frequency=1.0, wavelength=6.0)
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(quantized=quantized, wind=wind, indirect=indirect)) as culled, \
            ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(quantized=quantized, wind=wind, culling=False)) as full:
        assert culled.extended and culled._culled == {}
        for name in ("inside the field", "at its edge, looking in", "at its edge, looking away"):
            view, proj = look(*CAMERAS[name])
            for t in (0.0, 0.8):
                full.time = culled.time = t
                a = draw(ctx, full, view, proj)
                b = draw(ctx, culled, view, proj)
                assert np.array_equal(a, b), (name, t, int((a != b).any(axis=2).sum()))
                assert culled.stats["visible"] < len(params)
        cull = culled._cull_passes[False]
        assert cull.out_bytes == (40 if quantized else 76) + 4


# ------------------------------------------------------------------ the command line
@pytest.mark.slow
def test_cli_render_stats_no_cull_lod_and_bad_lod_error(tmp_path, capsys):
    import subprocess
    import sys

    from PIL import Image

    from axialdeform.cli import main

    params = tmp_path / "p.adp"
    assert main(["random", "stone", "-n", "400", "--placement", "disc", "-o", str(params)]) == 0
    capsys.readouterr()
    pngs = {}
    for name, extra in {"cull": [], "nocull": ["--no-cull"], "lod": ["--lod-error", "3"]}.items():
        pngs[name] = tmp_path / f"{name}.png"
        assert main(["render", "stone", str(params), "-o", str(pngs[name]), "--size", "160x120", "--stats", *extra]) == 0
        out = capsys.readouterr().out
        assert "instances: 400 submitted, " in out and " ms" in out and "vertices processed:" in out, out
        assert ("culling off" in out) == (name == "nocull")
        assert ("LOD levels" in out) == (name == "lod")
    images = {k: np.asarray(Image.open(v)) for k, v in pngs.items()}
    assert np.array_equal(images["cull"], images["nocull"])
    assert not np.array_equal(images["cull"], images["lod"])  # levels of detail do change pixels
    for bad in ("0", "-2", "nan"):
        run = subprocess.run([sys.executable, "-m", "axialdeform", "render", "stone", str(params), "-o",
                              str(tmp_path / "x.png"), "--lod-error", bad], capture_output=True, text=True)
        assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr
        assert run.stderr.strip().count("\n") == 0 and "lod_error: expected a number of pixels > 0" in run.stderr
        assert not (tmp_path / "x.png").exists()


@pytest.mark.slow
def test_viewer_draws_a_field_with_culling_and_lod(ctx):
    from axialdeform.viewer import LOD_AUTO_COUNT, Viewer

    stone = ad.load_mesh("stone")
    params = ad.random_params(stone, 2000, seed=2)
    v = Viewer.create(stone, params, headless=True, size=(160, 120), options=ad.RenderOptions(lod=True, lod_error=2.0))
    try:
        assert v.renderer.culling_enabled and v.renderer.lod and len(v.renderer.lod_levels) >= 2
        v.orbit.zoom(0.3)  # zoom into the field: most instances leave the view
        v.step(2)
        assert 0 < v.renderer.stats["visible"] < 2000
        assert "2000 instances - solid" in v.status() and f" - {v.renderer.stats['visible']} drawn - " in v.status()
    finally:
        v.release()
        v.wnd.destroy()
    ctx.__enter__()
    assert LOD_AUTO_COUNT == 100_000


def test_culling_follows_set_params_and_set_tint(ctx, stone):
    """Growing the instance buffer and re-tinting after the pass exists: the
    culled picture still equals the unculled one."""
    small, big = field(stone, 100, seed=1), field(stone, 1500, seed=2)
    view, proj = look((1.0, 1.7, 0.5), (25.0, 0.2, 12.0))
    with ad.AxialRenderer(ctx, stone, small) as culled, ad.AxialRenderer(ctx, stone, small,
                                                                         options=ad.RenderOptions(culling=False)) as full:
        assert np.array_equal(draw(ctx, full, view, proj), draw(ctx, culled, view, proj))
        for r in (culled, full):
            r.set_params(big)
            r.set_tint(np.random.default_rng(3).uniform(0, 1, (1500, 3)))
        assert np.array_equal(draw(ctx, full, view, proj), draw(ctx, culled, view, proj))
        assert 0 < culled.stats["visible"] < 1500
        for r in (culled, full):
            r.set_tint(None)
            r.set_params(big[:700])
        assert np.array_equal(draw(ctx, full, view, proj), draw(ctx, culled, view, proj))
        assert culled.stats["submitted"] == 700


# ------------------------------------------------------------------ property: the numpy bound, many random instances
_finite = dict(allow_nan=False, allow_infinity=False)


@settings(max_examples=150, deadline=None)
@given(offsets=arrays(np.float64, (4, 10), elements=st.floats(-3, 3, **_finite)),
       place=arrays(np.float64, (4, 6), elements=st.floats(-50, 50, **_finite)),
       extra=st.tuples(st.floats(0.05, 4, **_finite), st.floats(-12, 12, **_finite), st.floats(-3, 0.99, **_finite)),
       extended=st.booleans())
def test_bound_holds_the_cpu_reference_for_any_parameters(stone, offsets, place, extra, extended):
    """Any offsets, positions, angles (and scale, twist, taper): every vertex
    of the CPU reference deformation lies in the sphere and the box."""
    params = np.hstack([offsets, place]).astype(np.float32)
    if extended:
        params = np.hstack([params, np.tile(np.asarray(extra, np.float32), (4, 1))])
    world, _ = ad.deform(stone.axis, stone.positions, stone.normals, params)
    world = world.astype(np.float64)
    centers, radii = instance_bounds(stone, params)
    tol = 1e-5 * (1 + np.abs(place).max() + radii.max())
    assert (np.linalg.norm(world - centers[:, None], axis=2) <= radii[:, None] + tol).all()
    lo, hi = instance_boxes(stone, params)
    assert (world >= lo[:, None] - tol).all() and (world <= hi[:, None] + tol).all()


# ------------------------------------------------------------------ the two paths: indirect (GL >= 4.3) and query (GL 3.3)
def _compacted(cull, counts):
    """The compacted records of every level, as bytes (levels one after another)."""
    return cull.output.read(size=max(sum(counts), 1) * cull.out_bytes)[: sum(counts) * cull.out_bytes]


@pytest.mark.slow
@pytest.mark.parametrize("variant", ["plain", "quantized+tinted", "extended"])
def test_indirect_and_query_paths_agree_with_lod(ctx, stone, variant):
    """With LOD on, the indirect path (compute + indirect draws) and the GL 3.3
    path (transform feedback + query) keep the same instances at the same
    levels, write the same compacted records, and draw the same picture, which
    is also the picture of LOD without culling; on every test camera."""
    params = extended_field(stone, 3000) if variant == "extended" else field(stone)
    quantized = "quantized" in variant
    kw = dict(quantized=quantized, lod=True, lod_error=2.0)
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(indirect=True, **kw)) as ind, \
            ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(indirect=False, **kw)) as query, \
            ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(culling=False, **kw)) as uncull:
        if "tinted" in variant:
            tint = np.random.default_rng(5).uniform(0, 1, (len(params), 3))
            for r in (ind, query, uncull):
                r.set_tint(tint)
        tinted = "tinted" in variant
        used_levels = set()
        for name, (eye, target) in CAMERAS.items():
            view, proj = look(eye, target)
            a, b, c = (draw(ctx, r, view, proj) for r in (ind, query, uncull))
            assert ind.stats["indirect"] and not query.stats["indirect"]
            assert ind.stats == {**query.stats, "indirect": True}, name
            assert np.array_equal(a, b), (name, int((a != b).any(axis=2).sum()))
            assert np.array_equal(a, c), (name, int((a != c).any(axis=2).sum()))
            assert uncull.stats["visible"] == len(params) and uncull.stats["lod"]
            counts = ind.stats["levels"]
            used_levels |= {k for k, n in enumerate(counts) if n}
            ca, cb = ind._cull_passes[tinted], query._cull_passes[tinted]
            assert ca.indirect and not cb.indirect
            assert _compacted(ca, counts) == _compacted(cb, counts), name
        assert len(used_levels) >= 2, used_levels  # the cameras exercise several levels


def test_an_indirect_frame_never_waits_for_the_count(ctx, stone, monkeypatch):
    """On the indirect path render() reads nothing back from the GPU (no
    query, no buffer read); the counts are read once, when stats is asked,
    and describe that render even after a shadow pass ran the cull again."""
    import moderngl

    import axialdeform.gl.renderer as renderer_module

    params = field(stone, 800)
    view, proj = look(*CAMERAS["inside the field"])
    reads = []
    original_read = moderngl.Buffer.read

    def counting_read(self, *args, **kwargs):
        reads.append(self)
        return original_read(self, *args, **kwargs)

    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(indirect=True)) as r, \
            ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(indirect=False)) as ref, ad.gl.ShadowMap(ctx, 256) as shadow:
        expected = draw(ctx, ref, view, proj)
        with Offscreen(ctx, (160, 120), samples=4) as target:
            monkeypatch.setattr(moderngl.Buffer, "read", counting_read)
            target.use(BACKGROUND)
            r.render(view, proj)
            assert reads == [], "render() read a buffer back"
            monkeypatch.setattr(moderngl.Buffer, "read", original_read)
            picture = target.read()
        assert np.array_equal(picture, expected)
        shadow.fit(stone, params[:50])
        r.render_shadow(shadow)  # runs the cull again, for the light: the stats stay those of render()
        monkeypatch.setattr(renderer_module, "read_counts", lambda *a: reads.append("counts") or [7])
        assert r.stats["visible"] == 7 and r.stats["levels"] == [7] and reads == ["counts"]
        assert r.stats["visible"] == 7 and reads == ["counts"], "read once"
        monkeypatch.undo()
        draw(ctx, r, view, proj)
        assert r.stats["visible"] == ref.stats["visible"] and 0 < ref.stats["visible"] < 800


def test_the_path_is_chosen_by_version_and_can_be_forced(ctx, stone, monkeypatch):
    from axialdeform.gl.cull import INDIRECT_ENV, choose_indirect, indirect_supported

    class GL33:
        version_code = 330

    assert not indirect_supported(GL33()) and not choose_indirect(GL33(), None)
    with pytest.raises(ad.core.ContextError, match="indirect: the indirect culling path needs OpenGL >= 4.3"):
        choose_indirect(GL33(), True)
    assert indirect_supported(ctx) == (ctx.version_code >= 430)
    params = field(stone, 100)
    view, proj = look(*CAMERAS["inside the field"])
    monkeypatch.setenv(INDIRECT_ENV, "0")
    with ad.AxialRenderer(ctx, stone, params) as r:
        draw(ctx, r, view, proj)
        assert not r._cull_passes[False].indirect and r.stats["indirect"] is False
    monkeypatch.delenv(INDIRECT_ENV)
    with ad.AxialRenderer(ctx, stone, params) as r:
        draw(ctx, r, view, proj)
        assert r._cull_passes[False].indirect == indirect_supported(ctx) and r.stats["indirect"] == indirect_supported(ctx)


def test_indirect_pass_on_a_two_dimensional_grid_of_work_groups(ctx, stone, monkeypatch):
    """More blocks than work groups along x (65 535 in GL; 5 here) go on a
    second grid dimension; the extra groups of the last row write nothing."""
    import axialdeform.gl.cull as cull_module

    params = field(stone)  # 3000 instances: 24 blocks of 128 -> a 5 x 5 grid
    view, proj = look(*CAMERAS["at its edge, looking in"])
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(indirect=True)) as r:
        expected = draw(ctx, r, view, proj)
        counts = r.stats["levels"]
        records = _compacted(r._cull_passes[False], counts)
        monkeypatch.setattr(cull_module, "_MAX_GROUPS", 5)
        picture = draw(ctx, r, view, proj)
        assert r.stats["levels"] == counts and 0 < counts[0] < len(params)
        assert _compacted(r._cull_passes[False], counts) == records
        assert np.array_equal(picture, expected)
        r._cull_passes[False].storage_limit = 1000  # buffers over the storage-block limit: the GL 3.3 path
        picture = draw(ctx, r, view, proj)
        assert r.stats["levels"] == counts and r.stats["indirect"] is False
    assert np.array_equal(picture, expected)


@pytest.mark.parametrize("indirect", [True, False], ids=["indirect", "query"])
def test_shadow_pass_culls_casters_to_the_light_volume(ctx, stone, indirect):
    """A shadow map fitted to part of the field: the culled shadow pass keeps
    only the casters that reach the light's view volume and writes the same
    depth map as drawing every instance."""
    params = field(stone)
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(indirect=indirect)) as culled, \
            ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(culling=False)) as full, \
            ad.gl.ShadowMap(ctx, 512) as shadow:
        maps = []
        corner = params[(params[:, 10] > 0.5 * EDGE) & (params[:, 12] > 0.3 * EDGE)]
        for part in (corner, params):  # a corner of the field, then all of it
            shadow.fit(stone, part)
            full.render_shadow(shadow)
            plain = np.frombuffer(shadow.texture.read(), "f4")
            culled.render_shadow(shadow)
            result = culled.shadow_result
            kept = result.counts() if indirect else result
            assert np.array_equal(np.frombuffer(shadow.texture.read(), "f4"), plain)
            assert (plain < 1.0).mean() > 0.05  # the map holds shadows
            maps.append(kept[0])
        assert len(corner) <= maps[0] < len(params) / 3 and maps[1] == len(params), (len(corner), maps)
        assert full.shadow_result is None  # culling off: every caster, no pass


@pytest.mark.slow
def test_field_bench_reports_both_paths(ctx):
    """The field bench on a small field: every culled picture is the unculled
    one, both paths (indirect draws, query wait) draw the same instances,
    and the report names both with their pass share."""
    from axialdeform.bench.field import format_field, run_field

    res = run_field(3000, (96, 72), frames=1, ctx=ctx, all_visible_frames=1)
    for view in ("across", "out"):
        d = res["views"][view]["draws"]
        assert d["cull"]["identical"] and d["cull (query)"]["identical"]
        assert d["cull"]["stats"]["indirect"] == (ctx.version_code >= 430)
        assert not d["cull (query)"]["stats"]["indirect"]
        for lod in ("cull+lod", "cull+lod (query)"):
            assert d[lod]["stats"]["lod"] and d[lod]["mean_pixel_error"] < 0.05
        assert d["cull"]["stats"]["levels"] == d["cull (query)"]["stats"]["levels"]
        assert d["cull+lod"]["stats"]["levels"] == d["cull+lod (query)"]["stats"]["levels"]
        assert 0 < d["cull"]["stats"]["visible"] < 3000
    av = res["all_visible"]
    assert av["visible"] == 3000 and av["indirect"] == (ctx.version_code >= 430) and not av["query_indirect"]
    text = format_field(res)
    assert "cull (indirect draws): culled frame" in text and "cull (query wait): culled frame" in text
    assert "% of the instances in view: culling alone removes at most" in text


def test_a_compute_pass_that_does_not_build_falls_back_to_the_query_path(ctx, stone, monkeypatch):
    import axialdeform.gl.cull as cull_module

    params = field(stone, 300)
    view, proj = look(*CAMERAS["inside the field"])
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(culling=False)) as full:
        expected = draw(ctx, full, view, proj)

    def broken(*args, **kwargs):
        raise ad.core.ShaderError("glsl/cull.comp, line 1 (compute shader): error: no compute here")

    monkeypatch.setattr(cull_module, "build_compute", broken)
    if not cull_module.indirect_supported(ctx):
        monkeypatch.setattr(cull_module, "indirect_supported", lambda ctx: True)
    with ad.AxialRenderer(ctx, stone, params) as r:
        with pytest.warns(RuntimeWarning, match="indirect culling unavailable, using transform feedback: .*cull.comp"):
            picture = draw(ctx, r, view, proj)
        assert r.stats["culling"] and not r.stats["indirect"] and 0 < r.stats["visible"] < 300
        assert not r._cull_passes[False].indirect
    assert np.array_equal(picture, expected)


@pytest.mark.slow
def test_a_gl_3_3_context_takes_the_query_path(tmp_path):
    """Mesa told to report GL 3.3 (``MESA_GL_VERSION_OVERRIDE``): the
    renderer picks transform feedback + query by itself, draws the unculled
    picture, and ``indirect=True`` is refused with a ContextError."""
    import os
    import subprocess
    import sys

    script = tmp_path / "gl33.py"
    script.write_text(
        "import warnings, numpy as np, pyrr, axialdeform as ad\n"
        "warnings.simplefilter('error', RuntimeWarning)  # chosen by version, not a fallback after a failed build\n"
        "ctx = ad.create_context()\n"
        "assert ctx.version_code == 330, ctx.version_code\n"
        "stone = ad.load_mesh('stone')\n"
        "params = ad.random_params(stone, 500, seed=4, bend=0.15, placement='disc', spacing=stone.axis.length)\n"
        "view = pyrr.matrix44.create_look_at((1.0, 1.7, 0.5), (25.0, 0.2, 12.0), (0, 1, 0), dtype=np.float32)\n"
        "proj = pyrr.matrix44.create_perspective_projection(60.0, 4 / 3, 0.05, 400.0, dtype=np.float32)\n"
        "pictures = []\n"
        "for culling in (True, False):\n"
        "    with ad.AxialRenderer(ctx, stone, params, culling=culling) as r, ad.Offscreen(ctx, (96, 72)) as t:\n"
        "        t.use((1, 1, 1)); r.render(view, proj); pictures.append(t.read())\n"
        "        if culling:\n"
        "            assert r.stats['culling'] and not r.stats['indirect'] and 0 < r.stats['visible'] < 500, r.stats\n"
        "            assert not r._cull_passes[False].indirect\n"
        "assert np.array_equal(*pictures)\n"
        "try:\n"
        "    ad.AxialRenderer(ctx, stone, params, indirect=True)\n"
        "except ad.core.ContextError as exc:\n"
        "    assert 'needs OpenGL >= 4.3' in str(exc) and '330' in str(exc), exc\n"
        "else:\n"
        "    raise AssertionError('indirect=True on GL 3.3 was accepted')\n"
        "assert ctx.error == 'GL_NO_ERROR'\n"
        "print('ok')\n")
    env = {**os.environ, "MESA_GL_VERSION_OVERRIDE": "3.3"}
    env.pop("AXIALDEFORM_INDIRECT", None)
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 0 and run.stdout.strip().endswith("ok"), run.stdout + run.stderr

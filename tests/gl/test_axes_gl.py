"""Several axes on the GPU (AXIAL_AXES): one draw, the child axes' offsets
fetched from a texture by instance id; the capture equals the CPU
reference for K = 1 .. 16, with wind, quantized and extended; culling
(its bounds cover every axis) never changes the picture."""

import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

import axialdeform as ad
from axialdeform.core.axes import TREE_AXES
from axialdeform.gl.renderer import AxialRenderer

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
import make_tree  # noqa: E402 - tools/ is not a package

from helpers.models import blended  # noqa: E402


def comb(k: int, seed: int = 0):
    """A trunk and k − 1 branches (some on branches: depth up to 3), one axis each."""
    rng = np.random.default_rng(seed)
    scene = trimesh.Scene()
    scene.add_geometry(make_tree.tube([0, 0, 0], [0, 3, 0], 0.15, 0.06, rings=9), geom_name="a0", node_name="a0")
    ends = [((0.0, 0.0, 0.0), (0.0, 3.0, 0.0))]
    spec = [{"part": "a0", "axis": "y"}]
    for i in range(1, k):
        parent = int(rng.integers(0, i)) if i > 3 else 0
        a, b = map(np.asarray, ends[parent])
        start = a + rng.uniform(0.3, 0.8) * (b - a)
        d = rng.normal(size=3)
        d[1] = abs(d[1]) + 0.5
        end = start + (0.5 + 0.5 * rng.random()) * d / np.linalg.norm(d)
        scene.add_geometry(make_tree.tube(start, end, 0.04, 0.02, rings=5, sides=5), geom_name=f"a{i}", node_name=f"a{i}")
        ends.append((tuple(start), tuple(end)))
        spec.append({"part": f"a{i}", "parent": f"a{parent}", "axis": "oriented"})
    return ad.load_mesh(scene).with_axes(spec)


def _params(mesh, n=40, seed=1, extended=False):
    options = {"scale": (0.6, 1.4), "twist": 0.8, "taper": 0.4} if extended else {}
    return ad.random_params(mesh, n, seed=seed, variation=ad.Variation(bend=(0.1, 0.3, 0.3), **options), placement="disc", spacing=3.0)


def _check_capture(ctx, mesh, p, **kw):
    with AxialRenderer(ctx, mesh, p, **kw) as r:
        gpu = r.capture()
    cpu = ad.deform(mesh, p)
    L = mesh.axis.length
    reach = max(1.0, float(np.abs(p[:, -9 if p.shape[1] % 10 == 9 else -6:][:, :3]).max()) / L)
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * L * reach
    assert np.abs(gpu[1] - cpu[1]).max() <= 1e-5 * 10  # normals through cof(J) in float32
    return gpu


@pytest.mark.parametrize("k", range(1, 17))
def test_gpu_equals_cpu_for_every_axis_count(ctx, k):
    mesh = comb(k, seed=k)
    assert mesh.axis_count == k
    for extended in (False, True):
        _check_capture(ctx, mesh, _params(mesh, extended=extended))


def test_quantized_trees_equal_the_cpu(ctx):
    mesh = ad.load_mesh("tree", axes=TREE_AXES)
    p = _params(mesh, n=60, extended=True)
    with AxialRenderer(ctx, mesh, p, options=ad.RenderOptions(quantized=True)) as r:
        gpu = r.capture()
        standard = r.instances.read()
        children = r._axes.read()
    from axialdeform.core.record import join_record, split_record

    assert np.array_equal(children, split_record(p, 10)[1])  # the texture holds the float32 numbers as given
    used = join_record(standard, children)
    cpu = ad.deform(mesh, used)
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * mesh.axis.length * 3


def test_wind_sways_every_axis_on_gpu_as_on_cpu(ctx):
    mesh = ad.load_mesh("tree", axes=TREE_AXES)
    p = _params(mesh, n=30)
    wind = ad.Wind(direction=(1.0, 0.0, 0.3), strength=0.15, gustiness=0.6, frequency=0.5)
    with AxialRenderer(ctx, mesh, p, options=ad.RenderOptions(wind=wind)) as r:
        gpu = r.capture(time=4.0)
        still = r.capture(wind=None)
    cpu = ad.bake(mesh, p, "cpu", options=ad.RenderOptions(wind=wind, time=4.0))
    L = mesh.axis.length
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * L * 3
    moved = np.linalg.norm(gpu[0] - still[0], axis=-1)  # the tips of the branches move most
    va = mesh.tree.vertex_axis
    assert moved[:, va >= 7].mean() > moved[:, va == 0].mean()


def test_update_params_reaches_the_child_axes(ctx):
    mesh = comb(4, seed=2)
    p = _params(mesh, n=20)
    q = _params(mesh, n=5, seed=9)
    with AxialRenderer(ctx, mesh, p) as r:
        r.update_params(q, start=7)
        gpu = r.capture()
    p[7:12] = q
    cpu = ad.deform(mesh, p)
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * mesh.axis.length * 3


def test_culling_a_forest_never_changes_its_picture(ctx):
    mesh = ad.load_mesh("tree", axes=TREE_AXES)
    # branches swung far (2 L_j): a tree whose trunk is out of view reaches into it by its branches alone
    p = ad.random_params(mesh, 300, seed=3, variation=ad.Variation(bend=(0.05, 2.0, 2.0)), placement="disc", spacing=2.0)
    look = ad.Look(ground=False, shadow=False)
    camera = ad.Camera(eye=(6.0, 3.0, 5.0), target=(0.0, 1.5, 0.0), fovy=45.0)  # inside the forest
    view, proj = camera.view(), camera.projection(240 / 160)
    target = ad.Offscreen(ctx, (240, 160))
    try:
        with AxialRenderer(ctx, mesh, p, options=ad.RenderOptions(culling=True)) as r:
            target.use(look.background)
            r.render(view, proj, look=look)
            culled = target.read()
            visible = r.stats["visible"]
            target.use(look.background)
            r.culling_enabled = False
            r.render(view, proj, look=look)
            full = target.read()
    finally:
        target.release()
    assert visible < 300  # some were culled
    assert np.array_equal(culled, full)
    # every tree with a vertex in the view volume is kept (CPU: its deformed vertices in clip space)
    world = ad.deform(mesh, p)[0].astype(np.float64)
    clip = np.concatenate([world, np.ones(world.shape[:2] + (1,))], axis=-1) @ view.astype(np.float64) @ proj
    w = clip[..., 3:]
    inside = ((np.abs(clip[..., :3]) <= w) & (w > 0)).all(axis=-1).any(axis=-1)
    trunks_out = inside & ~((np.abs(clip[..., :3]) <= w) & (w > 0)).all(axis=-1)[:, mesh.tree.vertex_axis == 0].any(axis=-1)
    assert trunks_out.sum() >= 3  # trees seen by their branches alone: what the child axes' reach is for
    assert visible >= inside.sum()
    assert (np.abs(full.astype(int) - full[0, 0]).max(axis=-1) > 30).mean() > 0.2  # trees fill the picture


def test_levels_of_detail_of_a_tree_keep_each_vertex_on_its_axis(ctx):
    """Every part is simplified on its own; each simplified vertex keeps its
    part's axis, and the GPU bends every level as the CPU does."""
    from axialdeform.core.axes import AxisTree

    mesh = ad.load_mesh("tree", axes=TREE_AXES)
    p = _params(mesh, n=20)
    with AxialRenderer(ctx, mesh, p, options=ad.RenderOptions(lod=True)) as r:
        levels = r.lod_levels
        assert len(levels) >= 3
        for level in range(1, len(levels)):
            lv = levels[level]
            for part in lv.parts:  # a part's vertices: that part's axis only
                used = np.unique(lv.faces[part.start:part.start + part.count])
                assert set(lv.vertex_axis[used]) == {mesh.tree.names.index(part.name)}
            gpu, _ = r.capture(level=level)
            same = ad.BaseMesh(lv.positions, lv.normals, lv.faces, name="level",
                               tree=AxisTree(mesh.tree.axes, mesh.tree.parents, lv.vertex_axis, mesh.tree.names))
            cpu, _ = ad.deform(same, p)
            assert np.abs(gpu - cpu).max() <= 1e-5 * mesh.axis.length * 3
        target = ad.Offscreen(ctx, (160, 120))
        try:
            cam = ad.Camera(eye=(30.0, 12.0, 30.0), target=(0.0, 1.0, 0.0), fovy=20.0)
            target.use()
            r.render(cam.view(), cam.projection(160 / 120))
            assert sum(r.stats["levels"][1:]) > 0  # far trees drawn coarser
        finally:
            target.release()


def test_more_trees_than_the_offsets_texture_holds_is_said_in_words(ctx, monkeypatch):
    from axialdeform.core import ParamError

    mesh = comb(3, seed=1)
    p = _params(mesh, n=10)
    monkeypatch.setitem(ctx.info, "GL_MAX_TEXTURE_SIZE", 1)  # one row: 4095 texels, 682 instances of 3 axes
    with pytest.raises(ParamError, match="instances: 700 of 3 axes need a 4095 x 2 offsets texture"):
        AxialRenderer(ctx, mesh, p, capacity=700).release()
    with AxialRenderer(ctx, mesh, p, capacity=682) as r:
        assert r.count == 10


def test_gpu_equals_cpu_for_axes_from_the_shape(ctx, tmp_path, monkeypatch):
    """axes="skeleton" on a one-piece wood (tests/helpers/one_piece.py): one draw bends every branch as
    the CPU reference does."""
    from helpers.one_piece import one_piece_tree

    monkeypatch.setenv("AXIALDEFORM_CACHE", str(tmp_path))
    mesh = one_piece_tree().with_axes("skeleton")
    assert mesh.axis_count == 5
    _check_capture(ctx, mesh, _params(mesh, n=12))


def test_vertices_blending_two_chains_bend_on_the_gpu_as_on_the_cpu(ctx):
    """A vertex blending two axes' chains (AxisTree.blend: one float a vertex, b + 64 b1 + 4096 q): the GPU
    equals the CPU, extended and in the wind; the blend moves the vertices it weighs and no other."""
    mesh = ad.load_mesh("tree", axes=TREE_AXES)
    mixed = blended(mesh)
    for extended in (False, True):
        gpu = _check_capture(ctx, mixed, _params(mixed, n=20, extended=extended))
    p = _params(mixed, n=20)
    plain, _ = ad.deform(mesh, p)
    moved = np.abs(ad.deform(mixed, p)[0] - plain).max(axis=(0, 2))
    w = mixed.tree.blend[:, 1]
    other = mixed.tree.blend[:, 0] != mixed.tree.vertex_axis
    assert np.all(moved[w == 0] == 0) and np.median(moved[(w > 0.2) & other]) > 1e-3 * mesh.axis.length
    wind = ad.Wind(direction=(1.0, 0.0, 0.3), strength=0.15, gustiness=0.6, frequency=0.5)
    with AxialRenderer(ctx, mixed, p, options=ad.RenderOptions(wind=wind)) as r:
        gpu = r.capture(time=4.0)
    cpu = ad.bake(mixed, p, "cpu", options=ad.RenderOptions(wind=wind, time=4.0))
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * mesh.axis.length * 3


def test_a_blended_tree_keeps_its_blends_through_its_code_a_glb_and_its_levels(ctx, tmp_path):
    from axialdeform.core.blend import split_vertex_code

    mesh = ad.load_mesh("tree", axes=TREE_AXES)
    mixed = blended(mesh)
    va, blend = split_vertex_code(mixed.tree.vertex_code)
    assert np.array_equal(va, mixed.tree.vertex_axis) and np.array_equal(blend[blend[:, 1] > 0], mixed.tree.blend[blend[:, 1] > 0])
    assert split_vertex_code(mesh.tree.vertex_code)[1] is None  # no blend: the code is the axis
    p = _params(mixed, n=6)
    from axialdeform.core.io.gltf_read import read_instanced_glb

    ad.export_glb(tmp_path / "blended.glb", mixed, p, "instanced")
    back, q = read_instanced_glb(tmp_path / "blended.glb")
    assert back.tree.blend is not None and np.array_equal(back.tree.vertex_code, mixed.tree.vertex_code)
    assert np.abs(ad.deform(back, q)[0] - ad.deform(mixed, p)[0]).max() <= 1e-5 * mesh.axis.length
    with AxialRenderer(ctx, mixed, p, options=ad.RenderOptions(lod=True)) as r:
        for level in range(1, len(r.lod_levels)):
            lv = r.lod_levels[level]
            assert set(np.unique(lv.vertex_axis)) <= set(np.unique(mixed.tree.vertex_code))  # whole codes, none mixed

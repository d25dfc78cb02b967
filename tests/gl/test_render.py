"""The GPU path: capture == CPU reference, one draw call, deterministic
pictures, solid and wireframe silhouettes agree, buffer updates in place."""

from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

import axialdeform as ad
from axialdeform.gl.context import Offscreen

from helpers.gl_scenes import meshes_for_all_axes


def test_gpu_capture_equals_cpu_reference(ctx, tmp_path, stone, leaf):
    for name, mesh in meshes_for_all_axes(tmp_path, stone, leaf).items():
        L = mesh.axis.length
        params = ad.random_params(mesh, 1200, seed=11, variation=ad.Variation(bend=0.2, tilt=(-3, 3)), placement="disc")
        with ad.AxialRenderer(ctx, mesh, params) as r:
            gpu_pos, gpu_nrm = r.capture()
        cpu_pos, cpu_nrm = ad.deform(mesh.axis, mesh.positions, mesh.normals, params)
        assert gpu_pos.shape == (1200, mesh.vertex_count, 3)
        assert np.abs(gpu_pos - cpu_pos).max() <= 1e-5 * L, name
        assert np.abs(gpu_nrm - cpu_nrm).max() <= 1e-5, name
        # and the bend is really there (not a trivially equal zero deformation)
        rigid = ad.deform(mesh.axis, mesh.positions, mesh.normals, np.hstack([np.zeros((1200, 10), np.float32), params[:, 10:]]))[0]
        assert np.abs(cpu_pos - rigid).max() > 0.05 * L


def test_capture_in_chunks_and_slices(ctx, stone, monkeypatch):
    import axialdeform.gl.capture as R

    params = ad.random_params(stone, 100, seed=2, variation=ad.Variation(bend=0.3))
    monkeypatch.setattr(R, "_CAPTURE_BYTES", 58 * 24 * 7)  # 7 instances per pass
    with ad.AxialRenderer(ctx, stone, params) as r:
        pos, nrm = r.capture(start=13, count=40)
    cpu_pos, _ = ad.deform(stone.axis, stone.positions, stone.normals, params[13:53])
    assert np.abs(pos - cpu_pos).max() <= 1e-5 * stone.axis.length


def test_no_bend_program_is_rigid(ctx, stone):
    params = ad.random_params(stone, 50, seed=3, variation=ad.Variation(bend=0.3))
    with ad.AxialRenderer(ctx, stone, params, options=ad.RenderOptions(bend=False)) as r:
        pos, _ = r.capture()
    rigid = params.copy()
    rigid[:, :10] = 0
    assert np.abs(pos - ad.deform(stone.axis, stone.positions, stone.normals, rigid)[0]).max() <= 1e-5 * stone.axis.length


def test_one_draw_call_draws_every_instance(ctx, stone, monkeypatch):
    """All instances in ONE instanced draw call."""
    import moderngl

    calls = []
    original = moderngl.VertexArray.render

    def spy(self, *args, **kwargs):
        calls.append(kwargs.get("instances"))
        return original(self, *args, **kwargs)

    original_indirect = moderngl.VertexArray.render_indirect

    def spy_indirect(self, buffer, mode=None, count=-1, first=0):  # the culled draw on GL >= 4.3
        calls.append(int(np.frombuffer(buffer.read(size=20, offset=20 * first), "<u4")[1]))  # its instanceCount
        return original_indirect(self, buffer, mode, count, first)

    monkeypatch.setattr(moderngl.VertexArray, "render", spy)
    monkeypatch.setattr(moderngl.VertexArray, "render_indirect", spy_indirect)
    # whole draws: on llvmpipe a multisampled frame over 250 000 triangles is drawn in
    # slices, every instance in each (test_big_draws_are_sliced_with_the_same_picture)
    monkeypatch.setattr(ctx, "_axialdeform_flush", None, raising=False)
    params = ad.random_params(stone, 3000, seed=1)
    for mode in ad.gl.MODES:
        calls.clear()
        img = ad.render_image(stone, params, (160, 120), mode, ctx=ctx, look=ad.Look(fast=True))
        assert calls == [3000], mode
        assert (img != img[0, 0]).any()
        # with the extras: a shadow pass, and for wireframe a depth pre-pass, each
        # again one instanced draw of every instance; the ground is not instanced
        calls.clear()
        ad.render_image(stone, params, (160, 120), mode, ctx=ctx)
        assert [c for c in calls if c is not None] == [3000] * (3 if mode == "wireframe" else 2), mode
        assert calls.count(None) == 1  # the ground plane


def test_same_parameters_give_identical_pixels(ctx, stone):
    params = ad.random_params(stone, 1500, seed=4, variation=ad.Variation(bend=0.15))
    a = ad.render_image(stone, params, (320, 240), ("solid", "flat", "wireframe"), ctx=ctx)
    b = ad.render_image(stone, params, (320, 240), ("solid", "flat", "wireframe"), ctx=ctx)
    assert np.array_equal(a, b)
    other = ad.render_image(stone, ad.random_params(stone, 1500, seed=5, variation=ad.Variation(bend=0.15)), (320, 240), "solid", ctx=ctx)
    assert not np.array_equal(a[:, :320], other)


def _mask(img, background):
    return np.abs(img.astype(int) - background).sum(axis=2) > 12


def test_solid_and_wireframe_cover_the_same_silhouette(ctx, stone):
    params = ad.random_params(stone, 60, seed=8, variation=ad.Variation(bend=0.25), spacing=2.5 * stone.axis.length)
    # a black background: every lit stone pixel and every line differs from it
    img = ad.render_image(stone, params, (480, 360), ("solid", "wireframe"), ctx=ctx,
                          look=ad.Look(samples=0, background=(0, 0, 0), line_color=(1, 1, 1), fast=True))
    bg = img[0, 0].astype(int)
    solid, wire = _mask(img[:, :480], bg), _mask(img[:, 480:], bg)
    assert solid.mean() > 0.02
    # every wire pixel lies on a stone...
    assert (wire & ~ndimage.binary_dilation(solid, iterations=1)).sum() <= 0.002 * wire.sum()
    # ...and the filled wireframe covers the stones; lines and triangles
    # rasterize their borders differently, so compare up to one pixel
    filled = ndimage.binary_fill_holes(ndimage.binary_closing(wire, iterations=2))
    assert (solid & ~ndimage.binary_dilation(filled)).sum() <= 0.002 * solid.sum()
    assert (filled & ~ndimage.binary_dilation(solid)).sum() <= 0.002 * filled.sum()
    assert filled.sum() > 0.9 * solid.sum()
    # blobs: one per visible stone, the same count in both
    assert ndimage.label(solid)[1] == ndimage.label(filled)[1]


def test_flat_and_solid_differ_only_in_shading(ctx, stone):
    params = ad.random_params(stone, 40, seed=8, variation=ad.Variation(bend=0.25), spacing=2.5 * stone.axis.length)
    img = ad.render_image(stone, params, (320, 240), ("solid", "flat"), ctx=ctx, look=ad.Look(samples=0, fast=True))
    bg = img[0, 0].astype(int)
    solid, flat = _mask(img[:, :320], bg), _mask(img[:, 320:], bg)
    assert (solid ^ flat).sum() <= 0.01 * solid.sum()
    assert not np.array_equal(img[:, :320], img[:, 320:])


def test_parameter_updates_write_in_place(ctx, stone):
    params = ad.random_params(stone, 500, seed=1, variation=ad.Variation(bend=0.1))
    with ad.AxialRenderer(ctx, stone, params) as r:
        glo = r.instances.buffer.glo
        new = ad.random_params(stone, 500, seed=2, variation=ad.Variation(bend=0.1))
        r.set_params(new)
        r.update_params(params[100:150], start=100)
        expected = new.copy()
        expected[100:150] = params[100:150]
        assert np.array_equal(r.instances.read(), expected)
        assert r.instances.buffer.glo == glo and r.instances.reallocations == 0
        pos, _ = r.capture(start=100, count=50)
        assert np.abs(pos - ad.deform(stone.axis, stone.positions, stone.normals, params[100:150])[0]).max() < 1e-5 * stone.axis.length
        r.set_params(params[:10])  # fewer: no reallocation
        assert r.count == 10 and r.instances.reallocations == 0
        r.set_params(ad.random_params(stone, 900, seed=3))  # more than the capacity: grows once
        assert r.count == 900 and r.instances.reallocations == 1
        with pytest.raises(ad.core.ParamError, match="do not fit"):
            r.update_params(params[:5], start=898)


def test_release_is_safe_twice_and_use_after_release_fails(ctx, stone):
    r = ad.AxialRenderer(ctx, stone, ad.random_params(stone, 5))
    r.capture()
    r.release()
    r.release()
    with pytest.raises(ad.AxialDeformError, match="released"):
        r.render(np.eye(4), np.eye(4))


def test_render_with_callers_pyrr_matrices(ctx, stone):
    """The documented matrix convention: pyrr matrices as they come, clip = proj * view * world."""
    import pyrr

    params = ad.core.make_params(positions=[[0.0, 0.0, 0.0]])
    view = pyrr.matrix44.create_look_at([0.0, 0.0, 5.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    proj = pyrr.matrix44.create_perspective_projection(40.0, 1.0, 0.1, 100.0)
    with ad.AxialRenderer(ctx, stone, params) as r, Offscreen(ctx, (64, 64), samples=0) as target:
        target.use()
        r.render(view, proj)
        img = target.read()
        # the stone (long along x, centred) is drawn in the middle, wider than tall
        mask = _mask(img, img[0, 0].astype(int))
        ys, xs = np.nonzero(mask)
        assert abs(xs.mean() - 31.5) < 2 and abs(ys.mean() - 31.5) < 2
        assert np.ptp(xs) > 1.5 * np.ptp(ys)
        # moved right in world x -> right in the picture
        r.set_params(ad.core.make_params(positions=[[1.0, 0.0, 0.0]]))
        target.use()
        r.render(view, proj)
        assert np.nonzero(_mask(target.read(), img[0, 0].astype(int)))[1].mean() > xs.mean() + 5


def test_bad_mode_is_an_error(ctx, stone):
    with ad.AxialRenderer(ctx, stone, ad.random_params(stone, 2)) as r:
        with pytest.raises(ad.AxialDeformError, match="render mode: expected one of solid, flat, wireframe"):
            r.render(np.eye(4), np.eye(4), mode="points")


def _picture(ctx, renderers, view, proj, size=(320, 240)):
    with Offscreen(ctx, size, samples=0) as target:
        target.use()
        ctx.clear(0.9, 0.9, 0.9)
        for r in renderers:
            r.render(view, proj, "solid")
        return target.read().astype(int)


def test_back_faces_are_culled_only_where_nothing_changes(ctx, stone, leaf):
    """Default culling: on for a closed outward mesh (same picture, fewer
    triangles rasterized), off for an open one (two-sided leaves), and the
    draw leaves CULL_FACE off for whatever is drawn next."""
    from axialdeform.core.camera import frame_instances

    stones = ad.random_params(stone, 300, seed=3, variation=ad.Variation(bend=0.2))
    leaves = ad.random_params(leaf, 300, seed=3, variation=ad.Variation(bend=0.2))
    cam = frame_instances(stone, stones, 320 / 240)
    view, proj = cam.view(), cam.projection(320 / 240)
    with ad.AxialRenderer(ctx, stone, stones) as auto, \
            ad.AxialRenderer(ctx, stone, stones, options=ad.RenderOptions(cull_back_faces=False)) as two_sided:
        assert auto.cull_back_faces and not two_sided.cull_back_faces
        a, b = _picture(ctx, [auto], view, proj), _picture(ctx, [two_sided], view, proj)
        assert (np.abs(a - b).max(axis=2) > 2).sum() <= 3  # silhouettes may differ by a pixel's rounding
        # a mirroring camera (a reflection pass) turns the winding round: still the same picture as two-sided
        mirror = np.diag([-1.0, 1.0, 1.0, 1.0]).astype(np.float32)
        mview = (np.asarray(view, np.float32) @ mirror).astype(np.float32)  # pyrr layout: view, then mirror x
        ma, mb = _picture(ctx, [auto], mview, proj), _picture(ctx, [two_sided], mview, proj)
        assert (np.abs(ma - mb).max(axis=2) > 2).sum() <= 3
        assert (np.abs(ma - a).max(axis=2) > 30).sum() > 500  # the mirrored picture is another picture
    lcam = frame_instances(leaf, leaves, 320 / 240)
    lview, lproj = lcam.view(), lcam.projection(320 / 240)
    with ad.AxialRenderer(ctx, leaf, leaves) as auto, \
            ad.AxialRenderer(ctx, leaf, leaves, options=ad.RenderOptions(cull_back_faces=True)) as culled, \
            ad.AxialRenderer(ctx, stone, stones) as stone_r:
        assert not auto.cull_back_faces
        two = _picture(ctx, [auto], lview, lproj)
        one = _picture(ctx, [culled], lview, lproj)
        assert (np.abs(two - one).max(axis=2) > 30).sum() > 500  # culling does drop the leaves' backs
        # a culled draw first (the stones, far behind the near plane or not) must not cull the leaves after it
        after = _picture(ctx, [stone_r, auto], lview, lproj)
        alone = _picture(ctx, [stone_r], lview, lproj)
        leaf_px = np.abs(two - 0.9 * 255).max(axis=2) > 30
        stone_px = np.abs(alone - 0.9 * 255).max(axis=2) > 30
        only_leaf = leaf_px & ~stone_px
        assert only_leaf.sum() > 500
        assert np.array_equal(after[only_leaf], two[only_leaf])


def test_big_draws_are_sliced_with_the_same_picture(ctx, stone, monkeypatch):
    """On a software rasteriser a multisampled draw of more than ``flush_interval``
    primitives (instances x triangles) is made in slices, the queue finished in
    between (llvmpipe's memory for a multisampled frame grows with what it was
    given until then).  A small mesh: slices of whole instances, in order
    (indirect commands with a base instance): the very same picture, every mode.
    A big mesh: slices of its triangles, every instance in each: the same
    picture solid and flat; wireframe over its translucent fill up to the order
    of overlapping translucent lines."""
    import sys

    import moderngl
    import trimesh as tm

    from axialdeform.gl.context import _multisampled, flush_interval

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
    from big_mesh import torus

    modes = ("solid", "flat", "wireframe")
    calls, indirect, finishes = [], [], []
    original, original_indirect = moderngl.VertexArray.render, moderngl.VertexArray.render_indirect
    original_finish = moderngl.Context.finish

    def spy(self, mode=None, vertices=-1, first=0, instances=-1):
        if _multisampled(ctx):  # the colour passes only (the shadow map, single-sampled, has slices of its own)
            calls.append((mode, vertices, first, instances))
        return original(self, mode, vertices=vertices, first=first, instances=instances)

    def spy_indirect(self, buffer, mode=None, count=-1, first=0):
        if _multisampled(ctx):
            indirect.append((mode, *np.frombuffer(buffer.read(size=20, offset=20 * first), "<u4").tolist()))
        return original_indirect(self, buffer, mode, count, first)

    pos, faces = torus(2000)
    ring = ad.load_mesh(tm.Trimesh(pos, faces, process=False))
    for mesh, n, size in ((stone, 400, (200, 150)), (ring, 6, (120, 90))):
        params = ad.random_params(mesh, n, seed=6, variation=ad.Variation(bend=0.2))
        monkeypatch.setattr(ctx, "_axialdeform_flush", None, raising=False)
        assert flush_interval(ctx) is None
        whole = ad.render_image(mesh, params, size, modes, ctx=ctx)
        calls.clear(), indirect.clear(), finishes.clear()
        monkeypatch.setattr(moderngl.VertexArray, "render", spy)
        monkeypatch.setattr(moderngl.VertexArray, "render_indirect", spy_indirect)
        monkeypatch.setattr(moderngl.Context, "finish", lambda self: (finishes.append(1), original_finish(self))[1])
        monkeypatch.setattr(ctx, "_axialdeform_flush", 7000)
        sliced = ad.render_image(mesh, params, size, modes, ctx=ctx)
        monkeypatch.undo()
        w = size[0]
        if mesh is stone:  # 112 triangles: slices of 7000 // 112 = 62 instances, lines 7000 // 3 // 168 = 13
            assert np.array_equal(sliced, whole)
            tri = [c for c in indirect if c[0] == moderngl.TRIANGLES]
            assert tri and all(c[2] <= 62 for c in tri) and all(c[2] <= 13 for c in indirect if c[0] == moderngl.LINES)
            assert sorted(c[5] for c in tri[:7]) == list(range(0, 400, 62))  # one pass: every instance once
            assert not [c for c in calls if c[3] == 400]  # no whole draw of every instance
        else:  # 1 996 triangles x 6: slices of 7000 // 6 = 1 166 triangles, lines a third
            assert np.array_equal(sliced[:, :2 * w], whole[:, :2 * w])
            diff = np.abs(sliced[:, 2 * w:].astype(int) - whole[:, 2 * w:].astype(int))
            assert (diff > 40).mean() < 0.002 and diff.mean() < 0.5
            # (the culled frame's draws are indirect: their commands hold index count and first index)
            tri = [(c[1], c[3]) for c in indirect if c[0] == moderngl.TRIANGLES]
            tri += [(v, f) for m, v, f, k in calls if m == moderngl.TRIANGLES and k == n]
            lines = [c[1] for c in indirect if c[0] == moderngl.LINES] + [v for m, v, _, k in calls
                                                                          if m == moderngl.LINES and k == n]
            assert all(v <= 1166 * 3 for v, _ in tri) and all(v <= 388 * 2 for v in lines)
            assert sorted(f // 3 for _, f in tri[:2]) == [0, 1166] and len(lines) >= 2
        assert len(finishes) >= 3
    assert ctx.error == "GL_NO_ERROR"


@pytest.mark.slow
def test_multisampled_frame_memory_does_not_grow_with_triangles(tmp_path):
    """llvmpipe kept ~48 bytes a triangle of a multisampled frame until it was
    finished: 50 instances of a 200 000-triangle mesh (10 M triangles) into a
    64x64 4-sample target grew the process by 150 to 480 MB.  Sliced, the growth
    is bounded by one slice.  Measured in child processes, with the slicing off
    (``AXIALDEFORM_FLUSH_PRIMITIVES=0``: the measurement sees the growth) and on."""
    import os
    import subprocess
    import sys

    script = (
        "import sys, numpy as np\n"
        "def rss(key):\n"
        "    return next(int(l.split()[1]) for l in open('/proc/self/status') if l.startswith(key + ':'))\n"
        "sys.path.insert(0, 'tools')\n"
        "import axialdeform as ad\n"
        "from big_mesh import torus\n"
        "from axialdeform.gl.context import Offscreen, create_context\n"
        "from axialdeform.core.camera import frame_instances\n"
        "pos, faces = torus(200_000)\n"
        "import trimesh\n"
        "mesh = ad.load_mesh(trimesh.Trimesh(pos, faces, process=False))\n"
        "params = ad.random_params(mesh, 50, seed=1)\n"
        "ctx = create_context()\n"
        "r = ad.AxialRenderer(ctx, mesh, params)\n"
        "cam = frame_instances(mesh, params, 1.0)\n"
        "view, proj = cam.view(), cam.projection(1.0)\n"
        "with Offscreen(ctx, (64, 64), samples=4) as out:\n"
        "    out.use()\n"
        "    r.set_params(params[:1])\n"
        "    r.render(view, proj)\n"  # the programs built, one instance drawn
        "    ctx.finish()\n"
        "    r.set_params(params)\n"
        "    open('/proc/self/clear_refs', 'w').write('5')\n"  # the high-water mark starts again here
        "    before = rss('VmRSS')\n"
        "    r.render(view, proj)\n"
        "    ctx.finish()\n"
        "    after = rss('VmHWM')\n"
        "assert ctx.error == 'GL_NO_ERROR'\n"
        "print((after - before) / 1024)\n")
    root = Path(__file__).resolve().parents[2]
    growth = {}
    for flush in ("0", "default"):
        env = {**os.environ, "AXIALDEFORM_FLUSH_PRIMITIVES": flush, "AXIALDEFORM_INDIRECT": "0"}
        if flush == "default":
            env.pop("AXIALDEFORM_FLUSH_PRIMITIVES")
        done = subprocess.run([sys.executable, "-c", script], cwd=root, env=env, capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        growth[flush] = float(done.stdout.split()[-1])
    assert growth["0"] > 150, growth  # unsliced: the driver's memory grows (the measurement can see it)
    assert growth["default"] < 80 and growth["0"] > 3 * growth["default"], growth  # sliced: one slice at a time


@pytest.mark.parametrize("culling", [False, True])
def test_a_height_maps_wireframe_in_blocks_is_the_whole_edge_list(ctx, monkeypatch, culling):
    """GL >= 4.2: a height map's edges are drawn block by block from one small
    index buffer with base vertices -- the same picture as the whole edge
    buffer (every hidden-line style, culled or not), and the blocks' commands
    hold exactly the grid's edges in the same order."""
    from axialdeform.core.mesh import BaseMesh, area_weighted_normals, grid_edges
    from axialdeform.core.surface import surface_from_heights
    from axialdeform.gl import buffers
    from axialdeform.gl.renderer import AxialRenderer

    rng = np.random.default_rng(3)
    surf = surface_from_heights(rng.random((70, 90)), height_scale=8.0, extent=(40, 30))
    mesh = BaseMesh(surf.vertices, area_weighted_normals(surf.vertices, surf.faces), surf.faces, name="map",
                    grid=surf.grid)
    params = ad.random_params(mesh, 3, seed=1, variation=ad.Variation(bend=0.02), spacing=50)
    cam = ad.Camera(eye=(60.0, 45.0, 70.0), target=(0.0, 0.0, 0.0), fovy=60.0)
    view, proj = cam.view(), cam.projection(4 / 3)

    def pictures():
        out = []
        for hidden in ("fill", True, False):
            look = ad.Look(ground=False, shadow=False, hidden_line=hidden)
            with AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(culling=culling)) as r, ad.Offscreen(ctx, (160, 120)) as t:
                t.use((0.9, 0.9, 0.9))
                r.render(view, proj, "wireframe", look=look)
                out.append(t.read())
                blocks = r.mesh_buffers.grid_blocks
        return out, blocks

    blocked, blocks = pictures()
    assert blocks is not None
    pattern = buffers._grid_block_pattern(*surf.grid, blocks[2])
    rebuilt = np.concatenate([pattern[c[2] // 2:(c[2] + c[0]) // 2] + np.uint32(c[3])
                              for c in buffers.MeshBuffers.grid_edge_draws(type("M", (), {"grid_blocks": blocks})(), 1)])
    assert np.array_equal(rebuilt, grid_edges(*surf.grid))
    monkeypatch.setattr(buffers, "GRID_BLOCK_ROWS", None)  # the whole edge buffer, as GL 3.3 draws it
    monkeypatch.setattr(buffers.MeshBuffers, "_block_rows", property(lambda self: None))
    real_init = buffers.MeshBuffers.__init__

    def whole(self, *a, **k):
        real_init(self, *a, **k)
        self.grid_blocks = None
    monkeypatch.setattr(buffers.MeshBuffers, "__init__", whole)
    whole_pictures, none = pictures()
    assert none is None
    for a, b in zip(blocked, whole_pictures):
        assert np.array_equal(a, b)
    assert (np.abs(blocked[2].astype(int) - 230).max(axis=-1) > 40).mean() > 0.05  # lines were drawn

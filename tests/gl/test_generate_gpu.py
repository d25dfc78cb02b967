"""Generated layers on the GPU (glsl/generate.glsl by a compute shader on GL >= 4.3 and by transform feedback,
both run here) equal the numpy reference."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core import ContextError
from axialdeform.core.generate import Generate, generate_tile, generate_tiles
from axialdeform.core.record import SCALE
from axialdeform.gl.generate import TileGenerator, compute_available, generate_tile_gpu

#: both ways of writing the slots: glsl/generate.comp and glsl/generate.vert by transform feedback
WAYS = pytest.mark.parametrize("compute", [True, False], ids=["compute", "transform feedback"])

RECIPES = [Generate(rate=4.0, tile=8.0, min_distance=0.3, seed=7, bend=0.1),
           Generate(rate=2.5, tile=10.0, min_distance=0.1, seed=4_000_000_000, bend=0.2, scale=(0.7, 1.3),
                    twist=0.5, taper=0.3, yaw=(-2.0, 1.5)),
           Generate(rate=4.0, tile=8.0, seed=11, bend=0.1, clump_cells=3, clump_radius=1.5),
           Generate(rate=4.0, tile=8.0, seed=12, bend=0.1, clump_cells=3, clump_radius=1.5, clump_core=0.4,
                    clump_core_radius=0.3),
           Generate(rate=4.0, tile=8.0, seed=5, bend=0.1, scale=(0.3, 2.0), scale_quartiles=(0.5, 0.7, 1.1)),
           Generate(rate=4.0, tile=8.0, seed=6, bend=0.1, scale=(0.3, 2.0), scale_quartiles=(0.5, 0.7, 1.1),
                    scale_octiles=(0.35, 0.6, 0.9, 1.5))]


@pytest.mark.parametrize("recipe", RECIPES, ids=["16 numbers", "19 numbers", "clumps", "clumps with a core", "scale quartiles",
                                                      "scale octiles"])
@WAYS
def test_the_gpu_makes_the_numpy_records(ctx, recipe, compute):
    stone = ad.load_mesh("stone")
    for tile in [(0, 0), (-3, 5), (1000, -7), (-40000, 123456)]:
        cpu, _ = generate_tile(recipe, stone, *tile)
        gpu, kept = generate_tile_gpu(ctx, recipe, stone, *tile, compute=compute)
        assert kept.all()
        assert gpu.shape == cpu.shape
        rel = np.abs(gpu - cpu) / np.maximum(1.0, np.abs(cpu))
        assert rel.max() <= 1e-6, (tile, rel.max())
    # the hash is exact: the positions' jitter (u0, u1) is the same number on both sides
    assert np.array_equal(gpu[:, [10, 12]], cpu[:, [10, 12]])
    if recipe.scale_quartiles is not None:  # the scales through the five knots: a quarter of them in each span
        lo, hi = recipe.scale
        q = np.quantile(cpu[:, SCALE], [0.25, 0.5, 0.75])  # (and the octiles' between them)
        assert np.abs(q - recipe.scale_quartiles).max() < 0.05 * (hi - lo), q
        assert np.array_equal(gpu[:, SCALE], cpu[:, SCALE])


@WAYS
def test_one_program_makes_any_tile_into_a_gpu_buffer(ctx, compute):
    stone = ad.load_mesh("stone")
    gen = TileGenerator(ctx, RECIPES[0], stone, compute=compute)
    buf = gen.buffer()
    try:
        out = []
        for tile in [(2, 2), (0, 0), (2, 2)]:
            gen.run(tile, buf)
            out.append(np.frombuffer(buf.read(), np.float32).reshape(gen.count, 23)[:, :16].copy())
    finally:
        buf.release()
        gen.release()
        gen.release()  # safe twice
    assert np.array_equal(out[0], out[2]) and not np.array_equal(out[0], out[1])
    assert np.array_equal(out[1], generate_tile(RECIPES[0], stone, 0, 0)[0])
    # tiles side by side in one buffer (the layout of a layer's instance buffer): each at its offset
    gen = TileGenerator(ctx, RECIPES[0], stone, compute=compute)
    both = ctx.buffer(reserve=2 * gen.count * 23 * 4)
    try:
        gen.run((5, -5), both, offset=gen.count * 23 * 4)
        gen.run((0, 0), both)
        got = np.frombuffer(both.read(), np.float32).reshape(2 * gen.count, 23)[:, :16]
    finally:
        both.release()
        gen.release()
    assert np.array_equal(got, generate_tiles(RECIPES[0], stone, [(0, 0), (5, -5)]))


def _hills(rows=33, cols=41):
    """A height map's terrain (60 x 44 units, heights 0..6) and a density map with a hole."""
    from axialdeform.core.surface import surface_from_heights

    r, c = np.mgrid[0:rows, 0:cols] / np.array([rows - 1, cols - 1])[:, None, None]
    heights = 0.5 + 0.35 * np.sin(5 * c) * np.cos(4 * r) + 0.1 * r
    density = np.ones((16, 16))
    density[4:10, 6:12] = 0.0
    density[:, :3] = 0.3
    return surface_from_heights(heights, height_scale=6.0, extent=(60.0, 44.0)), density


@pytest.mark.parametrize("flat", [False, True], ids=["height map", "flat, density repeated"])
@WAYS
def test_the_gpu_keeps_and_places_as_numpy_on_the_ground_maps(ctx, flat, compute):
    """Heights on the terrain's triangles, the altitude and slope bands, the density map and the tint."""
    from axialdeform.core.generate import GroundMaps

    stone = ad.load_mesh("stone")
    terrain, density = _hills()
    if flat:
        recipe = Generate(rate=3.0, tile=8.0, min_distance=0.2, seed=9, bend=0.1, tint=0.4, tint_color=(0.9, 0.8, 0.7),
                          tint_hue=0.5, choice=(0.25, 0.9))
        maps = GroundMaps.of(None, density, extent=(-10, -10, 10, 10))
    else:
        recipe = Generate(rate=3.0, tile=8.0, min_distance=0.2, seed=9, bend=0.1, altitude=(1.0, 5.0), slope=(0.0, 35.0),
                          scale=(0.5, 1.0))
        sunk = Generate(rate=3.0, tile=8.0, seed=9, bend=0.1, scale=(0.5, 1.0), anchor="center", lift=(0.1, 0.4))
        cpu, _ = generate_tile(sunk, stone, 1, 1, GroundMaps.of(terrain, None))
        gpu, _ = generate_tile_gpu(ctx, sunk, stone, 1, 1, GroundMaps.of(terrain, None), compute=compute)
        assert (np.abs(gpu - cpu) / np.maximum(1.0, np.abs(cpu))).max() <= 1e-6
        maps = GroundMaps.of(terrain, density)
    kept_all = []
    for tile in [(0, 0), (-4, -3), (3, 2), (-1, 1), (20, 20)]:
        cpu, kept = generate_tile(recipe, stone, *tile, maps)
        gpu, gkept = generate_tile_gpu(ctx, recipe, stone, *tile, maps, compute=compute)
        assert np.array_equal(gkept, kept), tile
        rel = np.abs(gpu - cpu) / np.maximum(1.0, np.abs(cpu))
        assert rel.max() <= 1e-6, (tile, rel.max())
        kept_all.append(kept)
    share = np.concatenate(kept_all[:4]).mean()
    assert 0.2 < share < 0.95, share  # the bands and the density drop some, not all
    if not flat:
        assert not kept_all[4].any()  # beyond the height map nothing stands
        p, k = generate_tile(recipe, stone, 0, 0, maps)
        v = np.asarray(terrain.vertices)
        # standing on the terrain: each instance's lowest point at the height of the terrain mesh's own
        # triangle under it (trimesh's ray test, straight down)
        import trimesh

        ground_mesh = trimesh.Trimesh(v, np.asarray(terrain.faces), process=False)
        xz = p[k][:, [10, 12]].astype(np.float64)
        origins = np.column_stack([xz[:, 0], np.full(len(xz), 100.0), xz[:, 1]])
        hit, ray, _ = ground_mesh.ray.intersects_location(origins, np.tile([0.0, -1.0, 0.0], (len(xz), 1)),
                                                          multiple_hits=False)
        ground = np.full(len(xz), np.nan)
        ground[ray] = hit[:, 1]
        s = p[k][:, 16]
        assert np.allclose(p[k][:, 11] + stone.positions[:, 1].min() * s, ground, atol=1e-4)
        assert ((ground >= 1.0 - 1e-3) & (ground <= 5.0 + 1e-3)).all()
    else:
        t = generate_tile(recipe, stone, 0, 0, maps)[0]
        assert t.shape[1] == 22 and (t[:, 19:22] <= np.array([0.9, 0.8, 0.7]) + 1e-7).all()
        assert (t[:, 19:22] >= 0.6 * np.array([0.9, 0.8, 0.7]) - 1e-7).all()


@WAYS
def test_the_gpu_makes_a_trees_child_axes_as_numpy(ctx, compute):
    """A mesh of ten axes: each level its bend, every child axis's offsets projected so its joint stays."""
    from axialdeform.core.axes import bernstein4

    tree = ad.load_mesh("tree", axes=str(Path(__file__).resolve().parents[2] / "examples" / "forest" / "tree-axes.toml"))
    recipe = Generate(rate=0.2, tile=16.0, min_distance=0.5, seed=21, bend=(0.04, 0.25), scale=(0.8, 1.1))
    for tile in [(0, 0), (-2, 7)]:
        cpu, kept = generate_tile(recipe, tree, *tile)
        gpu, gkept = generate_tile_gpu(ctx, recipe, tree, *tile, compute=compute)
        assert cpu.shape == gpu.shape == (kept.size, 19 + 90) and np.array_equal(kept, gkept)
        rel = np.abs(gpu - cpu) / np.maximum(1.0, np.abs(cpu))
        assert rel.max() <= 1e-6, (tile, rel.max())
    # each child axis bends within its level's amplitude, and not at its joint (value and slope zero there)
    from axialdeform.core.record import split_record

    _std, children = split_record(cpu, tree.axis_count)
    b, db = bernstein4(np.asarray(tree.tree.anchors[1:]))
    at_joint = np.einsum("jq,njqc->njc", b, children.reshape(len(cpu), 9, 5, 2))
    slope = np.einsum("jq,njqc->njc", db, children.reshape(len(cpu), 9, 5, 2))
    assert np.abs(at_joint).max() < 1e-5 and np.abs(slope).max() < 1e-4
    assert np.abs(children).max() > 0.01  # they do bend


@WAYS
def test_instances_lean_toward_the_ground_as_scatter_turns_them(ctx, compute):
    """align_to_normal on a height map: the GPU's turn (its own sine, cosine and arctangent) equals numpy's;
    both are scatter's R = Rt(up x n, align angle) Ry(ry), read back from the Euler angles; the anchor rests
    on the ground after the turn."""
    from axialdeform.core.generate import GroundMaps
    from axialdeform.core.transforms import rotation_matrices

    stone = ad.load_mesh("stone")
    terrain, _ = _hills()
    maps = GroundMaps.of(terrain, None)
    recipe = Generate(rate=2.0, tile=8.0, seed=12, bend=0.1, scale=(0.5, 1.0), align_to_normal=0.7, anchor="bottom")
    for tile in [(0, 0), (-3, -2), (2, 1)]:
        cpu, kept = generate_tile(recipe, stone, *tile, maps)
        gpu, gkept = generate_tile_gpu(ctx, recipe, stone, *tile, maps, compute=compute)
        assert np.array_equal(kept, gkept)
        rel = np.abs(gpu - cpu) / np.maximum(1.0, np.abs(cpu))
        assert rel.max() <= 1e-6, (tile, rel.max())
    p = cpu[kept]
    # the reference in float64: scatter's construction from the terrain's normal under each instance
    flat = generate_tile(Generate(rate=2.0, tile=8.0, seed=12, bend=0.1, scale=(0.5, 1.0)), stone, 2, 1, maps)[0][kept]
    r = rotation_matrices(p[:, 13:16].astype(np.float64))
    up = r[:, :, 1]  # where the mesh's up went
    assert np.allclose(rotation_matrices(flat[:, 13:16])[:, 1, 1], 1.0)  # without align: upright
    tilt = np.degrees(np.arccos(np.clip(up[:, 1], -1, 1)))
    assert tilt.max() > 3.0  # on the hills' slopes they lean
    # scatter's construction in float64 from the normal of the terrain triangle under each instance
    import trimesh

    from axialdeform.core.transforms import matrices_from_rotation_vectors

    v, f = np.asarray(terrain.vertices), np.asarray(terrain.faces)
    ground = trimesh.Trimesh(v, f, process=False)
    origins = np.column_stack([p[:, 10], np.full(len(p), 100.0), p[:, 12]]).astype(np.float64)
    _hit, ray, tri = ground.ray.intersects_location(origins, np.tile([0.0, -1.0, 0.0], (len(p), 1)), multiple_hits=False)
    n = np.zeros((len(p), 3))
    n[ray] = ground.face_normals[tri]
    n *= np.sign(n[:, 1:2])
    cross = np.cross(np.array([0.0, 1.0, 0.0]), n)
    sin = np.linalg.norm(cross, axis=1)
    axis = np.where(sin[:, None] > 1e-12, cross / np.maximum(sin, 1e-12)[:, None], 0.0)
    tilt = matrices_from_rotation_vectors(axis * (np.arctan2(sin, n[:, 1]) * 0.7)[:, None])
    want = tilt @ rotation_matrices(np.column_stack([np.zeros(len(p)), flat[:, 14], np.zeros(len(p))]))
    assert np.abs(r - want).max() < 1e-4, np.abs(r - want).max()


def _tree():
    return ad.load_mesh("tree", axes=str(Path(__file__).resolve().parents[2] / "examples" / "forest" / "tree-axes.toml"))


@pytest.mark.parametrize("kind", ["16 numbers", "tinted on the ground maps", "tree of ten axes"])
@WAYS
def test_tiles_are_made_straight_into_the_renderers_buffers(ctx, kind, compute):
    """GeneratedTiles: the kept instances compacted on the GPU into the renderer's own instance buffer, tint
    buffer and child-axes texture equal generate_tiles for the same tiles, in its order; the bounds found
    from the recipe alone hold every instance; a second make replaces the first."""
    from axialdeform.core.bounds import instance_bounds
    from axialdeform.core.generate import GroundMaps, tile_spheres
    from axialdeform.core.record import split_record
    from axialdeform.gl.generated import GeneratedTiles
    from axialdeform.gl.renderer import AxialRenderer

    mesh, maps = ad.load_mesh("stone"), None
    if kind == "16 numbers":
        recipe = RECIPES[0]
    elif kind == "tinted on the ground maps":
        terrain, density = _hills()
        maps = GroundMaps.of(terrain, density)
        recipe = Generate(rate=3.0, tile=8.0, min_distance=0.2, seed=9, bend=0.1, altitude=(1.0, 5.0), scale=(0.5, 1.0),
                          tint=0.4, lift=(0.0, 0.3), align_to_normal=0.5)
    else:
        mesh, recipe = _tree(), Generate(rate=0.2, tile=16.0, min_distance=0.5, seed=21, bend=(0.04, 0.25),
                                         scale=(0.8, 1.1))
    width = recipe.width + 10 * (mesh.axis_count - 1)
    renderer = AxialRenderer(ctx, mesh, np.zeros((0, width), np.float32))
    gen = GeneratedTiles(renderer, recipe, mesh, maps, compute=compute)
    assert (gen.generator.compute is not None) == compute
    try:
        for tiles in ([(0, 0), (1, 0), (-1, 2), (3, -2)], [(2, 2), (-3, -1)]):
            cpu = generate_tiles(recipe, mesh, tiles, maps)
            assert gen.make(tiles) == renderer.count == len(cpu) > 0
            std, children = split_record(cpu, mesh.axis_count) if mesh.axis_count > 1 else (cpu, None)
            assert np.array_equal(renderer.instances.read(), std[:, :renderer.instances.columns])
            if recipe.tint is not None:
                tint = np.frombuffer(renderer._tint[3].read(size=12 * len(cpu)), np.float32).reshape(-1, 3)
                assert np.array_equal(tint, cpu[:, 19:22])
            if children is not None:
                got = renderer._axes.read()
                assert np.abs(got - children).max() <= 1e-6 and np.abs(children).max() > 0.01
                assert renderer.child_reach >= renderer._axes.reach(children)  # culling's bound holds them
            # the tiles' spheres (from the recipe alone) hold every instance's bounding sphere
            centers, radii = instance_bounds(mesh, cpu)
            spheres = tile_spheres(recipe, mesh, tiles, maps)
            own = np.repeat(np.arange(len(tiles)), [len(generate_tiles(recipe, mesh, [t], maps)) for t in tiles])
            assert (np.linalg.norm(centers - spheres[own, :3], axis=1) + radii <= spheres[own, 3] + 1e-9).all()
        assert gen.make([]) == renderer.count == 0
    finally:
        gen.release()
        gen.release()  # safe twice
        renderer.release()


def test_a_quantized_renderer_cannot_take_gpu_made_instances(ctx):
    from axialdeform.core.errors import AxialDeformError
    from axialdeform.gl.renderer import AxialRenderer

    stone = ad.load_mesh("stone")
    renderer = AxialRenderer(ctx, stone, np.zeros((4, 16), np.float32), options=ad.RenderOptions(quantized=True))
    try:
        with pytest.raises(AxialDeformError, match="quantized=False"):
            renderer.gpu_targets(10)
    finally:
        renderer.release()


def test_view_draws_the_gpus_records_and_makes_none_on_the_cpu(monkeypatch):
    """The viewer's generated layers (stones, grass, trees of ten axes) are made on the GPU into the
    renderers: with numpy's generator made to fail, a walk still fills every layer, and what each renderer
    holds equals the numpy reference for the tiles within reach.  N (another seed) and UP (more bend) make
    them again on the GPU, as numpy makes them with seed + 7919 and offsets x 1.25."""
    import axialdeform.core.generate as core_generate
    from axialdeform.core.record import split_record
    from axialdeform.viewer import Viewer, ViewerSettings

    scene = ad.Scene.load(Path(__file__).resolve().parents[2] / "examples" / "generated" / "walk.toml")
    v = Viewer.create(scene, headless=True, size=(96, 72), settings=ViewerSettings(walk=(30.0, 18.0)))

    def refuse(*_a, **_k):
        raise AssertionError("a tile was made on the CPU")

    try:
        monkeypatch.setattr(core_generate, "generate_tile", refuse)
        v.step(3)
        v.on_key_event("N", v.wnd.keys.ACTION_PRESS, None)
        v.on_key_event("UP", v.wnd.keys.ACTION_PRESS, None)
        v.step(1)
        monkeypatch.undo()
        t = v.orbit.target
        jobs = [(v.generate, v.mesh, v.renderer)] + [(layer.generate, layer.mesh, r) for layer, r, _ in v.layers]
        assert len(jobs) == 3 and v.layers[-1][0].mesh.axis_count == 10
        from dataclasses import replace

        for rec, mesh, renderer in jobs:
            again = replace(rec.generate, seed=rec.generate.seed + 7919)
            cpu = generate_tiles(again, mesh, core_generate.tiles_around(again, float(t[0]), float(t[2]), rec.reach),
                                 rec.maps)
            assert renderer.count == len(cpu) > 0
            cpu[:, :10 * mesh.axis_count] *= np.float32(1.25)
            std, children = split_record(cpu, mesh.axis_count) if mesh.axis_count > 1 else (cpu, None)
            got = renderer.instances.read()
            assert (np.abs(got - std[:, :got.shape[1]]) / np.maximum(1.0, np.abs(std[:, :got.shape[1]]))).max() <= 1e-6
            if children is not None:
                assert np.abs(renderer._axes.read() - children).max() <= 1e-6
    finally:
        v.release()
        v.wnd.destroy()


def test_the_compute_path_is_the_default_where_the_context_has_one(ctx):
    """GL >= 4.3 (llvmpipe's 4.5 here): the slots by glsl/generate.comp unless told otherwise; compute=True
    on a context without compute shaders is a ContextError naming what it needs."""
    stone = ad.load_mesh("stone")
    assert compute_available(ctx)
    gen = TileGenerator(ctx, RECIPES[0], stone)
    try:
        assert gen.compute is not None
    finally:
        gen.release()

    class GL33:
        version_code = 330

        def __getattr__(self, name):
            return getattr(ctx, name)

    with pytest.raises(ContextError, match=r"compute=True needs OpenGL >= 4.3.*has 330"):
        TileGenerator(GL33(), RECIPES[0], stone, compute=True)


def test_a_generated_instance_keeps_its_sway_and_shade_when_its_tiles_are_made_again(ctx):
    """The view makes the tiles within reach again, in another order, as the camera walks: an instance's index
    changes, so a generated layer's wind phase and shade hash where it stands (AXIAL_POSITION_IDS,
    core.wind.position_ids): its bent vertices in the wind are the same whichever tile set it was made in,
    and equal the CPU reference with those ids; phases by index would differ (the check can fail)."""
    from axialdeform.core.wind import apply_wind
    from axialdeform.gl.generated import GeneratedTiles
    from axialdeform.gl.renderer import AxialRenderer

    stone = ad.load_mesh("stone")
    recipe = Generate(rate=1.0, tile=4.0, min_distance=0.3, seed=12, bend=0.1)
    wind = ad.Wind(direction=(1.0, 0.0, 0.3), strength=0.3, gustiness=0.7)
    renderer = AxialRenderer(ctx, stone, np.zeros((0, 16), np.float32), options=ad.RenderOptions(wind=wind, position_ids=True))
    gen = GeneratedTiles(renderer, recipe, stone)
    try:
        bent = []
        for tiles in ([(0, 0), (1, 0), (5, 5)], [(7, -3), (1, 0), (2, 2), (0, 0)]):
            gen.make(tiles)
            positions, _ = renderer.capture(time=1.3)
            records = generate_tiles(recipe, stone, tiles)
            cpu, _ = ad.deform(stone, apply_wind(wind, stone.axis, records, 1.3, ids="position"))
            assert np.abs(positions - cpu).max() <= 1e-5 * stone.axis.length
            by_index, _ = ad.deform(stone, apply_wind(wind, stone.axis, records, 1.3))
            assert np.abs(by_index - cpu).max() > 0.05 * stone.axis.length
            bent.append({tuple(r[10:13]): p for r, p in zip(records, positions)})
        shared = bent[0].keys() & bent[1].keys()  # tiles (0, 0) and (1, 0): made twice, other indices
        assert len(shared) == 2 * recipe_cells(recipe)
        assert all(np.array_equal(bent[0][k], bent[1][k]) for k in shared)
    finally:
        gen.release()
        renderer.release()
    # the shade too: the same tiles made in two orders draw the same picture; by index they would not
    from axialdeform.core.camera import Camera
    from axialdeform.gl.context import release_framebuffer

    camera = Camera(eye=(4.0, 6.0, 9.0), target=(4.0, 0.0, 2.0), fovy=40.0, near=0.1, far=100.0)
    pictures = {}
    for ids in (True, False):
        renderer = AxialRenderer(ctx, stone, np.zeros((0, 16), np.float32), options=ad.RenderOptions(position_ids=ids))
        gen = GeneratedTiles(renderer, recipe, stone)
        target = ctx.simple_framebuffer((160, 120))
        try:
            for order in ([(0, 0), (1, 0)], [(1, 0), (0, 0)]):
                target.use()
                gen.make(order)
                ctx.clear(0.9, 0.9, 0.9, 1.0, depth=1.0)
                renderer.render(camera.view(), camera.projection(160 / 120), look=ad.Look(fast=True))
                pictures[ids, order[0]] = np.frombuffer(target.read(), np.uint8).astype(int)
        finally:
            gen.release()
            renderer.release()
            release_framebuffer(ctx, target)
    assert np.array_equal(pictures[True, (0, 0)], pictures[True, (1, 0)])
    assert np.abs(pictures[False, (0, 0)] - pictures[False, (1, 0)]).max() > 10


def recipe_cells(recipe) -> int:
    from axialdeform.core.generate import tile_size

    return tile_size(recipe)[0] ** 2


def test_view_and_the_page_make_no_generated_extent_on_the_cpu(ctx, monkeypatch):
    """One computation a layer: loading a scene makes no generated instance (a layer's ``params`` are made
    when first asked for), the viewer makes every tile on the GPU and frames the recipe's extent, and the
    page writer makes no extent; render draws the extent, made by numpy then, framed the same way (the
    frame comes from the recipe, so it is the same before and after the instances exist)."""
    import axialdeform.core.generate as core_generate
    import axialdeform.core.scene as core_scene
    from axialdeform.gl.scene import scene_camera
    from axialdeform.viewer import Viewer
    from axialdeform.web import build_scene_file

    def refuse(*_a, **_k):
        raise AssertionError("a generated extent was made on the CPU")

    path = Path(__file__).resolve().parents[2] / "examples" / "generated" / "walk.toml"
    with monkeypatch.context() as m:
        m.setattr(core_scene, "generate_extent", refuse)
        scene = ad.Scene.load(path)
        assert [layer.made for layer in scene.layers] == [False, False, False]
        before = scene_camera(scene, 4 / 3)
        page = build_scene_file(scene, allow_outside=True)
        assert page.config["instances"] > 1000  # the tiles around the camera at the start (none beyond)
        m.setattr(core_generate, "generate_tile", refuse)  # and the viewer no tile either
        v = Viewer.create(scene, headless=True, size=(96, 72))
        try:
            v.step(1)
            held = v.renderer.count + sum(r.count for _, r, _ in v.layers)
        finally:
            v.release()
            v.wnd.destroy()
        assert held > 1000 and not any(layer.made for layer in scene.layers)
    ctx.__enter__()
    image = ad.render_image(scene, size=(96, 72), ctx=ctx)
    assert all(layer.made for layer in scene.layers) and len(scene.layers[1].params) > 1000
    after = scene_camera(scene, 4 / 3)
    assert np.allclose(before.eye, after.eye) and np.allclose(before.target, after.target)
    assert (np.abs(image.astype(int) - image[0, 0]).max(axis=2) > 30).mean() > 0.1  # the layers are drawn

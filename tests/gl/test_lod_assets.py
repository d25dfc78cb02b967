"""real assets: levels of detail of textured, coloured, multi-part
meshes (each part simplified on its own, UVs / colours / normals / tangents
carried to the simplified vertices), drawn one instanced draw per level and part."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh

import axialdeform as ad
from axialdeform.core.lod import MIN_LOD_TRIANGLES, build_lod_levels
from axialdeform.core.material import Material, Part, compute_tangents
from axialdeform.core.mesh import area_weighted_normals

from conftest import data_mesh
from helpers.gl_scenes import draw, look


def leaf_uv(positions):
    """The bundled leaf card's texture map: u = x / 0.72 + 0.5, v = y (affine in x, y)."""
    return np.stack([positions[:, 0] / 0.72 + 0.5, positions[:, 1]], axis=1)


def leaf_color(positions):
    """Vertex colours of the test meshes: affine in the position too."""
    p = np.asarray(positions, dtype=np.float64)
    return np.stack([0.5 + 0.5 * p[:, 0], 0.3 + 0.5 * p[:, 1], 1.0 - 0.5 * p[:, 1], np.ones(len(p))], axis=1)


def fine_leafcard(subdivisions: int = 2):
    """The bundled textured leaf card (alpha cut-out, 24 triangles: too few to
    simplify) subdivided (UVs carried): 384 triangles, one part, its material."""
    card = ad.load_mesh("leafcard")
    v, f, uv = card.positions.astype(np.float64), card.faces.astype(np.int64), card.uvs
    for _ in range(subdivisions):
        v, f, attr = trimesh.remesh.subdivide(v, f, vertex_attributes={"uv": uv})
        uv = attr["uv"]
    nrm = area_weighted_normals(v, f)
    return ad.BaseMesh(v, nrm, f, name="leafcard-fine", uvs=uv, colors=leaf_color(v),
                       tangents=compute_tangents(v, nrm, uv, f),
                       parts=(Part("leaf", 0, len(f), card.parts[0].material),))


def two_part_mesh():
    """A textured cut-out leaf card (part "leaf") and an opaque stone at its
    foot (part "stone", base colour only): ONE base mesh, two parts."""
    leaf = fine_leafcard()
    stone = ad.load_mesh("stone")
    sp = stone.positions.astype(np.float64) * 0.25 + (0.0, 0.05, 0.12)
    positions = np.vstack([leaf.positions, sp])
    normals = np.vstack([leaf.normals, stone.normals])
    faces = np.vstack([leaf.faces.astype(np.int64), stone.faces.astype(np.int64) + leaf.vertex_count])
    uvs = np.vstack([leaf.uvs, leaf_uv(sp)])
    tangents = np.vstack([leaf.tangents, compute_tangents(sp, stone.normals, leaf_uv(sp), stone.faces)])
    rock = Material(name="rock", base_color=(0.5, 0.45, 0.4, 1.0))
    parts = (Part("leaf", 0, len(leaf.faces), leaf.parts[0].material),
             Part("stone", len(leaf.faces), len(stone.faces), rock))
    return ad.BaseMesh(positions, normals, faces, name="leaf+stone", uvs=uvs, colors=leaf_color(positions),
                       tangents=tangents, parts=parts)


# ------------------------------------------------------------------ levels (numpy)


@pytest.mark.parametrize("make", [fine_leafcard, two_part_mesh])
def test_levels_keep_parts_materials_and_carry_every_attribute(make):
    mesh = make()
    levels = build_lod_levels(mesh)
    assert len(levels) >= 3
    assert levels[0].uvs is mesh.uvs and levels[0].parts == mesh.parts
    faces = [len(level.faces) for level in levels]
    assert faces == sorted(faces, reverse=True) and faces[-1] < faces[0] / 3
    for k, level in enumerate(levels):
        n = level.vertex_count
        assert level.uvs.shape == (n, 2) and level.colors.shape == (n, 4) and level.tangents.shape == (n, 4), k
        assert level.faces.max() < n and len(np.unique(level.faces)) == n  # no unused vertex
        assert [p.name for p in level.parts] == [p.name for p in mesh.parts]
        assert all(a.material is b.material for a, b in zip(level.parts, mesh.parts))
        assert sum(p.count for p in level.parts) == len(level.faces)
        # the texture map and the colours are affine in the position: carried
        # by closest-point interpolation they stay on it up to the distance
        # the vertex left the surface (the curved stone), and exactly on the
        # (almost flat) card; the values of the collapsed vertices, averaged
        # or the survivor's, would not (the quadric moves the vertex along
        # the surface by up to an edge length: 0.1 to 0.3 here)
        tol = 1e-5 if k == 0 else (2e-3 if len(mesh.parts) == 1 else 0.5 * level.error / mesh.axis.length)
        assert np.abs(level.uvs - leaf_uv(level.positions)).max() <= tol, (k, level.error)
        assert np.abs(level.colors - leaf_color(level.positions)).max() <= tol, k
        assert np.allclose(np.linalg.norm(level.normals, axis=1), 1.0, atol=1e-5)
        t, nrm = level.tangents, level.normals
        assert np.allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-5)
        assert np.abs(np.einsum("ij,ij->i", t[:, :3], nrm)).max() < 1e-5 and set(np.unique(t[:, 3])) <= {-1.0, 1.0}
        # each part's triangles use only that part's vertices
        for part in level.parts:
            used = np.unique(level.faces[part.start:part.start + part.count])
            others = np.unique(np.delete(level.faces, np.s_[part.start:part.start + part.count], axis=0))
            assert not np.intersect1d(used, others).size, (k, part.name)
    errors = [level.error for level in levels]
    assert errors == sorted(errors) and errors[1] > 0


def test_parts_too_small_to_simplify_keep_their_triangles():
    """simple_pole.glb: 11 parts; those under MIN_LOD_TRIANGLES are carried
    unchanged into every level, the others shrink."""
    mesh = ad.load_mesh(data_mesh("gltf/simple_pole.glb"))
    levels = build_lod_levels(mesh)
    assert len(levels) >= 2
    for level in levels[1:]:
        for base, part in zip(mesh.parts, level.parts):
            if base.count < MIN_LOD_TRIANGLES:
                assert part.count == base.count
                a = mesh.positions[mesh.faces[base.start:base.start + base.count]]
                b = level.positions[level.faces[part.start:part.start + part.count]]
                assert np.array_equal(a, b), part.name
            else:
                assert part.count < base.count, part.name


def test_a_mesh_without_a_large_enough_part_keeps_one_level():
    for mesh in (ad.load_mesh("leafcard"), ad.load_mesh(data_mesh("assets/AlphaBlendModeTest.glb"))):
        with pytest.warns(UserWarning, match="too few to simplify"):
            assert len(build_lod_levels(mesh)) == 1


# ------------------------------------------------------------------ GPU


def meadow(mesh, n=1500, seed=4):
    """``n`` instances scattered on a disc (y up) of radius about 30 L."""
    return ad.random_params(mesh, n, seed=seed, variation=ad.Variation(bend=0.15), placement="disc", spacing=1.4 * mesh.axis.length)


MEADOW_VIEW = look((1.0, 1.7, 0.5), (25.0, 0.2, 12.0))


@pytest.mark.slow
@pytest.mark.parametrize("make", [fine_leafcard, two_part_mesh])
def test_lod_draws_textured_multi_part_meshes_close_to_the_full_picture(ctx, make):
    mesh = make()
    params = meadow(mesh)
    view, proj = MEADOW_VIEW
    with ad.AxialRenderer(ctx, mesh, params) as full, ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(lod=True)) as lod:
        assert len(lod.lod_levels) >= 3
        a = draw(ctx, full, view, proj, size=(320, 240)).astype(int)
        b = draw(ctx, lod, view, proj, size=(320, 240)).astype(int)
        levels = lod.stats["levels"]
        assert levels[0] > 0 and sum(levels[1:]) > 0.3 * sum(levels), levels
        assert sum(levels) == full.stats["visible"] and lod.stats["vertices"] < 0.8 * full.stats["vertices"]
        # the texture is drawn at every level: leaf green, not the base colour
        green = (a[..., 1] > a[..., 0] + 20) & (a[..., 1] > a[..., 2] + 20)
        green_lod = (b[..., 1] > b[..., 0] + 20) & (b[..., 1] > b[..., 2] + 20)
        assert green.sum() > 2000 and abs(int(green_lod.sum()) - int(green.sum())) < 0.02 * green.sum()
        # mean pixel error (fraction of 255), measured 4.7e-5 (card) and
        # 2.2e-4 (card + stone): far below the 1 %
        error = np.abs(a - b).mean() / 255
        assert 0 < error < 1e-3, error
        # wireframe draws every level too (and lines do differ between levels)
        wa = draw(ctx, full, view, proj, mode="wireframe", size=(160, 120))
        wb = draw(ctx, lod, view, proj, mode="wireframe", size=(160, 120))
        assert sum(lod.stats["levels"][1:]) > 0 and not np.array_equal(wa, wb)
        assert np.abs(wa.astype(int) - wb).mean() / 255 < 0.05
    if len(mesh.parts) > 1:
        with ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(lod=True, parts="stone")) as one:
            for mode in ("solid", "wireframe"):
                img = draw(ctx, one, view, proj, mode=mode, size=(160, 120)).astype(int)
                assert sum(one.stats["levels"][1:]) > 0
                assert ((img[..., 1] > img[..., 0] + 20) & (img[..., 1] > img[..., 2] + 20)).sum() == 0  # no leaf
                assert (np.abs(img - np.round(np.array((0.93, 0.94, 0.96)) * 255)).sum(axis=2) > 30).sum() > 50
    assert ctx.error == "GL_NO_ERROR"


@pytest.mark.parametrize("make", [fine_leafcard, two_part_mesh])
def test_gpu_capture_of_every_level_equals_the_cpu_reference(ctx, make):
    mesh = make()
    params = ad.random_params(mesh, 12, seed=7, variation=ad.Variation(bend=0.25))
    tol = 1e-5 * mesh.axis.length
    with ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(lod=True)) as r:
        assert len(r.lod_levels) >= 3
        for k, level in enumerate(r.lod_levels):
            pos, nrm = r.capture(level=k)
            assert pos.shape == (12, level.vertex_count, 3)
            cpu_pos, cpu_nrm = ad.deform(mesh.axis, level.positions, level.normals, params)  # the BASE axis
            assert np.abs(pos - cpu_pos).max() <= tol, k
            assert np.abs(nrm - cpu_nrm).max() <= 1e-4, k
        with pytest.raises(ad.core.ParamError, match="capture: level: expected 0.."):
            r.capture(level=len(r.lod_levels))
    assert ctx.error == "GL_NO_ERROR"


def test_lod_of_a_mesh_too_small_draws_one_level(ctx):
    mesh = ad.load_mesh("leafcard")
    params = meadow(mesh, 60)
    view, proj = MEADOW_VIEW
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(lod=True)) as lod, ad.AxialRenderer(ctx, mesh, params) as full:
            assert len(lod.lod_levels) == 1
            assert np.array_equal(draw(ctx, lod, view, proj), draw(ctx, full, view, proj))
    assert any("too few to simplify" in str(w.message) for w in caught)
    assert ctx.error == "GL_NO_ERROR"


@pytest.mark.slow
def test_scene_and_viewer_draw_lod_of_a_two_part_textured_layer(ctx):
    from pathlib import Path

    from axialdeform.core.scene import Layer, Scene
    from axialdeform.gl.scene import SceneRenderer
    from axialdeform.viewer import Viewer

    mesh = two_part_mesh()
    params = meadow(mesh)
    scene = Scene(path=Path("meadow.toml"), layers=[Layer("leaves", mesh, params)],
                  camera={"eye": [1.0, 1.7, 0.5], "target": [25.0, 0.2, 12.0], "fov": 60.0})
    full = ad.render_image(scene, size=(160, 120), ctx=ctx, look=ad.Look(samples=0)).astype(int)
    lod = ad.render_image(scene, size=(160, 120), ctx=ctx, look=ad.Look(samples=0), options=ad.RenderOptions(lod=True)).astype(int)
    # mean pixel error measured 1.2e-3 (160 x 120, no multisampling: aliased edges)
    assert not np.array_equal(full, lod) and np.abs(full - lod).mean() / 255 < 5e-3
    with SceneRenderer(ctx, scene, lod=True) as sr:
        r = sr.layer("leaves")
        assert r.lod and len(r.lod_levels) >= 3 and [p.name for p in r.lod_levels[-1].parts] == ["leaf", "stone"]
    v = Viewer.create(mesh, params, headless=True, size=(160, 120), options=ad.RenderOptions(lod=True))
    try:
        v.orbit.zoom(0.3)
        v.step(1)
        stats = v.renderer.stats
        assert v.renderer.lod and stats["lod"] and sum(stats["levels"]) == stats["visible"] > 0
    finally:
        v.release()
        v.wnd.destroy()
    ctx.__enter__()
    assert ctx.error == "GL_NO_ERROR"


@pytest.mark.slow
def test_cli_render_lod_of_a_multi_part_file(tmp_path, capsys):
    from PIL import Image

    from axialdeform.cli import main

    pole = str(data_mesh("gltf/simple_pole.glb"))
    params = tmp_path / "p.adp"
    assert main(["random", pole, "-n", "300", "--placement", "disc", "-o", str(params)]) == 0
    capsys.readouterr()
    images = {}
    for name, extra in {"full": [], "lod": ["--lod-error", "3"], "part": ["--lod", "--part", "2"]}.items():
        out_png = tmp_path / f"{name}.png"
        assert main(["render", pole, str(params), "-o", str(out_png), "--size", "160x120", "--stats", *extra]) == 0
        out = capsys.readouterr().out
        assert ("LOD levels" in out) == (name != "full"), out
        images[name] = np.asarray(Image.open(out_png)).astype(int)
    assert not np.array_equal(images["full"], images["lod"])
    assert np.abs(images["full"] - images["lod"]).mean() / 255 < 0.01
    assert not np.array_equal(images["lod"], images["part"])  # one part only


@pytest.mark.slow
@pytest.mark.parametrize("indirect", [False, None])
def test_one_instanced_draw_per_level_and_part(ctx, monkeypatch, indirect):
    """GL 3.3 path (``indirect=False``): one ``render`` per part of every level
    that has instances, with that level's count; the default path (indirect
    draws where the context has GL >= 4.3): one ``render_indirect`` per part
    of every level (the counts stay on the GPU: a level that kept none is
    still issued), whose commands hold the kept count, the part's index
    count and its first index."""
    import moderngl

    mesh = two_part_mesh()
    params = meadow(mesh)
    calls, indirect_calls = [], []
    original, original_indirect = moderngl.VertexArray.render, moderngl.VertexArray.render_indirect

    def spy(self, *args, **kwargs):
        calls.append((kwargs.get("instances"), kwargs.get("vertices"), kwargs.get("first", 0)))
        return original(self, *args, **kwargs)

    def spy_indirect(self, buffer, mode=None, count=-1, first=0):
        result = original_indirect(self, buffer, mode, count, first)
        command = np.frombuffer(buffer.read(size=20, offset=20 * first), "<u4")  # count, instances, first index, ...
        indirect_calls.append((int(command[1]), int(command[0]), int(command[2])))
        return result

    with ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(lod=True, indirect=indirect)) as r:
        # whole draws (a multisampled frame on llvmpipe is otherwise drawn in slices: tests/gl/test_render.py)
        monkeypatch.setattr(ctx, "_axialdeform_flush", None, raising=False)
        monkeypatch.setattr(moderngl.VertexArray, "render", spy)
        monkeypatch.setattr(moderngl.VertexArray, "render_indirect", spy_indirect)
        draw(ctx, r, *MEADOW_VIEW, size=(160, 120))
        monkeypatch.undo()
        stats = r.stats
        assert len([k for k in stats["levels"] if k]) >= 2
        expected = [(kept, part.count * 3, part.start * 3)
                    for kept, level in zip(stats["levels"], r.lod_levels) if kept for part in level.parts]
        if stats.get("indirect"):
            assert calls == [] and len(indirect_calls) == len(r.lod_levels) * len(mesh.parts)
            assert sorted(c for c in indirect_calls if c[0]) == sorted(expected)
        else:
            assert indirect is None or indirect_calls == []
            assert sorted(calls) == sorted(expected)
    assert ctx.error == "GL_NO_ERROR"


FACES = [((1, 0, 0), (0, 1, 0), (0, 0, 1)), ((-1, 0, 0), (0, 0, 1), (0, 1, 0)), ((0, 1, 0), (0, 0, 1), (1, 0, 0)),
         ((0, -1, 0), (1, 0, 0), (0, 0, 1)), ((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 0, -1), (0, 1, 0), (1, 0, 0))]


def seamed_box(n: int = 7):
    """A unit cube, each side an n x n grid with its OWN vertices and UV chart
    (side k maps to u in [k/6 + 0.01, (k+1)/6 - 0.01]): every cube edge is a UV seam."""
    s, t = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    s, t = s.ravel(), t.ravel()
    q = np.arange(n * (n + 1)).reshape(n, n + 1)[:, :n].ravel()  # lower-left corner of each quad
    quad = np.stack([q, q + n + 1, q + n + 2, q + 1], axis=1)
    positions, uvs, faces = [], [], []
    for k, (normal, a, b) in enumerate(FACES):
        normal, a, b = map(np.asarray, (normal, a, b))
        p = 0.5 * normal + (s[:, None] - 0.5) * a + (t[:, None] - 0.5) * b
        tri = np.vstack([quad[:, [0, 1, 2]], quad[:, [0, 2, 3]]])
        if np.dot(np.cross(a, b), normal) < 0:  # outward winding
            tri = tri[:, ::-1]
        faces.append(tri + len(positions) * (n + 1) ** 2)
        positions.append(p)
        uvs.append(np.stack([k / 6 + 0.01 + s * (1 / 6 - 0.02), t], axis=1))
    positions, faces = np.vstack(positions), np.vstack(faces)
    return ad.BaseMesh(positions, area_weighted_normals(positions, faces), faces, name="seamed-box", uvs=np.vstack(uvs))


def test_no_uv_is_mixed_across_a_seam():
    """Each simplified vertex takes its UV from one side of a seam: it lies on
    one side's chart (u in that side's band) and equals that side's map at the
    vertex's position (projected onto that side), never a blend of two charts."""
    mesh = seamed_box()
    levels = build_lod_levels(mesh)
    assert len(levels) >= 3
    for k, level in enumerate(levels):
        side = np.floor(level.uvs[:, 0] * 6).astype(int)
        assert ((side >= 0) & (side < 6)).all()
        lo = side / 6 + 0.01 - 1e-4
        assert ((level.uvs[:, 0] >= lo) & (level.uvs[:, 0] <= lo + 1 / 6 - 0.02 + 2e-4)).all(), k
        a = np.array([f[1] for f in FACES], float)[side]
        b = np.array([f[2] for f in FACES], float)[side]
        p = level.positions.astype(np.float64)
        expected_u = side / 6 + 0.01 + np.clip(np.einsum("ij,ij->i", p, a) + 0.5, 0, 1) * (1 / 6 - 0.02)
        expected_v = np.clip(np.einsum("ij,ij->i", p, b) + 0.5, 0, 1)
        tol = 1e-5 + level.error
        assert np.abs(level.uvs[:, 0] - expected_u).max() <= tol / 6 and np.abs(level.uvs[:, 1] - expected_v).max() <= tol, k


# ---------------------------------------------------------------- big meshes

def _torus(faces):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
    from big_mesh import torus

    return torus(faces)


@pytest.mark.parametrize("name", ["torus", "base/rock_trimesh.obj", "base/grass_blade_flora.obj",
                                  "base/rock_caustics.obj"])
def test_collapse_mapping_is_the_replays_mapping(name):
    """``collapse_mapping`` reads from the collapse history what
    ``replay_simplification`` computes by simplifying a second time: the same
    simplified vertex for every original vertex the replay maps into a
    triangle; where a whole piece vanished (rock_caustics has some) the replay
    gives an index that is not meaningful and ours gives -1."""
    import fast_simplification

    from axialdeform.core.lod import collapse_mapping

    if name == "torus":
        p, f = _torus(20_000)
        p, f = p.astype(np.float64), f.astype(np.int64)
    else:
        tm = trimesh.load(data_mesh(name), process=False, force="mesh")
        p, f = np.asarray(tm.vertices, np.float64), np.asarray(tm.faces, np.int64)
    for reduction in (0.5, 0.8, 0.93):
        _, new_faces, collapses = fast_simplification.simplify(p, f, target_reduction=reduction,
                                                               return_collapses=True)
        new_faces = np.asarray(new_faces, np.int64).reshape(-1, 3)
        _, _, replay = fast_simplification.replay_simplification(p.astype(np.float32), f.astype(np.int32), collapses)
        ours = collapse_mapping(len(p), f, collapses, new_faces)
        assert ours is not None and ours.shape == (len(p),)
        referenced = np.zeros(len(p), bool)
        referenced[new_faces.ravel()] = True
        in_triangles = ours >= 0
        assert np.array_equal(ours[in_triangles], replay[in_triangles]), (name, reduction)
        if name != "base/rock_caustics.obj":
            assert in_triangles[np.unique(f)].all()
        assert np.array_equal(np.unique(ours[in_triangles]), np.arange(new_faces.max() + 1))
        # a history that does not give these triangles is refused (the caller then replays)
        assert collapse_mapping(len(p), f, collapses, new_faces[::-1]) is None


def test_spatial_chunks_partition_into_neighbourhoods():
    from axialdeform.core.lod import spatial_chunks

    rng = np.random.default_rng(4)
    pts = rng.random((10_000, 3)) * [10.0, 1.0, 3.0]
    chunks = spatial_chunks(pts, 1000)
    every = np.concatenate(chunks)
    assert len(every) == len(pts) and np.array_equal(np.sort(every), np.arange(len(pts)))
    assert all(500 <= len(c) <= 1000 for c in chunks) and len(chunks) == 16
    # neighbourhoods: the chunks' boxes add up to about the whole box (no chunk spans the field)
    volume = sum(np.prod(pts[c].max(axis=0) - pts[c].min(axis=0)) for c in chunks)
    assert volume < 1.2 * np.prod(pts.max(axis=0) - pts.min(axis=0))


def test_a_big_part_is_simplified_in_chunks_like_parts(monkeypatch):
    """A part over LOD_CHUNK_TRIANGLES is simplified chunk by chunk: the same
    reduction, attributes carried, and a geometric error like the unchunked one
    (chunk borders behave like the borders between parts: they may open by
    about the level's error)."""
    import axialdeform.core.lod as lod

    p, f = _torus(20_000)
    mesh = ad.load_mesh(trimesh.Trimesh(p, f, process=False))
    whole = build_lod_levels(mesh)
    monkeypatch.setattr(lod, "LOD_CHUNK_TRIANGLES", 3000)
    calls = []
    original = lod._simplified
    monkeypatch.setattr(lod, "_simplified", lambda *a: (calls.append(len(a[2])), original(*a))[1])
    chunked = build_lod_levels(mesh)
    assert len(calls) == 3 * 8 and max(calls) <= 3000  # 19 968 triangles: 8 chunks a level
    assert len(chunked) == len(whole)
    for a, b in zip(whole[1:], chunked[1:]):
        assert abs(len(b.faces) - len(a.faces)) <= 0.02 * len(a.faces)
        assert b.error <= 2.0 * a.error + 1e-6
        assert np.isfinite(b.normals).all() and np.allclose(np.linalg.norm(b.normals, axis=1), 1.0, atol=1e-5)


@pytest.mark.slow
def test_lod_of_a_big_mesh_has_bounded_memory(tmp_path):
    """fast-simplification keeps the working arrays of its largest input for the
    life of the process (~290 bytes a triangle; a replay as much again): LOD of
    a 0.5 M-triangle torus grew the process by ~560 MB before chunking and the
    history-read mapping, ~150 MB after.  Measured in a child process."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    script = ("import resource, sys, trimesh\n"
              "sys.path.insert(0, 'tools')\n"
              "from big_mesh import torus\n"
              "import axialdeform as ad\n"
              "from axialdeform.core.lod import build_lod_levels\n"
              "p, f = torus(500_000)\n"
              "mesh = ad.load_mesh(trimesh.Trimesh(p, f, process=False))\n"
              "del p, f\n"
              "before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
              "levels = build_lod_levels(mesh)\n"
              "after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
              "assert len(levels) == 4, len(levels)\n"
              "print((after - before) / 1024)\n")
    done = subprocess.run([sys.executable, "-c", script], cwd=root, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert float(done.stdout.split()[-1]) < 300

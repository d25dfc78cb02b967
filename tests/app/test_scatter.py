"""Scatter on surfaces.

The terrain is a mesh we did not make: ``base/rock_caustics.obj`` from the
test data (the rock of three.js's caustics example, BSD-3-Clause), a flat
rock about 19 x 14 x 7 units lying with +z up; its upper faces are the
"terrain".  There is no terrain mesh in the test data; this is the most
terrain-like real surface there (a broad, gently curved top).
"""

import subprocess
import sys

import numpy as np
import pytest
import trimesh
from PIL import Image
from scipy.spatial import cKDTree

import axialdeform as ad
from axialdeform.cli import main
from axialdeform.core.scatter import poisson_greedy
from axialdeform.core.surface import load_surface, surface_from_heights

from conftest import data_mesh

ROCK = "base/rock_caustics.obj"


@pytest.fixture(scope="module")
def terrain():
    path = data_mesh(ROCK)
    tm = trimesh.load(path, force="mesh", process=False)
    return path, tm, float(np.linalg.norm(tm.extents))


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_origin_anchor_puts_every_instance_on_the_terrain_and_keeps_the_spacing(terrain, stone):
    path, tm, size = terrain
    d = 0.6
    params = ad.scatter(path, stone, 300, placement=ad.core.Placement(min_distance=d, anchor="origin", up="z"), seed=3,
                        variation=ad.Variation(bend=0.2))
    assert params.shape == (300, 16) and params.dtype == np.float32
    p = params[:, 10:13].astype(np.float64)
    _, dist, face = trimesh.proximity.closest_point(tm, p)
    assert dist.max() <= 1e-4 * size
    assert (tm.face_normals[face, 2] > 0).all()  # on the faces that face up (+z)
    assert cKDTree(p).query(p, k=2)[0][:, 1].min() >= d * (1 - 1e-6)


def test_spacing_is_a_real_poisson_disk_and_matches_the_sequential_loop():
    rng = np.random.default_rng(5)
    pts = rng.random((600, 3)) * [10, 0, 10]
    fixed = rng.random((20, 3)) * [10, 0, 10]
    keep = poisson_greedy(pts, 0.7, fixed)
    kept = []  # the sequential definition, written out (600 points: a test, not a hot path)
    for i, q in enumerate(pts):
        if np.linalg.norm(fixed - q, axis=1).min() >= 0.7 and all(np.linalg.norm(pts[j] - q) >= 0.7 for j in kept):
            kept.append(i)
    assert np.flatnonzero(keep).tolist() == kept
    assert len(kept) > 50


def test_half_black_density_map_is_honoured(terrain, stone, tmp_path):
    path, tm, _ = terrain
    img = np.full((16, 32), 255, dtype=np.uint8)
    img[:, :16] = 0  # left half (smaller x) black
    Image.fromarray(img).save(tmp_path / "half.png")
    params = ad.scatter(path, stone, 400, placement=ad.core.Placement(min_distance=0.3, density=tmp_path / "half.png", anchor="origin",
                                                                 up="z"), seed=1)
    x = params[:, 10].astype(np.float64)
    mid = (tm.bounds[0, 0] + tm.bounds[1, 0]) / 2
    assert len(params) == 400
    assert x.min() >= mid - 1e-5  # none in the black half
    # and the white half is covered to its far edge (not just a sliver)
    assert x.max() > tm.bounds[1, 0] - 0.2 * tm.extents[0]


def test_density_rows_run_along_z_top_row_at_smallest_z(stone):
    heights = np.zeros((20, 30))
    dens = np.ones((10, 10))
    dens[:5] = 0  # top half of the image black: the smaller z
    params = ad.scatter(heights, stone, 200, placement=ad.core.Placement(density=dens, anchor="origin", extent=(30.0, 20.0)), seed=2)
    z = params[:, 12]
    assert z.min() >= 0.0 - 1e-6 and z.max() > 5.0
    assert np.abs(params[:, 11]).max() == 0.0  # flat map at height 0


@pytest.mark.slow
def test_same_seed_same_bytes_other_seed_other_bytes(terrain, tmp_path):
    path, _, _ = terrain
    args = ["scatter", path, "stone", "-n", "150", "--min-distance", "0.5", "--up", "z", "--align-to-normal", "0.7",
            "--scale", "0.5:1.5"]
    for name, seed in (("a.adp", 7), ("b.adp", 7), ("c.adp", 8)):
        res = run(*args, "--seed", seed, "-o", tmp_path / name)
        assert res.returncode == 0, res.stderr
    a, b, c = ((tmp_path / n).read_bytes() for n in ("a.adp", "b.adp", "c.adp"))
    assert a == b and a != c
    values = ad.read_params(tmp_path / "a.adp")
    assert values.shape == (150, 19)
    assert (values[:, 16] >= 0.5).all() and (values[:, 16] <= 1.5).all() and values[:, 16].std() > 0.1
    assert (values[:, 17:19] == 0).all()


def test_align_to_normal_turns_the_up_axis_onto_the_normal(terrain, stone):
    path, tm, _ = terrain
    for f in (0.0, 0.5, 1.0):
        params = ad.scatter(path, stone, 100, placement=ad.core.Placement(anchor="origin", up="z", align_to_normal=f), seed=4)
        up = ad.core.rotation_matrices(params[:, 13:16])[:, :, 2]  # R · e_z
        _, _, face = trimesh.proximity.closest_point(tm, params[:, 10:13].astype(np.float64))
        normal = tm.face_normals[face]
        full = np.arccos(np.clip(normal[:, 2], -1, 1))
        got = np.arccos(np.clip(np.einsum("ij,ij->i", up, normal), -1, 1))
        assert np.allclose(got, (1 - f) * full, atol=2e-3)
        # tilted within the plane of e_z and the normal
        plane = np.cross(np.array([0, 0, 1.0]), normal)
        assert np.abs(np.einsum("ij,ij->i", up, plane)).max() < 2e-3
    yaw = ad.core.rotation_matrices(params[:, 13:16])[:, :, 0]
    assert np.ptp(np.arctan2(yaw[:, 1], yaw[:, 0])) > 5.0  # random turns about the up axis


@pytest.mark.parametrize("anchor", ["bottom", "center"])
def test_the_bent_scaled_instance_stands_on_its_anchor(terrain, leaf, anchor):
    path, tm, size = terrain
    params = ad.scatter(path, leaf, 50, placement=ad.core.Placement(anchor=anchor, up="z", align_to_normal=0.6),
                        variation=ad.Variation(bend=0.3, scale=(0.5, 2.0)), seed=9)
    lo, hi = leaf.positions.min(axis=0), leaf.positions.max(axis=0)
    a = (lo + hi) / 2
    if anchor == "bottom":
        a[2] = lo[2]
    world, _ = ad.deform(leaf.axis, a[None, :], np.array([[0.0, 0.0, 1.0]]), params)
    _, dist, _ = trimesh.proximity.closest_point(tm, world[:, 0].astype(np.float64))
    assert dist.max() <= 1e-4 * size
    assert not np.allclose(params[:, 10:13], world[:, 0])  # p itself is not the surface point


def test_height_map_image_surface(tmp_path, stone):
    x = np.linspace(0, 1, 40)
    X, Z = np.meshgrid(x, x[:30])
    grey = (255 * (0.5 + 0.4 * np.sin(4 * X) * np.cos(3 * Z))).astype(np.uint8)
    Image.fromarray(grey).save(tmp_path / "hm.png")
    surf = load_surface(tmp_path / "hm.png", height_scale=5.0, extent=(40.0,))
    assert np.allclose(surf.mesh.extents[[0, 2]], [40.0, 40.0 * 29 / 39])
    params = ad.scatter(tmp_path / "hm.png", stone, 200, placement=ad.core.Placement(height_scale=5.0, extent=40.0, anchor="origin",
                                                                                min_distance=1.0))
    _, dist, _ = trimesh.proximity.closest_point(surf.mesh, params[:, 10:13].astype(np.float64))
    assert dist.max() <= 1e-4 * 40
    # a bright pixel is high: the vertex under pixel (row 0, col 39) is at the +x, -z corner
    v = np.asarray(surf.mesh.vertices)
    corner = v[np.argmin(np.linalg.norm(v[:, [0, 2]] - [20.0, -20.0 * 29 / 39], axis=1))]
    assert np.isclose(corner[1], grey[0, 39] / 255 * 5.0)


@pytest.mark.slow
def test_too_few_writes_what_fits_and_exits_2_unless_allowed(terrain, tmp_path):
    path, _, _ = terrain
    res = run("scatter", path, "stone", "-n", "100000", "--min-distance", "1.0", "--up", "z", "-o", tmp_path / "f.adp")
    assert res.returncode == 2
    line = res.stderr.strip()
    assert "\n" not in line and "Traceback" not in line and "of 100000" in line
    got = ad.read_params(tmp_path / "f.adp")
    assert 50 < len(got) < 100000 and f"only {len(got)} of 100000" in line
    res = run("scatter", path, "stone", "-n", "100000", "--min-distance", "1.0", "--up", "z", "-o", tmp_path / "g.adp",
              "--allow-fewer")
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "g.adp").read_bytes() == (tmp_path / "f.adp").read_bytes()
    with pytest.raises(ad.core.TooFewError) as info:
        ad.scatter(path, "stone", 100000, placement=ad.core.Placement(min_distance=1.0, up="z"))
    assert len(info.value.params) == len(got)


@pytest.mark.slow
def test_bad_input_one_line_exit_2(terrain, tmp_path, capsys):
    path, _, _ = terrain
    Image.new("L", (1, 1), 128).save(tmp_path / "one.png")
    Image.new("L", (8, 8), 0).save(tmp_path / "black.png")
    cases = [
        ([data_mesh("edge_cases/empty.obj"), "stone"], "empty.obj"),
        ([data_mesh("edge_cases/plane.ply"), "stone"], "faces up"),  # the plane faces +z only
        ([tmp_path / "one.png", "stone"], "1x1"),
        ([path, "stone", "--up", "z", "--density", tmp_path / "black.png"], "black"),
        ([path, "stone", "--up", "z", "--scale", "0:1"], "0 < MIN <= MAX"),
        ([path, "stone", "--up", "z", "--min-distance", "100"], "min-distance"),
        ([path, "stone", "--up", "z", "--align-to-normal", "1.5"], "align-to-normal"),
    ]
    out = tmp_path / "x.adp"
    for args, expect in cases:  # in-process (fast); one subprocess below checks the real exit
        assert main(["scatter", *map(str, args), "-n", "10", "-o", str(out)]) == 2, args
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and err.startswith("axialdeform scatter: error: ") and expect in err, (args, err)
        assert not out.exists()
    res = run("scatter", path, "stone", "--up", "z", "--scale", "0:1", "-n", "10", "-o", out)
    assert res.returncode == 2 and "Traceback" not in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_speed_sized_run_is_vectorized_and_correct():
    """A 20 000-triangle terrain and 5 000 instances (the speed goal itself is in tools/scatter_speed.py)."""
    x = np.linspace(0, 1, 101)
    X, Z = np.meshgrid(x, x)
    surf = surface_from_heights(0.5 + 0.3 * np.sin(5 * X) * np.cos(4 * Z), height_scale=10, extent=100.0)
    assert len(surf.mesh.faces) == 20000
    params = ad.scatter(surf, "stone", 5000, placement=ad.core.Placement(min_distance=0.8, anchor="origin"), seed=1)
    p = params[:, 10:13].astype(np.float64)
    assert cKDTree(p).query(p, k=2)[0][:, 1].min() >= 0.8 * (1 - 1e-6)


def test_density_white_only_where_nothing_faces_up_is_an_error(stone):
    # two squares side by side: x < 0 faces up, x > 0 faces down
    v = np.array([[-2, 0, -1], [0, 0, -1], [0, 0, 1], [-2, 0, 1], [2, 0, -1], [2, 0, 1]], dtype=float)
    f = np.array([[0, 2, 1], [0, 3, 2], [1, 5, 2], [1, 4, 5]])
    surface = trimesh.Trimesh(v, f, process=False)
    assert surface.face_normals[0, 1] > 0 and surface.face_normals[2, 1] < 0
    right = np.zeros((4, 4))
    right[:, 2:] = 1.0
    with pytest.raises(ad.core.ScatterError, match="density: no candidate"):
        ad.scatter(surface, stone, 10, placement=ad.core.Placement(density=right))
    left = 1.0 - right
    params = ad.scatter(surface, stone, 10, placement=ad.core.Placement(density=left, anchor="origin"))
    assert (params[:, 10] <= 0).all()


# ------------------------------------------- height maps within the memory bound


def _trimesh_weights(tm, u):
    """What scatter weighted faces by before: trimesh's own areas and normals of every face."""
    area = np.asarray(tm.area_faces)
    return np.where((np.asarray(tm.face_normals)[:, u] > 1e-9) & (area > 0), area, 0.0)


def _surfaces(terrain):
    rng = np.random.default_rng(5)
    yield surface_from_heights(rng.random((23, 31)), height_scale=4.0, extent=(10.0, 7.0))
    yield surface_from_heights(rng.random((17, 12)), up="z", height_scale=2.0)
    yield surface_from_heights(rng.random((9, 14)), up="x")
    yield load_surface(terrain[0], up="z")  # a real mesh: faces up and down, uint32 faces


def test_sample_is_trimesh_sample_surface(terrain, monkeypatch):
    """Surface.sample gathers only the picked faces, yet draws what
    trimesh.sample.sample_surface draws -- the same points and faces bit for
    bit, and the generator left in the same state -- for every kind of surface."""
    from axialdeform.core import surface as S

    monkeypatch.setattr(S, "FACE_BLOCK", 97)  # many blocks: the blocked areas must equal trimesh's whole ones
    for surf in _surfaces(terrain):
        tm = surf.mesh
        assert np.array_equal(surf.weights, _trimesh_weights(tm, surf.up))
        assert np.array_equal(surf.bounds, tm.bounds)
        tri = tm.triangles[surf.upward].reshape(-1, 3)
        assert surf.size == float((tri.max(axis=0) - tri.min(axis=0)).max())
        for seed, count in ((0, 1), (3, 257), (11, 5000)):
            mine, theirs = np.random.default_rng(seed), np.random.default_rng(seed)
            p, f = surf.sample(count, mine)
            q, g = trimesh.sample.sample_surface(tm, count, face_weight=surf.weights, seed=theirs)
            assert p.dtype == q.dtype and np.array_equal(p, q) and np.array_equal(f, g), surf.name
            assert mine.random() == theirs.random()
            assert np.array_equal(surf.face_normals(f), np.asarray(tm.face_normals)[f])


def test_height_map_grid_is_the_one_trimesh_built_before():
    """The grid written in place (uint32 faces, wound to face up) is the old
    meshgrid one: the same vertices, and the same faces up to the winding flip."""
    h = np.random.default_rng(2).random((6, 9))
    for up in "xyz":
        surf = surface_from_heights(h, up=up, height_scale=3.0, extent=(8.0,))
        rows, cols = h.shape
        u = "xyz".index(up)
        g0, g1 = ad.core.axis.PERPENDICULAR[u]
        jj, ii = np.meshgrid(np.arange(cols), np.arange(rows))
        verts = np.zeros((rows * cols, 3))
        verts[:, g0] = (jj.ravel() / (cols - 1) - 0.5) * 8.0
        verts[:, g1] = (ii.ravel() / (rows - 1) - 0.5) * 8.0 * (rows - 1) / (cols - 1)
        verts[:, u] = h.ravel() * 3.0
        k = (ii[:-1, :-1] * cols + jj[:-1, :-1]).ravel()
        faces = np.concatenate([np.stack([k, k + cols, k + 1], 1), np.stack([k + 1, k + cols, k + cols + 1], 1)])
        if trimesh.Trimesh(verts, faces, process=False).face_normals[:, u].sum() < 0:
            faces = faces[:, ::-1]
        assert np.array_equal(surf.vertices, verts) and surf.faces.dtype == np.uint32
        assert np.array_equal(surf.faces, faces) and surf.upward.all()


def _traced_peak_bytes(fn) -> int:
    import gc
    import tracemalloc

    gc.collect()
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


#: what the library may allocate (numpy arrays and Python objects, tracemalloc's
#: peak) per pixel of a 600 x 600 height map while scattering on it, or loading a
#: scene with it as a terrain (the surface, its drawing copy and normals, a scatter
#: layer); before: 600 and 682 bytes a pixel; after: ~95 and ~218
HEIGHT_MAP_TRACED_BYTES_PER_PIXEL = {"scatter": 150, "scene": 260}


@pytest.mark.slow
@pytest.mark.parametrize("what", ["scatter", "scene"])
def test_height_map_memory_is_bounded_per_pixel(tmp_path, stone, what):
    """A 600 x 600 height map: building the surface, its area weights, the
    scatter (and for a scene the terrain's drawing copy with its normals)
    peaks under HEIGHT_MAP_TRACED_BYTES_PER_PIXEL a pixel.  Before: trimesh's
    caches of every face and sample_surface's (f, 2, 3) edge vectors."""
    from axialdeform.core.scene import load_scene

    rng = np.random.default_rng(7)
    Image.fromarray((rng.random((600, 600)) * 255).astype(np.uint8)).save(tmp_path / "hm.png")
    if what == "scatter":
        run_it = lambda: ad.scatter(tmp_path / "hm.png", stone, 200, seed=1)  # noqa: E731
    else:
        (tmp_path / "s.toml").write_text('[terrain]\nheightmap = "hm.png"\nheight_scale = 20.0\n'
                                         '[[layer]]\nmesh = "stone"\n[layer.scatter]\ncount = 200\nseed = 3\n')
        run_it = lambda: load_scene(tmp_path / "s.toml")  # noqa: E731
    run_it()  # imports and first-use caches are not the map's
    peak = _traced_peak_bytes(run_it)
    assert peak < HEIGHT_MAP_TRACED_BYTES_PER_PIXEL[what] * 600 * 600, f"{peak / 2**20:.0f} MB: {peak / 600**2:.0f} B a pixel"

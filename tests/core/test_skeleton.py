"""axes="skeleton" and axes="auto": a model's axes from its own shape (core/skeleton.py), on a tree whose
wood is one welded piece (tests/helpers/one_piece.py): the branches found, a surface that stays whole at
a bend of 0.3 a level, the same tree whatever the order of the file, the cache, the rule "auto", errors."""

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core import skeleton
from axialdeform.core.errors import MeshError

from helpers.one_piece import branch_tips, one_piece_tree


@pytest.fixture(autouse=True)
def _own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("AXIALDEFORM_CACHE", str(tmp_path / "cache"))


@pytest.fixture(scope="module")
def wood():
    return one_piece_tree()


def _seams(mesh, bend=0.3, n=40, seed=2, wind=None):
    """Max stretch of an edge whose ends belong to two axes, max of one inside an axis, and the largest
    distance between bent vertices that share a rest position (in units of the trunk's L)."""
    tree = mesh.tree
    params = ad.random_params(mesh, n, seed=seed, variation=ad.Variation(bend=(bend,) * 3))
    if wind is not None:
        params = ad.core.wind.apply_wind(wind, tree, params, 1.1)
    pos, _ = ad.deform(mesh, params)
    e = mesh.edges.astype(np.int64)
    rest = np.linalg.norm(mesh.positions[e[:, 0]] - mesh.positions[e[:, 1]], axis=1)
    e, rest = e[rest > 0], rest[rest > 0]
    stretch = np.linalg.norm(pos[:, e[:, 0]] - pos[:, e[:, 1]], axis=2) / rest
    cross = tree.vertex_axis[e[:, 0]] != tree.vertex_axis[e[:, 1]]
    _, first, inverse = np.unique(mesh.positions, axis=0, return_index=True, return_inverse=True)
    spread = float(np.abs(pos - pos[:, first[inverse.ravel()]]).max()) / tree.axes[0].length
    return float(stretch[:, cross].max()), float(stretch[:, ~cross].max()), spread, int(cross.sum())


def test_a_one_piece_tree_gets_an_axis_per_branch(wood):
    mesh = wood.with_axes("skeleton")
    tree = mesh.tree
    assert tree.count == 5, tree.describe()
    assert tree.names[0] == "trunk" and all(p == 0 for p in tree.parents[1:])
    tips = [int(tree.vertex_axis[np.argmin(np.linalg.norm(mesh.positions - t, axis=1))]) for t in branch_tips()]
    assert sorted(tips) == [1, 2, 3, 4]  # each branch's tip on its own child axis
    foot = mesh.positions[mesh.positions[:, 1] < 0.3]
    assert set(tree.vertex_axis[mesh.positions[:, 1] < 0.3]) == {0} and len(foot)  # the trunk's foot is the root's
    assert all(t < 0.1 for t in tree.anchors[1:])  # each branch anchored where it leaves the trunk


def test_the_seams_of_one_piece_add_no_stretch_at_a_bend_of_0_3(wood):
    cross, inner, spread, count = _seams(wood.with_axes("skeleton"))
    assert count > 50
    assert cross <= 1.1 * inner, (cross, inner)
    assert spread == 0.0


def test_vertices_split_for_flat_shading_stay_together(wood):
    faces = wood.faces
    split = ad.BaseMesh.from_arrays(wood.positions[faces.ravel()], np.arange(faces.size, dtype=np.uint32).reshape(-1, 3),
                                    name="split")
    mesh = split.with_axes("skeleton")
    assert mesh.tree.count == 5
    cross, inner, spread, _ = _seams(mesh)
    assert spread <= 1e-3 and cross <= 1.1 * inner


def test_the_tree_does_not_depend_on_the_order_of_the_file(wood):
    rng = np.random.default_rng(4)
    order = rng.permutation(wood.vertex_count)
    back = np.argsort(order)
    shuffled = ad.BaseMesh.from_arrays(wood.positions[order], back[wood.faces][rng.permutation(len(wood.faces))].astype(np.uint32),
                                       name="shuffled")
    a, b = wood.with_axes("skeleton").tree, shuffled.with_axes("skeleton").tree
    assert a.describe() == b.describe()
    assert np.array_equal(a.vertex_axis[order], b.vertex_axis)
    for x, y in zip(a.axes, b.axes):
        assert np.allclose(x.matrix, y.matrix, atol=1e-9) and abs(x.length - y.length) < 1e-9


def test_the_skeleton_is_kept_by_the_mesh_fingerprint(wood, monkeypatch, tmp_path):
    first = wood.with_axes("skeleton").tree
    files = list((tmp_path / "cache").iterdir())
    assert len(files) == 1 and files[0].name.startswith(wood.fingerprint.hex()[:32])

    def no_second_time(*a, **k):
        raise AssertionError("computed again")

    monkeypatch.setattr(skeleton, "skeleton_tree", no_second_time)
    again = wood.with_axes("skeleton").tree
    assert again.digest == first.digest and again.describe() == first.describe()
    files[0].write_bytes(b"not a cache file")  # a damaged cache file is computed again, never an error
    monkeypatch.undo()
    monkeypatch.setenv("AXIALDEFORM_CACHE", str(tmp_path / "cache"))
    assert wood.with_axes("skeleton").tree.digest == first.digest
    assert files[0].read_bytes()[:2] == b"PK"  # and written anew


def test_the_branches_to_save_and_the_tree_come_from_one_skeleton(wood, monkeypatch):
    from axialdeform.core import shape_axes

    monkeypatch.setenv("AXIALDEFORM_CACHE", "off")
    calls = []
    real = shape_axes.skeleton_branches
    monkeypatch.setattr(shape_axes, "skeleton_branches", lambda *a, **k: calls.append(1) or real(*a, **k))
    tree, branches = shape_axes.skeleton_and_branches(wood)
    assert len(calls) == 1 and len(branches) == tree.count == 5
    assert tree.digest == wood.with_axes("skeleton").tree.digest  # what axes="skeleton" gives


def test_no_cache_is_kept_when_it_is_off(wood, monkeypatch, tmp_path):
    monkeypatch.setenv("AXIALDEFORM_CACHE", "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert wood.with_axes("skeleton").tree.count == 5
    assert not (tmp_path / "cache").exists() and not (tmp_path / "xdg").exists()


def test_auto_keeps_the_parts_when_they_are_the_limbs_and_finds_the_branches_when_not(wood):
    tree = ad.load_mesh("tree", axes="auto").tree
    assert tree.count == 10 and tree.names == ad.load_mesh("tree", axes="parts").tree.names
    assert wood.with_axes("auto").tree.describe() == wood.with_axes("skeleton").tree.describe()


def test_random_variation_wind_and_bounds_follow_the_skeleton(wood):
    mesh = wood.with_axes("skeleton")
    params = ad.random_params(mesh, 8, seed=1, variation=ad.Variation(bend=(0.05, 0.3), droop=0.2))
    assert params.shape == (8, 10 * 5 + 6)
    pos, normals = ad.deform(mesh, params)
    assert np.isfinite(pos).all() and np.allclose(np.linalg.norm(normals, axis=2), 1.0, atol=1e-5)
    fitted = ad.fit_params(mesh, pos)  # the numbers come back from the bent meshes
    assert np.abs(ad.deform(mesh, fitted.params)[0] - pos).max() < 1e-5 * mesh.axis.length
    wind = ad.Wind(direction=(1.0, 0.0, 0.3), strength=0.3, gustiness=0.5)
    swayed, _ = ad.deform(mesh, ad.core.wind.apply_wind(wind, mesh.tree, params, 1.1))
    assert np.abs(swayed - pos).max() > 0.05 * mesh.axis.length  # the wind moves the branches
    cross, inner, spread, _ = _seams(mesh, wind=wind)  # the seams hold in the wind (clamped at the anchors too)
    assert cross <= 1.1 * inner and spread == 0.0


def test_wrong_rules_and_settings_are_said_in_words(wood):
    with pytest.raises(MeshError, match="'parts', 'skeleton', 'auto'"):
        wood.with_axes("bones")
    with pytest.raises(MeshError, match="min_branch"):
        skeleton.skeleton_tree(wood, min_branch=1.5)
    with pytest.raises(MeshError, match="max_axes"):
        skeleton.skeleton_tree(wood, max_axes=0)


def test_max_axes_keeps_the_longest_branches(wood):
    tree = skeleton.skeleton_tree(wood, max_axes=3)
    assert tree.count == 3
    tips = branch_tips()
    kept = {int(tree.vertex_axis[np.argmin(np.linalg.norm(wood.positions - t, axis=1))]) for t in tips[:2]}
    assert kept == {1, 2}  # the two longest branches (1.0 and 0.9 long)


def test_a_second_limb_piece_keeps_its_own_branches_on_its_own_axes(wood):
    """Two woods side by side (two pieces): the second hangs on the first by one axis, and each of its other
    axes hangs on an axis of its own piece (not on the first wood's trunk)."""
    two = ad.BaseMesh.from_arrays(np.vstack([wood.positions, wood.positions + np.float32([1.8, 0.3, 0.0])]),
                                  np.vstack([wood.faces, wood.faces + wood.vertex_count]).astype(np.uint32), name="two")
    tree = two.with_axes("skeleton").tree
    assert tree.count == 10, tree.describe()
    second = np.arange(two.vertex_count) >= wood.vertex_count
    piece_of = [bool(second[tree.vertex_axis == k].all()) for k in range(tree.count)]
    assert piece_of.count(True) == 5
    crossing = [k for k in range(1, tree.count) if piece_of[k] != piece_of[tree.parents[k]]]
    assert len(crossing) == 1  # only the second wood's first axis hangs on the first wood


def test_the_parts_heuristic_does_not_depend_on_the_order_of_the_parts(tmp_path):
    """The bundled tree's ten parts written in the reverse order: the same trunk, the same parent for every part."""
    import trimesh

    from axialdeform.core.io.mesh import bundled_mesh_path

    scene = trimesh.load(bundled_mesh_path("tree"), force="scene")
    names = list(scene.geometry)
    again = trimesh.Scene()
    for name in reversed(names):
        again.add_geometry(scene.geometry[name], geom_name=name, node_name=name)
    again.export(str(tmp_path / "reversed.glb"))
    a = ad.load_mesh("tree", axes="parts").tree
    b = ad.load_mesh(tmp_path / "reversed.glb", axes="parts").tree
    assert ad.load_mesh(tmp_path / "reversed.glb").part_names == tuple(reversed(ad.load_mesh("tree").part_names))
    assert b.names[0] == a.names[0] == "trunk"
    assert {n: a.names[p] for n, p in zip(a.names[1:], a.parents[1:])} == {n: b.names[p] for n, p in zip(b.names[1:], b.parents[1:])}
    assert a.names == b.names  # the axes in the same order: nearest first, by where the parts are


def test_an_export_carries_the_axes_found_from_the_shape(wood, tmp_path):
    """The instanced GLB (AXIALDEFORM_bend) carries the skeleton's axes: read back, the same tree bends the
    same way, without computing a skeleton again."""
    from axialdeform.core.io.gltf import export_glb, read_instanced_glb

    mesh = wood.with_axes("skeleton")
    p = ad.random_params(mesh, 6, seed=4, variation=ad.Variation(bend=(0.05, 0.3)), placement="disc", spacing=3.0)
    path = export_glb(tmp_path / "woods.glb", mesh, p, "instanced")
    back, params = read_instanced_glb(path)
    assert back.tree.count == 5 and np.array_equal(back.tree.vertex_axis, mesh.tree.vertex_axis)
    assert np.allclose(back.tree.anchors, mesh.tree.anchors)
    assert np.abs(ad.deform(back, params)[0] - ad.deform(mesh, p)[0]).max() < 1e-5 * mesh.axis.length


def test_the_branches_can_be_saved_edited_and_loaded_again(wood, tmp_path):
    """An axes file of [[branch]] tables: written from the skeleton, read back it gives the same tree (the same
    digest, so parameter files fit); a branch left out gives its vertices to the branches near it; a file that
    is not one is refused naming the file and the branch."""
    from axialdeform.core.io.mesh import with_axes, write_axes_file

    branches = skeleton.skeleton_branches(wood)
    path = write_axes_file(tmp_path / "wood.toml", branches, wood.name)
    found = wood.with_axes("skeleton").tree
    again = with_axes(wood, path).tree
    assert again.digest == found.digest and again.describe() == found.describe()
    text = path.read_text()
    cut = text.index('[[branch]]\nname = "branch4"')
    path.write_text(text[:cut])
    fewer = with_axes(wood, path).tree
    assert fewer.count == 4 and fewer.names == found.names[:4]
    tip = branch_tips()[[int(found.vertex_axis[np.argmin(np.linalg.norm(wood.positions - t, axis=1))]) for t in branch_tips()].index(4)]
    assert fewer.vertex_axis[np.argmin(np.linalg.norm(wood.positions - tip, axis=1))] == 0  # to the trunk it grows from
    path.write_text(text.replace('parent = "trunk"', 'parent = "stem"', 1))
    with pytest.raises(MeshError, match=r"wood.toml: .*branch 2 \(branch1\): parent: expected the name of an earlier branch"):
        with_axes(wood, path)
    path.write_text('[[branch]]\nname = "trunk"\npoints = [[0, 0]]\n')
    with pytest.raises(MeshError, match=r"wood.toml: .*branch 1 \(trunk\): points: expected two or more points"):
        with_axes(wood, path)


def test_crowns_and_bark_marks_stay_on_what_they_sit_on():
    """Separate pieces (a crown blob on each branch tip, bark plates on the trunk) ride the branch they
    touch: where two pieces touch, the gap a bend of 0.3 a level opens is at most 0.1 of the local radius
    at the median and 0.5 at the 95th percentile, still and in the wind (tools/joint_gap.py)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
    import joint_gap

    from helpers.one_piece import crowned_tree

    mesh = crowned_tree().with_axes("skeleton")
    assert mesh.tree.count == 5
    for wind in (None, ad.Wind(direction=(1.0, 0.0, 0.4), strength=0.3, gustiness=0.5)):
        gaps = joint_gap.contact_gaps(mesh, 0.3, 40, 1, wind)
        assert gaps["pairs"] > 100 and gaps["median"] <= 0.1 and gaps["p95"] <= 0.5 and gaps["max"] <= 1.0, gaps


def test_a_crown_pierced_by_two_branches_stays_on_both():
    """A crown blob two branches (and the trunk) pierce: bound whole to one branch it opens where the other leaves it (median gap
    0.13 of the local radius in the wind, over the 0.1 bound); blending the two branches by nearness
    (AxisTree.blend) keeps both contacts closed -- measured on the same pairs, in the same units."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
    import joint_gap

    from axialdeform.core.skeleton import skeleton_tree

    from helpers.one_piece import pierced_tree

    mesh = pierced_tree()
    mixed, whole = mesh.with_axes("skeleton"), mesh.with_axes(skeleton_tree(mesh, blend=False))
    assert mixed.tree.blend is not None and whole.tree.blend is None and mixed.tree.count == whole.tree.count == 5
    crown = np.arange(one_piece_tree().vertex_count, mesh.vertex_count)
    assert len(set(mixed.tree.vertex_axis[crown])) >= 3  # the trunk and both branches hold it where they are nearest
    assert len(set(whole.tree.vertex_axis[crown])) == 1
    wind = ad.Wind(direction=(1.0, 0.0, 0.4), strength=0.3, gustiness=0.5)
    before = joint_gap.contact_gaps(whole, 0.3, 40, 1, wind, pairs_from=whole)
    after = joint_gap.contact_gaps(mixed, 0.3, 40, 1, wind, pairs_from=whole)
    assert before["median"] > 0.1 and after["median"] <= 0.1 and after["p95"] <= 0.5, (before, after)


def test_a_scene_layer_takes_axes_from_the_shape(wood, tmp_path):
    """``axes = "skeleton"`` in a scene file's layer: the scattered trees bend at every branch."""
    path = tmp_path / "wood.obj"
    with open(path, "w") as f:
        f.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in wood.positions.astype(float).tolist())
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in wood.faces)
    (tmp_path / "ground.obj").write_text("v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\nf 1 3 2\nf 1 4 3\n")
    terrain = '[terrain]\nmesh = "ground.obj"\n'
    (tmp_path / "s.toml").write_text(terrain + '[[layer]]\nname = "woods"\nmesh = "wood.obj"\naxes = "skeleton"\n'
                                     '[layer.scatter]\ncount = 12\nseed = 3\nbend = [0.04, 0.3]\n', encoding="utf-8")
    scene = ad.Scene.load(tmp_path / "s.toml")
    layer = scene.layers[0]
    assert layer.mesh.axis_count == 5 and layer.params.shape == (12, 10 * 5 + 6)
    (tmp_path / "t.toml").write_text(terrain + '[[layer]]\nname = "woods"\nmesh = "wood.obj"\naxes = 3\n'
                                     '[layer.scatter]\ncount = 12\n', encoding="utf-8")
    with pytest.raises(ad.core.SceneError, match="expected 'skeleton', 'parts', 'auto'"):
        ad.Scene.load(tmp_path / "t.toml")

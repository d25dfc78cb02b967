"""Several axes in a hierarchy (docs/method.md, "Several axes"): the tree,
the 10·K + 6 record, the CPU reference.  No GL."""

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

import axialdeform as ad
from axialdeform.core import MeshError, MeshMismatchError, ParamError
from axialdeform.core.axes import TREE_AXES, AxisTree
from axialdeform.core.deform import bend_model, tree_bend
from axialdeform.core.record import join_record, split_record, tree_width

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
import make_tree  # noqa: E402 - tools/ is not a package


def welded_tree():
    """A trunk along y and one branch along x whose first ring is ALSO in the
    trunk's part (coincident vertices, two indices): a closed joint to test."""
    trunk = make_tree.tube([0, 0, 0], [0, 3, 0], 0.2, 0.1, rings=8)
    ring = make_tree.tube([0, 1.5, 0], [1.5, 1.5, 0], 0.05, 0.02, rings=7, sides=6)
    collar = trimesh.Trimesh(ring.vertices[:6], [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]], process=False)
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.util.concatenate([trunk, collar]), geom_name="trunk", node_name="trunk")
    scene.add_geometry(ring, geom_name="branch", node_name="branch")
    mesh = ad.load_mesh(scene)
    return mesh.with_axes([{"part": "trunk", "axis": "y"}, {"part": "branch", "parent": "trunk", "axis": "x"}])


@pytest.fixture(scope="module")
def tree():
    return ad.load_mesh("tree", axes=TREE_AXES)


def test_the_bundled_tree_and_its_hierarchy(tree):
    assert tree.axis_count == 10 and tree.tree.parents == (-1, 0, 0, 0, 0, 0, 0, 1, 3, 5)
    assert list(tree.tree.depth) == [0, 1, 1, 1, 1, 1, 1, 2, 2, 2]
    assert set(tree.part_names) == {e["part"] for e in TREE_AXES}
    assert np.array_equal(tree.axis.direction, [0, 1, 0])  # the trunk: axis y
    for k in range(1, 10):  # every child axis points away from its parent (t = 0 at its root)
        a, parent = tree.tree.axes[k], tree.tree.axes[tree.tree.parents[k]]
        root, tip = a.control_points[0], a.control_points[-1]
        p0, p1 = parent.control_points[0], parent.control_points[-1]
        def dist(x, p0=p0, p1=p1):
            t = np.clip((x - p0) @ (p1 - p0) / ((p1 - p0) @ (p1 - p0)), 0, 1)
            return np.linalg.norm(x - (p0 + t * (p1 - p0)))
        assert dist(root) < dist(tip)
    # the same tree, made again by the tool, is the bundled file's
    fresh = ad.load_mesh(make_tree.tree_scene()).with_axes(TREE_AXES)
    assert np.allclose(fresh.positions, tree.positions) and fresh.tree.digest == tree.tree.digest


def test_one_axis_through_the_tree_code_is_the_plain_path():
    stone = ad.load_mesh("stone")
    one = dataclasses.replace(stone, tree=AxisTree((stone.axis,), (-1,), np.zeros(stone.vertex_count, np.int32)),
                              _axis=None)
    for extended in (False, True):
        turn = {"scale": (0.5, 2), "twist": 1, "taper": 0.5} if extended else {}
        p = ad.random_params(stone, 9, seed=2, variation=ad.Variation(bend=0.2, **turn))
        a, b = ad.deform(one, p), ad.deform(stone, p)
        np.testing.assert_allclose(a[0], b[0], atol=1e-6 * stone.axis.length)
        np.testing.assert_allclose(a[1], b[1], atol=1e-6)


def test_zero_offsets_give_the_mesh(tree):
    pos, nrm = ad.deform(tree, np.zeros((2, tree_width(tree.axis_count)), np.float32))
    assert np.array_equal(pos[0], tree.positions)
    np.testing.assert_allclose(nrm[0], tree.normals, atol=1e-6)


def test_a_trunk_only_bend_moves_every_vertex_as_the_trunks_field(tree):
    p = ad.random_params(tree, 6, seed=3, variation=ad.Variation(bend=(0.2, 0.0)))
    assert not p[:, 10:10 * tree.axis_count].any()
    pos, _ = ad.deform(tree, p)
    standard, _ = split_record(p, tree.axis_count)
    field, _ = bend_model(tree.axis, tree.positions, tree.normals, standard[:, :10].reshape(-1, 5, 2).astype(float))
    rot = ad.core.rotation_matrices(standard[:, 13:16].astype(float))
    expect = np.einsum("nij,nvj->nvi", rot, field) + standard[:, None, 10:13]
    assert np.abs(pos - expect).max() <= 1e-5 * tree.axis.length


def test_joints_stay_closed():
    mesh = welded_tree()
    tree = mesh.tree
    assert mesh.axis_count == 2
    # the coincident vertex pairs: one in the trunk, one in the branch
    _, first, counts = np.unique(np.round(mesh.positions, 6), axis=0, return_index=True, return_counts=True)
    keys = {tuple(np.round(v, 6)) for v, c in zip(mesh.positions[first], counts) if c == 2}
    pairs = [np.flatnonzero((np.round(mesh.positions, 6) == k).all(axis=1)) for k in keys]
    assert len(pairs) >= 6 and all(len(q) == 2 and tree.vertex_axis[q[0]] != tree.vertex_axis[q[1]] for q in pairs)
    p = ad.random_params(mesh, 20, seed=4, variation=ad.Variation(bend=(0.1, 0.3), scale=(0.5, 1.5), twist=0.8, taper=0.4))
    pos, _ = ad.deform(mesh, p)
    gap = max(np.abs(pos[:, q[0]] - pos[:, q[1]]).max() for q in pairs)
    assert gap <= 1e-5 * mesh.axis.length, gap
    # a child whose d1 is not zero opens the joint: the test can fail
    p[:, 10:12] = 0.05
    pos, _ = ad.deform(mesh, p)
    assert max(np.abs(pos[:, q[0]] - pos[:, q[1]]).max() for q in pairs) > 1e-3


def test_tree_normals_are_exact(tree):
    """n' = cof(J)·n is perpendicular to J·T (central differences) at points
    strictly inside their axes (no clamp boundary between the samples)."""
    rng = np.random.default_rng(5)
    va = tree.tree.vertex_axis
    offs = rng.uniform(-0.15, 0.15, (2, tree.axis_count, 5, 2))
    offs[:, 1:, 0] = 0
    extra = np.array([[1.2, 0.7, 0.3], [0.8, -0.5, -0.2]])
    v = tree.positions.astype(float)
    n = rng.normal(size=v.shape)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    _, bent, _ = tree_bend(tree.tree, v, n, offs, extra)
    inside = np.ones(len(v), bool)
    for j, axis in enumerate(tree.tree.axes):  # keep vertices away from every clamp boundary on their chain
        t = (v @ axis.matrix[0] - axis.lo) / axis.length
        near = (np.abs(t) < 1e-3) | (np.abs(t - 1) < 1e-3)
        inside &= ~(near & tree.tree.chain[va, j])
    h = 1e-6
    for _ in range(2):
        tan = np.cross(n, rng.normal(size=v.shape))
        tan /= np.linalg.norm(tan, axis=1, keepdims=True)
        jt = (tree_bend(tree.tree, v + h * tan, n, offs, extra)[0] - tree_bend(tree.tree, v - h * tan, n, offs, extra)[0]) / (2 * h)
        cos = np.einsum("nvk,nvk->nv", bent, jt) / np.linalg.norm(jt, axis=-1)
        assert np.abs(cos[:, inside]).max() < 1e-6


def test_random_trees_keep_roots_and_the_trunk_stream(tree):
    p = ad.random_params(tree, 50, seed=7, variation=ad.Variation(bend=(0.05, 0.2, 0.3)))
    assert p.shape == (50, tree_width(10))
    standard, children = split_record(p, 10)
    # every child's bend vanishes where it meets its parent, value and slope (a clamped joint)
    from axialdeform.core.axes import bernstein4

    lengths = np.array([a.length for a in tree.tree.axes[1:]])
    b, db = bernstein4(np.array(tree.tree.anchors[1:]))  # (K-1, 5)
    d = children.reshape(50, 9, 5, 2).astype(np.float64)
    assert (np.abs(np.einsum("ji,njic->njc", b, d)) <= 1e-6 * lengths[None, :, None]).all()
    assert (np.abs(np.einsum("ji,njic->njc", db, d)) <= 1e-5 * lengths[None, :, None]).all()
    assert (np.array(tree.tree.anchors[1:]) < 0.2).all()  # the bundled branches grow from the trunk's line
    # each level its own amplitude (in units of that axis's length): the projection never lengthens
    amp = np.abs(d).max(axis=(0, 2, 3)) / lengths
    assert (amp[:6] <= 0.2 * np.sqrt(5) + 1e-6).all() and (amp[:6] > 0.1).all() and (amp[6:] > amp[:6].max()).all()
    # the trunk's numbers are the plain mesh's for the same seed and options
    plain = ad.random_params(ad.load_mesh("tree"), 50, seed=7, variation=ad.Variation(bend=0.05))
    assert np.array_equal(standard, plain)
    assert np.array_equal(join_record(standard, children), p)


def test_tree_files_round_trip_and_refuse_another_tree(tree, tmp_path):
    p = ad.random_params(tree, 30, seed=1, variation=ad.Variation(bend=(0.05, 0.2), scale=(0.8, 1.2)))
    for name, quantize in (("t.adp", False), ("q.adp", True), ("t.txt", False)):
        path = tmp_path / name
        ad.write_params(path, p, tree, quantize=quantize)
        back = ad.read_params(path, tree)
        bound = ad.core.quantize.quantization_error_bound(p) if quantize else 0
        assert back.shape == p.shape and (np.abs(back - p) <= bound + 1e-12).all()
    text = (tmp_path / "t.txt").read_text()
    assert "a1.d1u" in text and "a9.d5v" in text  # the field names of every axis
    plain = ad.load_mesh("tree")
    with pytest.raises(MeshMismatchError, match="10 axes in a hierarchy"):
        ad.read_params(tmp_path / "t.adp", plain)
    with pytest.raises(MeshMismatchError, match="10 axes\\), but .* has 1 axes"):
        ad.read_params(tmp_path / "t.txt", plain)
    other = ad.load_mesh("tree", axes="parts")  # the same mesh, another hierarchy
    with pytest.raises(MeshMismatchError):
        ad.read_params(tmp_path / "t.adp", other)


def test_bad_trees_and_records_are_refused(tree):
    mesh = ad.load_mesh("tree")
    with pytest.raises(MeshError, match="no part 'root'"):
        mesh.with_axes([{"part": "root"}])
    with pytest.raises(MeshError, match="have no axis"):
        mesh.with_axes([{"part": "trunk"}, {"part": "branch1", "parent": "trunk"}])
    with pytest.raises(MeshError, match="is not an earlier entry"):
        mesh.with_axes([{"part": "trunk"}, {"part": "twig1", "parent": "branch1"}] + TREE_AXES[1:7] + TREE_AXES[8:])
    with pytest.raises(MeshError, match="expected one of 'parts', 'skeleton', 'auto'"):
        mesh.with_axes("limbs")
    with pytest.raises(ParamError, match=r"for a mesh of 10 axes \(10·K \+ 6 numbers an instance\)"):
        ad.deform(tree, np.zeros((1, 16), np.float32))
    bad = np.zeros((1, tree_width(10, 1)), np.float32)  # scale 0
    with pytest.raises(ParamError, match="field s: expected a scale s > 0"):
        ad.deform(tree, bad)
    bad = np.zeros((1, tree_width(10)), np.float32)
    bad[0, 35] = np.nan
    with pytest.raises(ParamError, match="field a3.d3v: expected a finite number"):
        ad.deform(tree, bad)


@pytest.mark.parametrize("blend", [False, True])
def test_bounds_hold_every_tree_vertex(tree, blend):
    """The culling spheres (still and in the wind) and boxes hold every bent vertex; a vertex blending two chains
    moves by a weighed mean of the two, so the bounds of the chains hold it too."""
    from axialdeform.core.bounds import instance_bounds, instance_boxes

    from helpers.models import blended

    tree = blended(tree) if blend else tree
    p = ad.random_params(tree, 40, seed=9, variation=ad.Variation(bend=(0.1, 0.3), scale=(0.5, 2.0), twist=1.0, taper=0.5))
    wind = ad.Wind(direction=(1, 0, 0), strength=0.3, gustiness=0.5)
    pos = ad.bake(tree, p, "cpu", options=ad.RenderOptions(wind=wind, time=2.0))[0]
    c, r = instance_bounds(tree, p, wind=wind)
    assert (np.linalg.norm(pos - c[:, None], axis=-1) <= r[:, None] * (1 + 1e-6)).all()
    lo, hi = instance_boxes(tree, p)
    still = ad.deform(tree, p)[0]
    assert (still >= lo[:, None] - 1e-5).all() and (still <= hi[:, None] + 1e-5).all()


def test_random_trees_in_pieces_are_the_whole(tree):
    from axialdeform.core.variation import iter_random_params

    whole = ad.random_params(tree, 70, seed=11, variation=ad.Variation(bend=(0.05, 0.2), tint=0.3))
    pieces = np.concatenate(list(iter_random_params(tree, 70, 11, chunk=16, variation=ad.Variation(bend=(0.05, 0.2), tint=0.3))))
    assert whole.shape == (70, tree_width(10, 2)) and np.array_equal(whole, pieces)


def test_fit_recovers_trees(tree):
    """The 10·K + 6 (+ 3) numbers back from baked trees: the shapes they give
    match the targets to float32 rounding."""
    p = ad.random_params(tree, 12, seed=3, variation=ad.Variation(bend=(0.05, 0.2, 0.25), tilt=(-0.5, 0.5)))
    shapes = ad.deform(tree, p)[0]
    fit = ad.fit_params(tree, shapes)
    assert fit.params.shape == (12, 106)
    back = ad.deform(tree, fit.params)[0]
    assert np.abs(back - shapes).max() <= 1e-5 * tree.axis.length
    assert fit.max.max() <= 1e-5
    # the extended numbers too: scale, twist and taper about the trunk's axis line
    p = ad.random_params(tree, 6, seed=4, variation=ad.Variation(bend=(0.05, 0.2, 0.25), tilt=(-0.5, 0.5), scale=(0.6, 1.5), twist=0.6,
                                                                 taper=0.4))
    shapes = ad.deform(tree, p)[0]
    fit = ad.fit_params(tree, shapes, extended=True)
    assert fit.params.shape == (6, 109)
    np.testing.assert_allclose(fit.params[:, -3:], p[:, -3:], atol=1e-4)
    assert np.abs(ad.deform(tree, fit.params)[0] - shapes).max() <= 1e-5 * tree.axis.length


def test_fit_recovers_trees_whose_vertices_blend_two_chains(tree):
    """fit_params weighs each axis's Bernstein columns by the vertices' blend weights (AxisTree.weights): a
    blended tree's baked shapes give back numbers that bend it to them."""
    from helpers.models import blended

    mixed = blended(tree)
    p = ad.random_params(mixed, 8, seed=5, variation=ad.Variation(bend=(0.05, 0.2, 0.25), tilt=(-0.5, 0.5)))
    shapes = ad.deform(mixed, p)[0]
    fit = ad.fit_params(mixed, shapes)
    assert np.abs(ad.deform(mixed, fit.params)[0] - shapes).max() <= 1e-5 * tree.axis.length
    assert np.abs(ad.deform(tree, fit.params)[0] - shapes).max() > 1e-3 * tree.axis.length  # the blend mattered


def test_hostile_tree_files_are_refused_in_words(tree, tmp_path):
    import json
    import struct
    import zlib

    import pygltflib

    from axialdeform.core import GltfError, ParamFileError
    from axialdeform.core.io.gltf import read_instanced_glb
    from axialdeform.core.io.params import decode_binary, encode_binary

    p = ad.random_params(tree, 3, seed=1)
    data = bytearray(encode_binary(p, axis=tree))

    def fixed(b):
        b[-4:] = zlib.crc32(bytes(b[:-4])).to_bytes(4, "little")
        return bytes(b)

    bad = bytearray(data)
    bad[28:32] = struct.pack("<I", 65)
    with pytest.raises(ParamFileError, match="axes: expected 1 to 64 axes, found 65"):
        decode_binary(fixed(bad), "t.adp")
    bad = bytearray(data)
    bad[28:32] = struct.pack("<I", 9)  # one axis fewer: the length no longer matches the count
    with pytest.raises(ParamFileError, match="count: the header declares 3 instances"):
        decode_binary(fixed(bad), "t.adp")
    one = bytearray(encode_binary(ad.random_params(ad.load_mesh("stone"), 3, seed=1), axis=ad.load_mesh("stone")))
    one[24] = 4  # "several axes" on a one-axis file
    with pytest.raises(ParamFileError, match="axis: expected 4 \\(several axes\\) exactly when"):
        decode_binary(fixed(one), "s.adp")
    # a GLB whose vertex axes point past the tree
    glb = tmp_path / "t.glb"
    ad.export_glb(glb, tree, p, "instanced")
    g = pygltflib.GLTF2().load(str(glb))
    node = next(n for n in g.nodes if n.extensions)
    bend = node.extensions["AXIALDEFORM_bend"]  # the open extension is what a reader reads
    bend["axes"]["parents"] = [-1] + [5] * 9  # a parent after its child
    g.save(str(tmp_path / "u.glb"))
    with pytest.raises(GltfError, match="u.glb: node .* AXIALDEFORM_bend: axes: parents: expected -1 for axis 0"):
        read_instanced_glb(tmp_path / "u.glb")
    # a file with only this library's extras (before the extension): they are read, and checked
    del node.extensions["AXIALDEFORM_bend"]
    node.extras["axialdeform"]["axes"]["parents"] = [-1] + [5] * 9
    g.save(str(tmp_path / "v.glb"))
    with pytest.raises(GltfError, match="v.glb: extras axes: axes: parents: expected -1 for axis 0"):
        read_instanced_glb(tmp_path / "v.glb")
    assert json.dumps(node.extras["axialdeform"]["count"]) == "3"


@pytest.mark.parametrize("parents", [[-1, 2, 1], [-1, 2, 0], [-1, 5, 0], [-2, 0, 0], [0, 0, 1], [-1, 0.5, 0], "ab",
                                     list(range(-1, 70))])
def test_bad_per_vertex_parents_are_refused_in_words(parents):
    """A cycle, a forward, out-of-range or negative parent, a non-integer, too many axes: a MeshError
    before anything is sized by them (they ended in IndexError)."""
    stone = ad.load_mesh("stone")
    va = (np.arange(stone.vertex_count) % 3).astype(int)
    with pytest.raises(ad.core.MeshError, match="axes: (parents|expected 1 to 64 axes)"):
        stone.with_axes({"vertex_axis": va, "parents": parents})


def test_oriented_frames_of_flat_and_line_meshes():
    """A flat mesh gets the minimum-area rectangle of its plane and its normal (no networkx); points on
    a line are refused in words, naming the mesh."""
    flat = trimesh.Trimesh(vertices=[[0, 0, 0], [2, 0.5, 0], [0, 1, 0], [2, 1.5, 0]], faces=[[0, 1, 2], [1, 3, 2]],
                           process=False)
    frame = ad.load_mesh(flat, axis="oriented").axis.matrix
    assert np.allclose(frame @ frame.T, np.eye(3), atol=1e-9)
    assert np.allclose(np.abs(frame[2]), [0, 0, 1], atol=1e-9)  # the third row is the plane's normal
    line = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]], faces=[[0, 1, 2], [1, 2, 3]],
                           process=False)
    with pytest.raises(ad.core.MeshError, match=r"<Trimesh>: axis: 'oriented' needs points spanning an area"):
        ad.load_mesh(line, axis="oriented")
    card = ad.load_mesh("leafcard", axis="oriented")  # a real flat mesh
    assert card.axis.length > 0


def test_too_many_parts_are_refused_before_any_axis_is_made(tmp_path, monkeypatch):
    """axes='parts' on 300 parts said 'at most 64 axes' only after every part's axis and the whole
    attachment search (minutes); now before the first axis is made."""
    from axialdeform.core import axes as axes_mod

    lines = []
    for k in range(300):
        x, y, b = k % 20, k // 20, 3 * k
        lines.append(f"o part{k}\nv {x} {y} 0\nv {x + 0.5} {y} 0\nv {x} {y + 0.5} 0.2\nf {b + 1} {b + 2} {b + 3}")
    (tmp_path / "p300.obj").write_text("\n".join(lines) + "\n")
    mesh = ad.load_mesh(tmp_path / "p300.obj")
    monkeypatch.setattr(axes_mod, "_axis_of", lambda *a, **k: pytest.fail("an axis was made before the refusal"))
    with pytest.raises(ad.core.MeshError, match="p300.obj: axes='parts': 300 parts, but a mesh has at most 64 axes"):
        mesh.with_axes("parts")


def test_a_blended_vertex_moves_by_both_chains_weighed(tree):
    """AxisTree.blend (docs/method.md, "Blended vertices"): a vertex of axis b blending b1 with weight w moves by
    (1 - w) of b's chain and w of b1's, an axis on both counting fully; w = 0 is the one-chain map exactly."""
    from axialdeform.core.blend import BLEND_STEPS, split_vertex_code

    t = tree.tree
    v = len(t.vertex_axis)
    twig = t.names.index("twig1")  # twig1 <- branch1 <- trunk; branch4 <- trunk
    b1 = t.names.index("branch4")
    w = np.zeros(v)
    w[t.vertex_axis == twig] = 0.3
    blend = np.stack([np.full(v, b1), w], axis=1)
    mixed = dataclasses.replace(tree, _axis=None, tree=AxisTree(t.axes, t.parents, t.vertex_axis, t.names, t.anchors, blend))
    om = mixed.tree.weights[t.vertex_axis == twig][0]
    q = round(0.3 * BLEND_STEPS) / BLEND_STEPS
    assert om[0] == pytest.approx(1.0) and om[twig] == pytest.approx(1 - q) and om[t.names.index("branch1")] == pytest.approx(1 - q)
    assert om[b1] == pytest.approx(q) and np.count_nonzero(om) == 4
    p = ad.random_params(tree, 5, seed=2, variation=ad.Variation(bend=(0.1, 0.3, 0.3)))
    plain, mixed_pos = ad.deform(tree, p)[0], ad.deform(mixed, p)[0]
    on = t.vertex_axis == twig
    assert np.array_equal(plain[:, ~on], mixed_pos[:, ~on])  # no blend, the same numbers to the bit
    # by hand: the twig's chain moved by (1 - q), plus q of branch4's own bend (its chain less the shared trunk)
    keep_b1 = p.copy()
    keep_b1[:, 10:10 * t.count] = 0
    keep_b1[:, 10 * b1:10 * b1 + 10] = p[:, 10 * b1:10 * b1 + 10]
    only_b1 = ad.deform(dataclasses.replace(tree, _axis=None, tree=AxisTree(t.axes, t.parents, np.full(v, b1), t.names, t.anchors)),
                        keep_b1)[0] - ad.deform(dataclasses.replace(tree, _axis=None, tree=AxisTree(
                            t.axes, t.parents, np.zeros(v, int), t.names, t.anchors)), keep_b1)[0]
    trunk_only = p.copy()
    trunk_only[:, 10:10 * t.count] = 0
    base = ad.deform(tree, trunk_only)[0]  # the trunk's bend alone (the same for every vertex's chain)
    want = base + (1 - q) * (plain - base) + q * only_b1
    assert np.abs(mixed_pos[:, on] - want[:, on]).max() <= 1e-6 * tree.axis.length  # float32 positions
    code = mixed.tree.vertex_code
    assert code.dtype == np.float32 and np.all(code[~on] == t.vertex_axis[~on]) and np.all(code < 2 ** 23)
    back_axis, back_blend = split_vertex_code(code)
    assert np.array_equal(back_axis, t.vertex_axis) and np.allclose(back_blend[on, 1], q)


def test_bad_blends_and_codes_are_refused_in_words(tree, tmp_path):
    import pygltflib

    from axialdeform.core import GltfError
    from axialdeform.core.io.glb import AXIS_ATTRIBUTE
    from axialdeform.core.io.gltf import read_instanced_glb

    t = tree.tree
    v = len(t.vertex_axis)
    for blend, expected in [(np.zeros((v, 3)), "expected a \\(v, 2\\) array"), (np.c_[np.full(v, 10.0), np.full(v, 0.5)],
                            "second axes of 0..9"), (np.c_[np.zeros(v), np.full(v, 1.5)], "weights in 0..1"),
                            (np.c_[np.zeros(v), np.full(v, np.nan)], "expected a \\(v, 2\\) array")]:
        with pytest.raises(MeshError, match=expected):
            AxisTree(t.axes, t.parents, t.vertex_axis, t.names, t.anchors, blend)
    glb = tmp_path / "t.glb"
    ad.export_glb(glb, tree, ad.random_params(tree, 3, seed=1), "instanced")
    g = pygltflib.GLTF2().load(str(glb))
    accessor = g.accessors[getattr(g.meshes[0].primitives[0].attributes, AXIS_ATTRIBUTE)]
    view = g.bufferViews[accessor.bufferView]
    blob = bytearray(g.binary_blob())
    start = view.byteOffset + (accessor.byteOffset or 0)
    for value, expected in [(2.0 ** 23, "below 2\\^23"), (1.5, "one whole axis index"), (10 + 4096.0 * 5, "axis indices: expected"),
                            (1 + 64 * 12 + 4096.0 * 5, "second axes of 0..9")]:
        bad = bytearray(blob)
        bad[start:start + 4] = np.float32(value).tobytes()
        g.set_binary_blob(bytes(bad))
        g.save(str(tmp_path / "u.glb"))
        with pytest.raises(GltfError, match=expected):
            read_instanced_glb(tmp_path / "u.glb")

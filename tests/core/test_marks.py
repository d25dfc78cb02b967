"""The marks of an example of the library's records (axialdeform.core.marks): the bend, twist, taper and tint
a recipe drew are learned back, a layer grown from what was learned draws each mark as the example has it
(KS <= 0.1, docs/learn.md "The marks"), and every reader of records hands them over (a tree's records too)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import tomllib
from scipy.spatial import cKDTree
from scipy.stats import ks_2samp

import axialdeform as ad
from axialdeform.core import learn as L
from axialdeform.core.errors import ExampleError
from axialdeform.core.generate import Generate, generate_extent
from axialdeform.core.io.example import read_example
from axialdeform.core.io.mesh import load_mesh
from axialdeform.core.marks import bend_amplitude, learn_marks, offset_differences, standard_records
from axialdeform.core.record import OFFSETS, POSITION, TAPER, TINT, TWIST, join_record
from axialdeform.core.variation import Variation

EXTENT = (0.0, 0.0, 40.0, 40.0)
ROOT = Path(__file__).resolve().parents[2]
DRAWN = {"bend": 0.2, "twist": 0.5, "taper": 0.3, "tint": 0.4, "tint_color": (0.8, 0.6, 0.3), "tint_hue": 0.5,
         "scale": (0.8, 1.2)}


@pytest.fixture(scope="module")
def stone():
    return load_mesh("stone", textures=False)


def _grown(stone, seed: int, **keys) -> np.ndarray:
    return generate_extent(Generate(rate=2.0, seed=seed, **keys), stone, EXTENT).astype(np.float64)


def test_a_recipes_marks_are_learned_back(stone):
    params = _grown(stone, 1, **DRAWN)
    marks = learn_marks(params[:, 16], params[:, 14], standard_records(params))
    keys = marks.recipe(stone)
    assert len(params) > 2500
    assert keys["bend"] == pytest.approx(0.2, rel=0.1)
    assert keys["twist"] == pytest.approx(0.5, rel=0.1) and keys["taper"] == pytest.approx(0.3, rel=0.1)
    assert keys["tint"] == pytest.approx(0.4, abs=0.04) and keys["tint_hue"] == pytest.approx(0.5, abs=0.1)
    assert keys["tint_color"] == pytest.approx([0.8, 0.6, 0.3], abs=0.02)
    one_hue = _grown(stone, 2, **{**DRAWN, "tint_hue": 0.0})
    assert learn_marks(None, None, standard_records(one_hue)).tint[2] < 0.05  # shades of one colour: no hue


def test_a_layer_grown_from_the_learned_marks_draws_them_as_the_example(stone):
    """Each mark's distribution, the example's against a layer grown from what was learned: KS <= 0.1 (the
    offsets as their differences between control points, over the axis length: the shift that keeps the
    anchor in place is the same for both)."""
    example = _grown(stone, 3, **DRAWN)
    keys = learn_marks(example[:, 16], example[:, 14], standard_records(example)).recipe(stone)
    grown = _grown(stone, 4, **{k: tuple(v) if isinstance(v, list) else v for k, v in keys.items()})
    L_ = stone.axis.length
    pairs = [(offset_differences(example[:, OFFSETS]).ravel() / L_, offset_differences(grown[:, OFFSETS]).ravel() / L_),
             (example[:, TWIST], grown[:, TWIST]), (example[:, TAPER], grown[:, TAPER]), (example[:, 16], grown[:, 16])]
    pairs += [(example[:, TINT][:, c], grown[:, TINT][:, c]) for c in range(3)]
    ks = [ks_2samp(a, b).statistic for a, b in pairs]
    assert max(ks) <= 0.1, ks
    # and a layer without the learned bend (the recipe's default 0.1) would not pass: the test can fail
    plain = _grown(stone, 4, **{k: tuple(v) if isinstance(v, list) else v for k, v in keys.items() if k != "bend"})
    assert ks_2samp(pairs[0][0], offset_differences(plain[:, OFFSETS]).ravel() / L_).statistic > 0.1


def test_the_bend_ignores_the_shift_of_the_offsets(stone):
    """random_params' offsets are canonical (zero mean over the five), the generator's keep the anchor in place:
    both give back the amplitude they drew."""
    canonical = ad.random_params(stone, 3000, seed=5, variation=Variation(bend=0.15))
    assert bend_amplitude(canonical[:, OFFSETS]) / stone.axis.length == pytest.approx(0.15, rel=0.05)
    anchored = _grown(stone, 6, bend=0.15)
    assert bend_amplitude(anchored[:, OFFSETS]) / stone.axis.length == pytest.approx(0.15, rel=0.05)


def test_a_trees_records_are_read_at_their_own_columns():
    """A record of K axes has its child axes' offsets between axis 0's offsets and its position: the example's
    places are the positions, not the child offsets (they were read from columns 10..12 before)."""
    rng = np.random.default_rng(0)
    std = np.zeros((60, 22), np.float32)
    std[:, POSITION] = rng.uniform(0, 50, (60, 3))
    std[:, OFFSETS] = rng.uniform(-0.3, 0.3, (60, 10))
    std[:, TINT] = 0.5
    tree = join_record(std, rng.normal(0, 5, (60, 2, 5, 2)))
    assert tree.shape == (60, 42)
    ex = read_example(tree)
    assert np.array_equal(ex.xz, std[:, POSITION][:, [0, 2]].astype(np.float64))
    assert np.array_equal(standard_records(ex.records), std.astype(np.float64))
    with pytest.raises(ExampleError, match=r"<params>: expected records of 10 K \+ 6"):
        read_example(np.zeros((5, 17)))


def test_learn_from_a_parameter_file_writes_the_marks(tmp_path, stone):
    """``learn`` from a parameter file of bent, twisted, tapered, tinted stones: the scene file's recipe has them."""
    params = _grown(stone, 7, **DRAWN).astype(np.float32)
    ad.write_params(tmp_path / "stones.adp", params, mesh=stone)
    layers = ad.learn_layer(tmp_path / "stones.adp", window=EXTENT)
    from axialdeform.core.io.example import write_learned

    write_learned(tmp_path / "out.toml", layers, None, mesh="stone")
    grown = ad.Scene.load(tmp_path / "out.toml").layers[0].params
    assert grown.shape[1] == 22
    assert bend_amplitude(grown[:, OFFSETS]) / stone.axis.length == pytest.approx(0.2, rel=0.1)
    assert np.abs(grown[:, TWIST]).max() == pytest.approx(0.5, rel=0.1)
    assert "offsets within" in (tmp_path / "out.toml").read_text()


def test_learn_reads_the_records_of_this_librarys_gltf(tmp_path, stone):
    params = _grown(stone, 8, **DRAWN).astype(np.float32)
    ad.export_glb(tmp_path / "stones.glb", stone, params, layout="instanced")
    ex = read_example(tmp_path / "stones.glb")
    assert ex.records is not None and ex.records.shape == (len(params), 22)
    assert np.array_equal(ex.records[:, OFFSETS], params[:, OFFSETS].astype(np.float64))
    assert np.allclose(ex.records[:, TINT], params[:, TINT]) and np.allclose(ex.records[:, TWIST], params[:, TWIST])
    marks = L.learn_layers(ex)[0].marks
    assert marks.tint[0] == pytest.approx(0.4, abs=0.04) and marks.twist == pytest.approx(0.5, rel=0.1)


def test_learn_fits_baked_objects_to_the_mesh(tmp_path, stone):
    """A glTF of baked objects (the library's baked export: one node an object, its world vertices) learned with
    ``--fit``: each object's record is fitted to the mesh, and its bend, scale, twist and taper are learned."""
    params = generate_extent(Generate(rate=0.3, seed=9, **{k: v for k, v in DRAWN.items() if "tint" not in k}),
                             stone, EXTENT)
    ad.export_glb(tmp_path / "baked.glb", stone, params, layout="baked")
    out = tmp_path / "out.toml"
    done = subprocess.run([sys.executable, "-m", "axialdeform", "learn", str(tmp_path / "baked.glb"), "--fit", "--mesh",
                           "stone", "-o", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    keys = tomllib.loads(out.read_text())["layer"][0]["generate"]
    assert keys["bend"] == pytest.approx(0.2, rel=0.1) and keys["twist"] == pytest.approx(0.5, rel=0.1)
    assert keys["taper"] == pytest.approx(0.3, rel=0.1) and keys["scale"] == pytest.approx([0.8, 1.2], rel=0.05)
    ex = read_example(tmp_path / "baked.glb", fit=stone)
    # the fitted places are the drawn ones (in the scene's node order), less the shift of the offsets the fit's
    # canonical form moves into them
    near = 2 * DRAWN["bend"] * stone.axis.length
    assert cKDTree(params[:, POSITION][:, [0, 2]]).query(ex.xz)[0].max() < near
    # an editor's duplicates: each object its own bent copy in its node's frame, placed by the node's matrix
    import trimesh

    from axialdeform.core.bake import bake_cpu

    local = params[:5].copy()
    local[:, POSITION] = 0.0
    shapes = bake_cpu(stone, local)[0]
    scene = trimesh.Scene()
    for k, v in enumerate(shapes):
        scene.add_geometry(trimesh.Trimesh(v, stone.faces, process=False), node_name=f"Rock.{k:03d}",
                           transform=trimesh.transformations.translation_matrix(params[k, POSITION]))
    scene.export(tmp_path / "editor.glb")
    ex = read_example(tmp_path / "editor.glb", fit=stone)
    d, at = cKDTree(params[:5, POSITION][:, [0, 2]]).query(ex.xz)
    assert d.max() < near and sorted(at) == list(range(5)) and ex.kind is None
    drawn, fitted = offset_differences(params[at, OFFSETS]), offset_differences(ex.records[:, OFFSETS])
    assert np.abs(fitted - drawn).max() < 1e-3 * stone.axis.length  # the bends, up to the shift the fit leaves out
    with pytest.raises(ExampleError, match=r"editor.glb: object 1 \(node Rock.000\): .* vertices; expected the mesh's"):
        read_example(tmp_path / "editor.glb", fit=load_mesh("leaf", textures=False))
    (tmp_path / "stones.csv").write_text("x,z\n1,2\n3,4\n5,1\n")
    with pytest.raises(ExampleError, match=r"stones.csv: fit: expected a .glb"):
        read_example(tmp_path / "stones.csv", fit=stone)


def test_more_of_a_scene_layer_grows_its_own_trees_bent_level_by_level(tmp_path):
    """``learn SCENE --layer trees`` without ``--mesh``: the learned layer is the layer's own mesh with its axes
    (the forest example's ten-axis tree), each level of the hierarchy bent as the example's (its child axes'
    amplitudes over their lengths), and its objects at the example's own median scale."""
    forest = ROOT / "examples" / "forest" / "forest.toml"
    out = tmp_path / "more.toml"
    done = subprocess.run([sys.executable, "-m", "axialdeform", "learn", str(forest), "--layer", "trees", "--terrain",
                           str(forest), "-o", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    layer = tomllib.loads(out.read_text())["layer"][0]
    assert layer["mesh"] == "tree" and Path(layer["axes"]) == (ROOT / "examples" / "forest" / "tree-axes.toml").resolve()
    assert layer["wind"] is True  # the layer's own keys of its objects
    example = ad.Scene.load(forest).layers[0]
    grown = ad.Scene.load(out).layers[0]
    assert grown.mesh.axis_count == example.mesh.axis_count == 10
    bends = layer["generate"]["bend"]
    assert isinstance(bends, list) and len(bends) == 3 and bends[1] > 2 * bends[0]  # branches bend more than the trunk
    for level in range(3):  # each level's offsets over its axes' lengths, as the example's
        axes = [j for j in range(10) if example.mesh.tree.depth[j] == level]
        spread = [np.sqrt(np.mean([np.mean(offset_differences(_axis_offsets(lay.params, j)) ** 2) / lay.mesh.tree.axes[j].length ** 2
                                   for j in axes])) for lay in (example, grown)]
        assert spread[1] == pytest.approx(spread[0], rel=0.15), (level, spread)
    assert np.median(grown.params[:, -3]) == pytest.approx(np.median(example.params[:, -3]), rel=0.1)  # the scale


def _axis_offsets(params: np.ndarray, j: int) -> np.ndarray:
    """Axis j's ten offsets of records of ten axes (axis 0's first, then the child axes', then the rest)."""
    return params[:, 10 * j:10 * j + 10]


def test_a_trees_instanced_gltf_gives_its_child_axes_bends(tmp_path):
    """The library's instanced glTF of a tree of ten axes carries each child axis's offsets (``_AXIAL_A{k}_*``):
    read back as the records, the marks learn each child axis's amplitude."""
    layer = ad.Scene.load(ROOT / "examples" / "forest" / "forest.toml").layers[0]
    ad.export_glb(tmp_path / "trees.glb", layer.mesh, layer.params[:300], layout="instanced")
    ex = read_example(tmp_path / "trees.glb")
    assert ex.records.shape == (300, 109)  # ten axes' offsets, then the place, the angles, the scale, twist, taper
    assert np.array_equal(ex.records[:, :100], layer.params[:300, :100].astype(np.float64))
    marks = L.learn_layers(ex)[0].marks
    assert len(marks.child_bends) == 9
    assert marks.record_scale == pytest.approx(np.median(layer.params[:300, -3]), rel=1e-5)  # glTF's SCALE, as drawn
    bends = marks.recipe(layer.mesh)["bend"]
    assert bends == pytest.approx([0.04, 0.22, 0.3], rel=0.15)


def test_the_lean_toward_the_grounds_normal_is_learned_back(stone):
    """A recipe's ``align_to_normal`` on hills comes back from the records' turns, and the turn about up with
    the lean undone keeps the recipe's narrow ``yaw``; objects standing upright learn no lean."""
    from helpers import processes as P

    maps, ground = P.ground()
    for align in (0.0, 0.6):
        params = generate_extent(Generate(rate=0.3, seed=3, align_to_normal=align, yaw=(0.5, 2.0)), stone, P.window(), maps)
        lay = L.learn_layers(read_example(params.astype(np.float64), P.window()), ground)[0]
        keys = lay.marks.recipe(stone)
        assert keys["yaw"] == pytest.approx([0.5, 2.0], abs=0.01)
        if align:
            assert keys["align_to_normal"] == pytest.approx(align, abs=0.01)
        else:
            assert "align_to_normal" not in keys


def test_the_lean_of_objects_of_no_finite_turn_is_left_out():
    up = np.array([[0.0, 1.0, 0.0], [np.nan, 1.0, 0.0], [0.0, 0.0, 0.0]])
    normal = np.tile([0.6, 0.8, 0.0], (3, 1))
    assert learn_marks(None, None, None, up, normal).align == 0.0
    assert learn_marks(None, None, None, up, np.tile([0.0, 1.0, 0.0], (3, 1))).align is None  # level ground


def test_more_of_a_scene_layer_stands_as_its_objects_do(tmp_path):
    """``learn SCENE --layer NAME``: the landscape's stones lean toward the ground's normal by 0.8 and stand on
    their centre, and so do the learned layer's; its leaves hang 1 to 7 units above the ground, and, placed
    by a density map the ground's features do not explain, they are learned as no clumps (the clumps' radius
    ran off to millions of units before)."""
    scene = ROOT / "examples" / "landscape" / "landscape.toml"
    got = {}
    for layer in ("stones", "leaves"):
        out = tmp_path / f"{layer}.toml"
        done = subprocess.run([sys.executable, "-m", "axialdeform", "learn", str(scene), "--layer", layer, "--terrain",
                               str(scene), "-o", str(out)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        got[layer] = tomllib.loads(out.read_text())["layer"][0]["generate"]
    assert got["stones"]["align_to_normal"] == pytest.approx(0.8, abs=0.02) and got["stones"]["anchor"] == "center"
    assert got["leaves"]["lift"] == [1.0, 7.0] and "align_to_normal" not in got["leaves"]
    assert "clump_radius" not in got["leaves"]


def test_a_scaled_leaning_objects_turn_and_up():
    """An editor's node: turned by psi about up, then leant by alpha about a level axis, scaled 2, 3, 4 along
    its own x, y, z: its up is the leant y, and its turn psi (the lean undone, the scale taken off)."""
    from axialdeform.core.marks import turn_and_up
    from axialdeform.core.transforms import matrices_from_rotation_vectors

    psi, alpha = np.array([0.3, 2.5, -1.2]), np.array([0.0, 0.4, 1.1])
    axis = np.array([[1.0, 0.0, 0.0], [0.6, 0.0, 0.8], [0.0, 0.0, -1.0]])  # level axes of the lean
    lean = matrices_from_rotation_vectors(axis * alpha[:, None])
    turn = matrices_from_rotation_vectors(np.outer(psi, [0.0, 1.0, 0.0]))
    yaw, up = turn_and_up(lean @ turn @ np.diag([2.0, 3.0, 4.0]))
    assert yaw == pytest.approx(psi, abs=1e-9)
    assert up == pytest.approx(lean[:, :, 1], abs=1e-12)

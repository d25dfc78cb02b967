"""A chosen axis frame through the files and the command line: --axis on
every command that loads a mesh, scene files' ``axis =``, parameter files
that refuse another frame, glTF exports that keep it."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.cli import main
from axialdeform.core.io.gltf import export_scene, read_instanced_glb
from axialdeform.core.scene import load_scene

from conftest import validate_gltf


def _cli(capsys, *args):
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:  # argparse's own refusals: status 2, one usage line
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def diag_obj(tmp_path_factory):
    """A capsule lying diagonally (nobody's axis-aligned model), as an OBJ file."""
    import trimesh

    cap = trimesh.creation.capsule(height=3.0, radius=0.35, count=[16, 16])
    t = trimesh.transformations
    cap.apply_transform(t.rotation_matrix(0.6, [0, 0, 1]) @ t.rotation_matrix(0.5, [0, 1, 0])
                        @ t.rotation_matrix(np.pi / 2, [0, 1, 0]))
    path = tmp_path_factory.mktemp("diag") / "diag.obj"
    cap.export(path)
    return path


def test_the_command_line_carries_the_frame(tmp_path, capsys, diag_obj):
    adp, png = tmp_path / "p.adp", tmp_path / "p.png"
    code, _, err = _cli(capsys, "random", diag_obj, "-n", 12, "--bend", 0.25, "--axis", "oriented", "-o", adp)
    assert code == 0, err
    mesh = ad.load_mesh(diag_obj, axis="oriented")
    length = np.array([0.0, 0.0, 1.0])  # the capsule's own length, turned as the file was
    c, s = np.cos, np.sin
    rz = np.array([[c(0.6), -s(0.6), 0], [s(0.6), c(0.6), 0], [0, 0, 1]])
    ry = np.array([[c(0.5), 0, s(0.5)], [0, 1, 0], [-s(0.5), 0, c(0.5)]])
    ry2 = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]])
    assert abs(mesh.axis.direction @ (rz @ ry @ ry2 @ length)) > 0.999  # bends along its own length
    code, out, _ = _cli(capsys, "info", adp)
    assert code == 0 and "a chosen axis frame (digest" in out
    assert _cli(capsys, "render", diag_obj, adp, "--axis", "oriented", "-o", png, "--size", "160x120")[0] == 0
    # the same file with the auto axis: refused, in one line
    code, _, err = _cli(capsys, "render", diag_obj, adp, "-o", tmp_path / "x.png", "--size", "160x120")
    assert code == 2 and "made for a chosen axis frame" in err and "Traceback" not in err
    glb = tmp_path / "p.glb"
    assert _cli(capsys, "export", diag_obj, adp, "--axis", "oriented", "--instanced", "-o", glb)[0] == 0
    back, params = read_instanced_glb(glb)
    assert back.axis == mesh.axis and np.array_equal(params, ad.read_params(adp, mesh))
    assert _cli(capsys, "export", diag_obj, adp, "--axis", "oriented", "-o", tmp_path / "b.glb")[0] == 0
    for report in validate_gltf(glb, tmp_path / "b.glb"):
        assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]
    # convert keeps the frame it reads; --mesh with --axis records that one
    assert _cli(capsys, "convert", adp, tmp_path / "q.adp", "--quantize")[0] == 0
    assert ad.core.read_param_file(tmp_path / "q.adp").axis.matches(mesh.axis)


@pytest.mark.parametrize("value, words", [
    ("diagonal", "--axis: expected one of auto, x, y, z, oriented or nine numbers"),
    ("1,0,0,0,1,0,0,0", "--axis: expected one of auto, x, y, z, oriented or nine numbers"),
    ("1,0,0,0,1,0,0,0,2", "axis: the frame is not orthogonal"),
])
def test_a_bad_axis_is_one_line_and_exit_2(tmp_path, capsys, value, words):
    out = tmp_path / "x.adp"
    code, _, err = _cli(capsys, "random", "stone", "-n", 3, "--axis", value, "-o", out)
    assert code == 2 and words in err and "Traceback" not in err and not out.exists()


def test_scene_files_name_each_layers_axis(tmp_path, capsys, diag_obj):
    turn = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    rod = ad.load_mesh(diag_obj, axis="oriented")
    ad.write_params(tmp_path / "rods.adp", ad.random_params(rod, 9, seed=3, variation=ad.Variation(bend=0.2), spacing=4.0), rod)
    stone = ad.load_mesh("stone", axis=turn)
    ad.write_params(tmp_path / "stones.adp", ad.random_params(stone, 9, seed=4, spacing=3.0), stone)
    body = f"""
        [[layer]]
        name = "rods"
        mesh = "{diag_obj.as_posix()}"
        axis = "oriented"
        params = "rods.adp"

        [[layer]]
        name = "stones"
        mesh = "stone"
        axis = {turn}
        params = "stones.adp"
        """
    path = tmp_path / "s.toml"
    path.write_text(textwrap.dedent(body).lstrip("\n"))
    scene = load_scene(path)
    rods, stones = scene.layers
    assert rods.mesh.axis.framed and rods.mesh.axis == ad.load_mesh(diag_obj, axis="oriented").axis
    # a permutation matrix is an axis-aligned axis: z here, drawn by the index path
    assert not stones.mesh.axis.framed and stones.mesh.axis.index == 2
    png = tmp_path / "s.png"
    assert _cli(capsys, "render", path, "-o", png, "--size", "160x120")[0] == 0
    code, _, err = _cli(capsys, "render", path, "--axis", "x", "-o", png)
    assert code == 2 and "--axis/--axes: a scene file" in err
    path.write_text(textwrap.dedent(body).lstrip("\n").replace('axis = "oriented"', 'axis = [1, 2]'))
    code, _, err = _cli(capsys, "render", path, "-o", png)
    assert code == 2 and "s.toml" in err and "axis" in err and "expected 9 finite number(s)" in err
    path.write_text(textwrap.dedent(body).lstrip("\n").replace('axis = "oriented"', 'axis = "sideways"'))
    code, _, err = _cli(capsys, "render", path, "-o", png)
    assert code == 2 and "s.toml" in err and "axis: expected one of auto, x, y, z, oriented" in err


FOREST = __import__("pathlib").Path(__file__).resolve().parents[2] / "examples" / "forest"


def test_trees_through_the_command_line_and_gltf(tmp_path, capsys):
    """--axes on random, info, render and export; the instanced GLB keeps the
    tree (its frames, parents, each vertex's axis) and every child axis's
    numbers; the Khronos validator finds no error."""
    axes = FOREST / "tree-axes.toml"
    adp = tmp_path / "trees.adp"
    code, _, err = _cli(capsys, "random", "tree", "-n", 40, "--axes", axes, "--bend", 0.05, "--placement", "disc",
                        "--spacing", 3, "-o", adp)
    assert code == 0, err
    tree = ad.load_mesh("tree", axes=axes)
    params = ad.read_params(adp, tree)
    assert params.shape == (40, 106)
    code, out, _ = _cli(capsys, "info", adp)
    assert code == 0 and "10 axes in a hierarchy" in out and "106 numbers an instance (plain, 10 axes" in out
    png = tmp_path / "t.png"
    assert _cli(capsys, "render", "tree", adp, "--axes", axes, "-o", png, "--size", "160x120")[0] == 0
    code, _, err = _cli(capsys, "render", "tree", adp, "-o", png, "--size", "160x120")  # without its axes (said before
    # the output that exists: an input's error comes first)
    assert code == 2 and "10 axes in a hierarchy" in err and "Traceback" not in err
    glb, baked = tmp_path / "t.glb", tmp_path / "b.glb"
    assert _cli(capsys, "export", "tree", adp, "--axes", axes, "--instanced", "-o", glb)[0] == 0
    assert _cli(capsys, "export", "tree", adp, "--axes", axes, "-o", baked)[0] == 0
    back, back_params = read_instanced_glb(glb)
    assert back.tree.digest == tree.tree.digest and np.array_equal(back_params, params)
    for report in validate_gltf(glb, baked):
        assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]
    bad = tmp_path / "bad.toml"
    bad.write_text('[[axis]]\npart = "trunk"\nlimb = 1\n')
    code, _, err = _cli(capsys, "random", "tree", "-n", 3, "--axes", bad, "-o", tmp_path / "x.adp")
    assert code == 2 and "bad.toml: axis 1: expected a table with a part name" in err


def test_the_forest_scene_loads_its_tree(tmp_path):
    scene = load_scene(FOREST / "forest.toml", scale_counts=0.05)
    glb = tmp_path / "forest.glb"
    export_scene(glb, scene, "instanced")  # the forest as an instanced GLB: the tree comes back
    back, params = read_instanced_glb(glb, node="trees")
    assert back.tree.digest == scene.layers[0].mesh.tree.digest and np.array_equal(params, scene.layers[0].params)
    assert validate_gltf(glb)[0]["issues"]["numErrors"] == 0
    trees = scene.layers[0]
    assert trees.mesh.axis_count == 10 and trees.params.shape[1] == 109 and trees.wind  # scaled: 10·K + 9
    from axialdeform.core.axes import bernstein4
    from axialdeform.core.record import split_record

    _, children = split_record(trees.params, 10)
    b, _ = bernstein4(np.array(trees.mesh.tree.anchors[1:]))
    at_joint = np.einsum("ji,njic->njc", b, children.reshape(len(children), 9, 5, 2).astype(np.float64))
    assert np.abs(at_joint).max() < 1e-6 and np.abs(children).max() > 0  # joints stay closed, the rest bends

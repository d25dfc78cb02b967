"""Trees from other people's files: anchored joints where a leaf crosses its stem,
the parts picked at load, the hierarchy the heuristic finds, and what it says.

The synthetic palm below is built like third-party palms (a trunk, fronds whose axes start
beyond the trunk and cross its top, a flat island and a water plane around it)."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

import axialdeform as ad
from axialdeform.core.axes import bernstein4
from axialdeform.core.material import AssetWarning

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))
import joint_gap  # noqa: E402 - tools/ is not a package

from helpers.models import PALM, palm_file  # noqa: E402


@pytest.fixture(scope="module")
def palm(tmp_path_factory):
    return palm_file(tmp_path_factory.mktemp("palm") / "palm.glb")


def test_parts_are_picked_when_loading(palm):
    whole = ad.load_mesh(palm)
    assert set(whole.part_names) == {*PALM, "île", "water"}
    tree = ad.load_mesh(palm, parts=PALM)
    assert tree.part_names == tuple(p for p in whole.part_names if p in PALM)  # the file's order and names
    # everything after is the palm's: its axis, its bounds (no 60-unit water plane), its fingerprint
    assert tree.axis.length < 5 and whole.axis.length > 50
    assert np.ptp(tree.positions, axis=0).max() < 6
    assert tree.fingerprint != whole.fingerprint
    # the dropped parts' vertices are gone; the kept ones keep their file order
    assert tree.vertex_count < whole.vertex_count
    keep = np.isin(whole.source_index, tree.source_index)
    assert np.array_equal(whole.positions[keep], tree.positions)
    with pytest.raises(ad.core.MeshError, match=r"palm.glb: parts: no part 'fronds'; expected some of 'trunk'"):
        ad.load_mesh(palm, parts=["trunk", "fronds"])


def test_the_heuristic_finds_the_trunk_and_attaches_every_frond_to_it(palm):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tree = ad.load_mesh(palm, axes="parts", axis="oriented").tree
    said = " ".join(str(w.message) for w in caught if issubclass(w.category, AssetWarning))
    assert "'île', 'water' look like ground or water" in said and "parts=" in said
    names, parents = tree.names, tree.parents
    assert names[0] == "trunk"  # not the island, not the water plane (the largest parts)
    for k, name in enumerate(names):
        if name in PALM[1:]:
            assert names[parents[k]] == "trunk", tree.describe()  # never a sibling frond
    clean = ad.load_mesh(palm, parts=PALM, axes="parts", axis="oriented").tree
    assert clean.names[0] == "trunk" and all(clean.names[p] == "trunk" for p in clean.parents[1:])
    assert "@ t=0." in clean.describe()  # the fronds' anchors, said


def test_auto_keeps_a_palms_crossing_fronds_as_its_parts(palm, tmp_path, monkeypatch):
    """axes="auto" on a palm whose fronds cross its crown: the whole model's skeleton hangs each frond at the
    crossing and splits it there, but no frond branches alone -- the parts are the limbs, each frond one axis
    on the trunk (as axes="parts"), from a cold cache and again from the cache."""
    monkeypatch.setenv("AXIALDEFORM_CACHE", str(tmp_path / "cache"))
    mesh = ad.load_mesh(palm, parts=PALM)
    assert mesh.with_axes("skeleton").tree.count > len(PALM)  # the fronds split where they cross
    for _ in range(2):
        tree = mesh.with_axes("auto").tree
        assert tree.names == mesh.with_axes("parts").tree.names and tree.count == len(PALM)
        assert all(tree.names[q] == "trunk" for q in tree.parents[1:]), tree.describe()


def test_a_crossing_leafs_joint_stays_closed(palm):
    """The fronds' axes cross the trunk's top: the anchor is there (not at t = 0), and at a frond
    bend of 0.3 the frond vertices within twice the trunk's radius of the joint move by their own
    bend at most 0.25 of that radius (median); with d1 = 0 alone they moved several times more."""
    mesh = ad.load_mesh(palm, parts=PALM, axes="parts", axis="oriented")
    tree = mesh.tree
    assert all(0.2 < t < 0.5 for t in tree.anchors[1:])  # the crown is a third of the way along
    rows = joint_gap.joint_figures(mesh, 0.3, 200, seed=4)
    medians_now = [r["after"][0] for r in rows if r["vertices"]]
    medians_before = [r["before"][0] for r in rows if r["vertices"]]
    assert len(medians_now) == 7
    assert max(medians_now) <= 0.25, rows
    assert np.median(medians_before) > 2 * np.median(medians_now), rows
    # the variation itself: every child's curve is zero, with zero slope, at its anchor
    p = ad.random_params(mesh, 30, seed=2, variation=ad.Variation(bend=(0.05, 0.3)))
    children = np.asarray(p)[:, 10:10 * tree.count].reshape(30, tree.count - 1, 5, 2).astype(np.float64)
    b, db = bernstein4(np.array(tree.anchors[1:]))
    assert np.abs(np.einsum("ji,njic->njc", b, children)).max() < 1e-6 * mesh.axis.length
    assert np.abs(np.einsum("ji,njic->njc", db, children)).max() < 1e-5 * mesh.axis.length


def test_an_axes_file_may_give_the_anchor(palm, tmp_path):
    spec = tmp_path / "palm.toml"
    spec.write_text('[[axis]]\npart = "trunk"\naxis = "y"\n' + "".join(
        f'[[axis]]\npart = "{name}"\nparent = "trunk"\naxis = "oriented"\nanchor = 0.4\n' for name in PALM[1:]),
        encoding="utf-8")
    tree = ad.load_mesh(palm, parts=PALM, axes=spec).tree
    assert tree.anchors[1:] == (0.4,) * 7
    spec.write_text('[[axis]]\npart = "trunk"\n[[axis]]\npart = "frond1"\nparent = "trunk"\nanchor = 1.5\n')
    with pytest.raises(ad.core.MeshError, match=r"frond1\): anchor: expected t in 0..1"):
        ad.load_mesh(palm, parts=["trunk", "frond1"], axes=spec)


def test_the_command_line_picks_parts_and_says_the_tree(palm, tmp_path):
    def cli(*args):
        return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True,
                              timeout=300, cwd=tmp_path)

    parts = ",".join(PALM)
    out = cli("info", palm, "--parts", parts, "--axes", "parts", "--axis", "oriented")
    assert out.returncode == 0, out.stderr
    assert "parts:     8:" in out.stdout and "axes:      8 axes (trunk, " in out.stdout and "<- trunk @ t=" in out.stdout
    made = cli("random", palm, "--parts", parts, "--axes", "parts", "--axis", "oriented", "-n", 12, "--bend",
               "0.05,0.3", "-o", "palms.adp")
    assert made.returncode == 0, made.stderr
    # the parameters belong to the palm without its scenery: said in one line, naming the flag
    wrong = cli("render", palm, "palms.adp", "-o", "x.png", "--size", "64x48")
    assert wrong.returncode == 2 and "--parts" in wrong.stderr and len(wrong.stderr.strip().splitlines()) == 1
    again = cli("render", palm, "palms.adp", "--parts", parts, "-o", "x.png", "--size", "64x48")
    assert "--axes" in again.stderr and again.returncode == 2  # the tree must be given again too
    ok = cli("render", palm, "palms.adp", "--parts", parts, "--axes", "parts", "--axis", "oriented", "-o", "x.png",
             "--size", "64x48")
    assert ok.returncode == 0, ok.stderr


def test_a_scene_layer_keeps_only_its_parts(palm, tmp_path):
    mesh = ad.load_mesh(palm, parts=PALM, axes="parts", axis="oriented")
    ad.write_params(tmp_path / "palms.adp", ad.random_params(mesh, 5, seed=1, variation=ad.Variation(bend=(0.05, 0.3))), mesh)
    names = ", ".join(f'"{n}"' for n in PALM)
    (tmp_path / "s.toml").write_text(f'[[layer]]\nname = "palms"\nmesh = "{palm.as_posix()}"\nparts = [{names}]\n'
                                     'axes = "parts"\naxis = "oriented"\nparams = "palms.adp"\n', encoding="utf-8")
    scene = ad.Scene.load(tmp_path / "s.toml")  # the file's parameters fit the palm without its scenery
    assert scene.layers[0].mesh.part_names == mesh.part_names and scene.count == 5
    (tmp_path / "t.toml").write_text(f'[[layer]]\nname = "p"\nmesh = "{palm.as_posix()}"\nparts = "trunk"\n'
                                     'params = "x.adp"\n', encoding="utf-8")
    with pytest.raises(ad.core.SceneError, match=r"t.toml:4: key 'parts': expected an array of part names"):
        ad.Scene.load(tmp_path / "t.toml")


def test_the_gpu_bends_an_anchored_palm_as_the_cpu_does(ctx, palm):
    """GPU == CPU for the anchored variation (the page and the npm module draw the same numbers
    through the same shader, tested on their own against the CPU)."""
    from axialdeform.gl.renderer import AxialRenderer

    mesh = ad.load_mesh(palm, parts=PALM, axes="parts", axis="oriented")
    p = ad.random_params(mesh, 24, seed=3, variation=ad.Variation(bend=(0.05, 0.3)), placement="disc", spacing=4.0)
    with AxialRenderer(ctx, mesh, p) as r:
        gpu = r.capture()
    cpu = ad.deform(mesh, p)
    reach = max(1.0, float(np.abs(np.asarray(p)[:, 10 * mesh.axis_count:10 * mesh.axis_count + 3]).max()) / mesh.axis.length)
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * mesh.axis.length * reach
    assert np.abs(gpu[1] - cpu[1]).max() <= 1e-4


def test_fronds_droop_toward_the_worlds_down(palm):
    """droop= (--droop, a scatter recipe's droop): every child axis sags toward the world's down
    beside the isotropic bend, clamped at its joint; the trunk and the other numbers stay."""
    mesh = ad.load_mesh(palm, parts=PALM, axes="parts", axis="oriented")
    plain = ad.random_params(mesh, 40, seed=1, variation=ad.Variation(bend=(0.03, 0.05)), placement="disc", spacing=5.0)
    droop = ad.random_params(mesh, 40, seed=1, variation=ad.Variation(bend=(0.03, 0.05), droop=0.3), placement="disc", spacing=5.0)
    k = mesh.axis_count
    assert np.array_equal(np.asarray(plain)[:, :10], np.asarray(droop)[:, :10])  # the trunk's own bend
    a, _ = ad.deform(mesh, plain)
    b, _ = ad.deform(mesh, droop)
    fronds = mesh.tree.vertex_axis > 0
    tips = fronds & (np.linalg.norm(mesh.positions[:, [0, 2]], axis=1) > 1.0)  # the frond ends, away from the crown
    assert (b[:, tips, 1] - a[:, tips, 1]).mean() < -0.1 * mesh.tree.axes[1].length  # down, in the world
    assert np.abs(b[:, ~fronds] - a[:, ~fronds]).max() < 1e-6
    d = np.asarray(droop)[:, 10:10 * k].reshape(40, k - 1, 5, 2).astype(np.float64)
    bb, db = bernstein4(np.array(mesh.tree.anchors[1:]))
    assert np.abs(np.einsum("ji,njic->njc", bb, d)).max() < 1e-5 and np.abs(np.einsum("ji,njic->njc", db, d)).max() < 1e-4
    with pytest.raises(ad.core.ParamError, match="droop: expected a fraction"):
        ad.Variation(droop=-1)


def test_the_wind_leaves_the_joints_where_they_are(ctx, palm, tmp_path):
    """The wind pushes a child axis on the control polygon of (t - t_a)^2: zero, with zero slope,
    at its anchor (a frond crossing the crown sways, the crown stays closed); on the GPU as on the
    CPU; the anchors travel in the instanced GLB (AXIALDEFORM_bend axes.anchors)."""
    from axialdeform.core.axes import sag_weights
    from axialdeform.core.io.gltf import export_glb, read_instanced_glb
    from axialdeform.core.wind import tree_wind_offsets
    from axialdeform.gl.renderer import AxialRenderer

    mesh = ad.load_mesh(palm, parts=PALM, axes="parts", axis="oriented")
    tree = mesh.tree
    p = ad.random_params(mesh, 16, seed=5, variation=ad.Variation(bend=(0.05, 0.3)), placement="disc", spacing=4.0)
    wind = ad.Wind(direction=(1.0, 0.0, 0.4), strength=0.3, gustiness=0.5)
    pushed = tree_wind_offsets(wind, tree, p, time=0.7)  # (n, K, 5, 2)
    b, db = bernstein4(np.array(tree.anchors[1:]))
    assert np.abs(np.einsum("ji,njic->njc", b, pushed[:, 1:])).max() < 1e-9
    assert np.abs(np.einsum("ji,njic->njc", db, pushed[:, 1:])).max() < 1e-9
    assert np.abs(pushed[:, 1:]).max() > 0.05 * tree.axes[1].length  # and it does push
    assert np.array_equal(sag_weights(0.0), [0.0, 0.0, 1 / 6, 0.5, 1.0])  # root-anchored: the wind as before
    with AxialRenderer(ctx, mesh, p, options=ad.RenderOptions(wind=wind)) as r:
        gpu = r.capture(time=0.7)
    cpu = ad.deform(mesh, ad.core.wind.apply_wind(wind, tree, p, 0.7))
    reach = max(1.0, float(np.abs(np.asarray(p)[:, 10 * tree.count:10 * tree.count + 3]).max()) / mesh.axis.length)
    assert np.abs(gpu[0] - cpu[0]).max() <= 1e-5 * mesh.axis.length * reach
    path = export_glb(tmp_path / "palms.glb", mesh, p, "instanced")
    back, _ = read_instanced_glb(path)
    assert np.allclose(back.tree.anchors, tree.anchors)


def test_a_single_axis_droops_too():
    """droop on a mesh of one axis (a blade, a leaf, a stone lying along x): its far end sags toward
    the world's down; random_params keeps the offsets' zero mean, scatter keeps the point it stands on."""
    stone = ad.load_mesh("stone")  # its axis lies along x: the down direction is across it
    flat = ad.random_params(stone, 100, seed=1, variation=ad.Variation(bend=0.0, tilt=(0.0, 0.0)))
    sag = ad.random_params(stone, 100, seed=1, variation=ad.Variation(bend=0.0, tilt=(0.0, 0.0), droop=0.3))
    a, _ = ad.deform(stone, flat)
    b, _ = ad.deform(stone, sag)
    t = stone.axis.parameter(stone.positions)
    tip, base = t > 0.9, t < 0.1
    assert (b[:, tip, 1] - a[:, tip, 1]).mean() - (b[:, base, 1] - a[:, base, 1]).mean() < -0.2 * stone.axis.length
    offsets = np.asarray(sag)[:, :10].reshape(100, 5, 2)
    assert np.abs(offsets.mean(axis=1)).max() < 1e-6  # canonical, as random_params' offsets always are
    ground = trimesh.creation.box(extents=[20.0, 0.1, 20.0])
    ground.apply_translation([0.0, -0.05, 0.0])
    still = ad.scatter(ground, stone, 30, seed=2, variation=ad.Variation(bend=0.0), placement=ad.core.Placement(min_distance=2.0))
    drooped = ad.scatter(ground, stone, 30, seed=2, variation=ad.Variation(bend=0.0, droop=0.3),
                         placement=ad.core.Placement(min_distance=2.0))
    c, _ = ad.deform(stone, still)
    d, _ = ad.deform(stone, drooped)
    assert np.allclose(np.asarray(still)[:, 10:], np.asarray(drooped)[:, 10:])  # the same places and turns
    assert (d[:, tip, 1] - c[:, tip, 1]).mean() < -0.1 * stone.axis.length  # the far end sags

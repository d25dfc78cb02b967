"""``axialdeform learn``: an example in the files users have becomes a scene file that grows the same kind of
scenery, on its own terrain and on another; bad input is one line and exit status 2."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import tomllib

import axialdeform as ad
from axialdeform.core.record import POSITION

from helpers import processes as P

ROOT = Path(__file__).resolve().parents[2]


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def _survey(path, xz, size=None, kind=None):
    cols = ["x", "z"] + (["size"] if size is not None else []) + (["kind"] if kind is not None else [])
    rows = [",".join(cols)]
    for i, (x, z) in enumerate(xz):
        rows.append(",".join([f"{x:.4f}", f"{z:.4f}"] + ([f"{size[i]:.4f}"] if size is not None else [])
                             + ([kind[i]] if kind is not None else [])))
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    folder = tmp_path_factory.mktemp("survey")
    scene = P.write_terrain(folder)
    _, g = P.ground()
    rng = np.random.default_rng(7)
    xz = P.inhomogeneous(rng, g, {"slope": 0.12}, 0.02)
    kind = np.where(rng.uniform(size=len(xz)) < 0.25, "birch", "oak")
    size = rng.lognormal(0, 0.25, len(xz))
    return folder, scene, _survey(folder / "plot.csv", xz, size, kind), xz, kind


def test_learn_writes_a_scene_that_grows_each_kind_as_often(survey, tmp_path):
    folder, scene, csv, xz, kind = survey
    out = tmp_path / "learned.toml"
    res = run("learn", csv, "--terrain", scene, "-o", out, "--size", "0.5", "--window=-100,-60,100,60")
    assert res.returncode == 0, res.stderr
    assert "oak:" in res.stdout and "birch:" in res.stdout
    data = tomllib.loads(out.read_text())
    assert [lay["name"] for lay in data["layer"]] == ["oak", "birch"]
    assert "extent" not in data["layer"][0]["generate"]  # a generated layer covers its height map
    built = ad.Scene.load(out)
    for lay in built.layers:
        n = int((kind == lay.name).sum())
        assert len(lay.params) == pytest.approx(n, rel=0.12), lay.name
        p = lay.params[:, POSITION]
        assert p[:, 0].min() >= -100 and p[:, 0].max() <= 100 and p[:, 2].min() >= -60 and p[:, 2].max() <= 60
    assert (tmp_path / "learned-oak-density.png").is_file()


def test_errors_poisson_keeps_the_ground_a_clumped_example_shows(survey, tmp_path):
    """--errors: the default tests a clumped example's ground terms against its clumps (none kept for a Matern
    pattern without a real effect); poisson keeps what the example shows; anything else is one line, exit 2."""
    folder, scene, *_ = survey
    csv = _survey(tmp_path / "clumps.csv", P.matern_cluster(np.random.default_rng(0), 0.01, 3.0, 8))
    said = {}
    for errors in ("clumps", "poisson"):
        out = tmp_path / f"{errors}.toml"
        res = run("learn", csv, "--terrain", scene, "-o", out, "--errors", errors, "--window=-100,-60,100,60")
        assert res.returncode == 0, res.stderr
        said[errors] = res.stdout
    assert "log rate = " in said["clumps"] and "spacing: cluster" in said["clumps"]
    assert re.search(r"log rate = [-0-9.e]+;", said["clumps"])  # no term
    assert not re.search(r"log rate = [-0-9.e]+;", said["poisson"])  # terms
    bad = run("learn", csv, "--terrain", scene, "-o", tmp_path / "x.toml", "--errors", "strict")
    assert bad.returncode == 2 and "--errors" in bad.stderr and "Traceback" not in bad.stderr


def test_apply_to_another_terrain(survey, tmp_path):
    folder, scene, csv, xz, kind = survey
    other = P.write_terrain(tmp_path, P.hills(phase=0.4), "other")
    out = tmp_path / "there.toml"
    res = run("learn", csv, "--terrain", scene, "--apply-to", other, "-o", out, "--features", "slope")
    assert res.returncode == 0, res.stderr
    data = tomllib.loads(out.read_text())
    assert data["terrain"]["heightmap"].endswith("other.png")
    built = ad.Scene.load(out)
    _, g_b = P.ground(P.hills(phase=0.4))
    slope = g_b.at(built.layers[0].params[:, POSITION][:, [0, 2]].astype(float), ["slope"])[:, 0]
    cut = np.median(g_b.grids["slope"])
    assert (slope > cut).sum() > 1.5 * (slope <= cut).sum()  # steeper ground, more trees: as in the example


def test_learn_from_a_parameter_file_a_gltf_scene_and_a_scene_layer(tmp_path):
    import trimesh

    stone = ad.load_mesh("stone")
    rng = np.random.default_rng(3)
    params = ad.random_params(stone, 400, seed=2)
    params[:, POSITION] = np.stack([rng.uniform(0, 40, 400), np.zeros(400), rng.uniform(0, 30, 400)], 1)
    ad.write_params(tmp_path / "p.adp", params, stone)
    ad.export_glb(tmp_path / "instanced.glb", stone, params, "instanced")
    editor = trimesh.Scene()  # one node an object, as an editor exports a hand-placed patch
    for i, (x, _, z) in enumerate(params[:, POSITION]):
        editor.add_geometry(trimesh.creation.box((0.3, 0.3, 0.3)), node_name=f"rock{i}",
                            transform=trimesh.transformations.translation_matrix((x, 0.0, z)))
    editor.export(tmp_path / "editor.glb")
    _foreign_instanced(tmp_path / "foreign.glb", params[:, POSITION])
    (tmp_path / "scene.toml").write_text('[[layer]]\nname = "rocks"\nmesh = "stone"\nparams = "p.adp"\n')
    for src, extra in (("p.adp", ()), ("instanced.glb", ()), ("editor.glb", ()), ("foreign.glb", ()),
                       ("scene.toml", ("--layer", "rocks"))):
        out = tmp_path / f"{src}.toml"
        res = run("learn", tmp_path / src, "-o", out, "--window", "0,0,40,30", "--mesh", "stone", *extra)
        assert res.returncode == 0, (src, res.stderr)
        assert "layer: learned from 400 objects" in res.stdout, (src, res.stdout)
        gen = tomllib.loads(out.read_text())["layer"][0]["generate"]
        assert gen["extent"] == [0.0, 0.0, 40.0, 30.0]
        assert len(ad.Scene.load(out).layers[0].params) == pytest.approx(400, rel=0.15)
    res = run("learn", tmp_path / "scene.toml", "-o", tmp_path / "x.toml", "--layer", "trees")
    assert res.returncode == 2 and "layer: expected one of rocks (--layer NAME), found 'trees'" in res.stderr


def test_a_gltf_scene_of_two_kinds_learns_a_layer_each(tmp_path):
    """An editor's scene of pines and birches (``Pine.001``, ``Birch.002``, ...: the node names of duplicates):
    one learned layer a kind, each grown as often as its kind stands in the scene."""
    import trimesh

    rng = np.random.default_rng(4)
    editor = trimesh.Scene()
    for i in range(600):
        kind = "Pine" if i % 4 else "Birch"  # three pines to a birch
        x, z = rng.uniform(0, 40), rng.uniform(0, 30)
        editor.add_geometry(trimesh.creation.box((0.3, 0.3, 0.3)), node_name=f"{kind}.{i:03d}",
                            transform=trimesh.transformations.translation_matrix((x, 0.0, z)))
    editor.export(tmp_path / "two.glb")
    res = run("learn", tmp_path / "two.glb", "-o", tmp_path / "two.toml", "--window", "0,0,40,30", "--mesh", "stone")
    assert res.returncode == 0, res.stderr
    layers = {layer.name: len(layer.params) for layer in ad.Scene.load(tmp_path / "two.toml").layers}
    assert set(layers) == {"Pine", "Birch"}, layers
    assert layers["Pine"] == pytest.approx(450, rel=0.15) and layers["Birch"] == pytest.approx(150, rel=0.25), layers


def _foreign_instanced(path, positions):
    """A GLB of one triangle instanced by EXT_mesh_gpu_instancing with TRANSLATION alone, under a parent node
    that moves it up 2 (as other tools write them)."""
    import pygltflib

    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    t = np.asarray(positions, np.float32).tobytes()
    g = pygltflib.GLTF2(
        scene=0, scenes=[pygltflib.Scene(nodes=[0])],
        nodes=[pygltflib.Node(translation=[0.0, 2.0, 0.0], children=[1]),
               pygltflib.Node(mesh=0, extensions={"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 1}}})],
        meshes=[pygltflib.Mesh(primitives=[pygltflib.Primitive(attributes=pygltflib.Attributes(POSITION=0))])],
        accessors=[pygltflib.Accessor(bufferView=0, componentType=5126, count=3, type="VEC3", min=[0, 0, 0], max=[1, 1, 0]),
                   pygltflib.Accessor(bufferView=1, componentType=5126, count=len(positions), type="VEC3")],
        bufferViews=[pygltflib.BufferView(buffer=0, byteOffset=0, byteLength=len(tri)),
                     pygltflib.BufferView(buffer=0, byteOffset=len(tri), byteLength=len(t))],
        buffers=[pygltflib.Buffer(byteLength=len(tri) + len(t))], extensionsUsed=["EXT_mesh_gpu_instancing"])
    g.set_binary_blob(tri + t)
    g.save(str(path))


@pytest.mark.parametrize("rows, message", [
    ("x,z\n1,2\n3,abc\n", r"plot\.csv: row 3: column 'z': expected a finite number, found 'abc'"),
    ("a,b\n1,2\n", r"plot\.csv: header: expected columns x and z"),
    ("x,z,size\n1,2,0\n", r"plot\.csv: row 2: column 'size': expected a number > 0"),
    ("x,z\n", r"plot\.csv: no rows after the header"),
    ("x,z\n1,nan\n", r"row 2: column 'z': expected a finite number"),
])
def test_bad_examples_are_one_line_and_exit_2(tmp_path, rows, message):
    (tmp_path / "plot.csv").write_text(rows)
    res = run("learn", tmp_path / "plot.csv", "-o", tmp_path / "o.toml")
    assert res.returncode == 2 and "Traceback" not in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and re.search(message, res.stderr), res.stderr
    assert not (tmp_path / "o.toml").exists()


def test_outputs_and_terrains_are_checked_before_anything_is_written(survey, tmp_path):
    folder, scene, csv, xz, kind = survey
    res = run("learn", csv, "-o", tmp_path / "w.toml", "--window", "0,0,-1,1")
    assert res.returncode == 2 and "argument --window: expected x0,z0,x1,z1 with x1 > x0" in res.stderr, res.stderr
    (tmp_path / "o.toml").write_text("keep")
    res = run("learn", csv, "--terrain", scene, "-o", tmp_path / "o.toml")
    assert res.returncode == 2 and "exists; refusing to replace it" in res.stderr
    assert (tmp_path / "o.toml").read_text() == "keep" and not list(tmp_path.glob("*.png"))
    res = run("learn", csv, "--terrain", scene, "-o", csv, "--overwrite")
    assert res.returncode == 2 and "is the input file" in res.stderr
    flat = tmp_path / "flat.toml"
    flat.write_text('[camera]\nfov = 30.0\n')
    res = run("learn", csv, "--terrain", flat, "-o", tmp_path / "x.toml")
    assert res.returncode == 2 and "terrain: expected a [terrain] with a heightmap" in res.stderr
    res = run("learn", csv, "--terrain", scene, "-o", tmp_path / "x.toml", "--features", "water")
    assert res.returncode == 2 and "water needs a mask" in res.stderr


def test_a_generated_layer_without_extent_covers_its_height_map_and_needs_one_on_flat_ground(tmp_path):
    scene = P.write_terrain(tmp_path)
    text = scene.read_text() + '[[layer]]\nname = "s"\nmesh = "stone"\n[layer.generate]\nrate = 0.01\ntile = 40.0\n'
    scene.write_text(text)
    p = ad.Scene.load(scene).layers[0].params[:, POSITION]
    assert p[:, 0].min() < -90 and p[:, 0].max() > 90 and p[:, 2].min() < -50 and p[:, 2].max() > 50
    flat = tmp_path / "flat.toml"
    flat.write_text('[[layer]]\nname = "s"\nmesh = "stone"\n[layer.generate]\nrate = 0.01\n')
    from axialdeform.core import SceneError

    with pytest.raises(SceneError, match=r"needs an extent .*\(on a height-map terrain it covers the terrain\)"):
        ad.Scene.load(flat)


def test_hostile_examples_are_refused_in_one_line(tmp_path):
    rows = "x,z,kind\n" + "".join(f"{i % 10},{i // 10},k{i}\n" for i in range(100))  # 100 kinds
    (tmp_path / "many.csv").write_text(rows)
    res = run("learn", tmp_path / "many.csv", "-o", tmp_path / "o.toml")
    assert res.returncode == 2 and "kind: expected at most 64 kinds (one layer each), found 100" in res.stderr, res.stderr
    import pygltflib

    g = pygltflib.GLTF2(scene=0, scenes=[pygltflib.Scene(nodes=[0])], nodes=[pygltflib.Node(children=[0])])
    g.save(str(tmp_path / "loop.glb"))  # a node its own child
    res = run("learn", tmp_path / "loop.glb", "-o", tmp_path / "o.toml")
    assert res.returncode == 2 and "node 0: expected each node once in the scene's tree" in res.stderr, res.stderr
    g = pygltflib.GLTF2(scene=5, scenes=[pygltflib.Scene(nodes=[0])], nodes=[pygltflib.Node(mesh=0)])  # no scene 5
    g.save(str(tmp_path / "odd.glb"))
    res = run("learn", tmp_path / "odd.glb", "-o", tmp_path / "o.toml")
    assert res.returncode == 2 and "not a glTF scene of placed objects this reader understands" in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and not (tmp_path / "o.toml").exists()


def test_kinds_that_read_alike_get_layers_of_their_own(tmp_path):
    rng = np.random.default_rng(1)
    xz = rng.uniform(0, 20, (300, 2))
    _survey(tmp_path / "two.csv", xz, kind=np.where(np.arange(300) % 2, "red oak", "red_oak"))
    res = run("learn", tmp_path / "two.csv", "-o", tmp_path / "o.toml", "--window", "0,0,20,20")
    assert res.returncode == 0, res.stderr
    names = [lay["name"] for lay in tomllib.loads((tmp_path / "o.toml").read_text())["layer"]]
    assert names == ["red_oak-0", "red_oak-1"] and len(list(tmp_path.glob("o-*-density.png"))) == 2


def test_tools_learn_gltf_compares_a_gltf_scene_on_its_ground_mesh(tmp_path, capsys):
    """tools/learn_gltf.py (docs/learn.md, "A public glTF scene"): the ground glTF's vertices in the scene's frame
    (its node's translation applied), sampled into a height map centred on the origin, the objects moved into
    it; both comparisons (the whole scene, a random half against the other) printed."""
    import trimesh

    sys.path.insert(0, str(ROOT / "tools"))
    import learn_gltf

    x, z = np.meshgrid(np.linspace(0, 60, 31), np.linspace(0, 40, 21))
    y = 0.2 * x + 0.05 * z  # a tilted plane, moved by its node
    faces = [[j * 31 + i, (j + 1) * 31 + i, j * 31 + i + 1] for j in range(20) for i in range(30)]
    ground = trimesh.Trimesh(np.stack([x.ravel(), y.ravel(), z.ravel()], 1), faces + [[f[1], f[1] + 1, f[2]] for f in faces],
                             process=False)
    scene = trimesh.Scene()
    scene.add_geometry(ground, node_name="ground", transform=trimesh.transformations.translation_matrix((100.0, 5.0, -20.0)))
    scene.export(tmp_path / "ground.glb")
    points = learn_gltf.ground_points(tmp_path / "ground.glb")
    assert points[:, 0].min() == pytest.approx(100) and points[:, 2].max() == pytest.approx(20)
    assert points[:, 1].min() == pytest.approx(5) and points[:, 1].max() == pytest.approx(5 + 12 + 2)
    toml, shift = learn_gltf.terrain(points, tmp_path, 64)
    assert np.allclose(shift, (-130, 0)) and "extent = [60.0, 40.0]" in toml.read_text()
    rng = np.random.default_rng(4)
    xz = np.stack([rng.uniform(101, 159, 300), rng.uniform(-19, 19, 300)], 1)
    _foreign_instanced(tmp_path / "rocks.glb", np.stack([xz[:, 0], np.zeros(300), xz[:, 1]], 1))
    assert learn_gltf.main([str(tmp_path / "rocks.glb"), "--ground", str(tmp_path / "ground.glb"), "--sims", "3",
                            "--grid", "64", "--out", str(tmp_path / "run"), "--calibrate", "1", "--halves", "1"]) == 0
    out = capsys.readouterr().out.splitlines()
    rows = [r for r in out if r.startswith("| rocks.glb")]
    assert len(rows) == 5 and rows[0].split("|")[2].strip() == "300", rows
    # the random half's row: the learned half's own quartile counts against the other half's, a figure of its own
    head = [h.strip() for h in next(r for r in out if r.startswith("| plot | objects")).split("|")]
    own = float(rows[1].split("|")[head.index("worst quartile of the learned half itself")])
    assert 0.0 < own < 1.0 and rows[0].split("|")[head.index("worst quartile of the learned half itself")].strip() == ""
    assert "1 patterns grown from what was learned, whole" in rows[2] and "(the other half compared)" in rows[3]
    calibrated = [h.strip() for h in next(r for r in out if r.startswith("| plot | total ratio")).split("|")]
    place = [r.split("|")[calibrated.index("the example's figures: as far off or farther")].strip() for r in rows[2:4]]
    assert all(re.fullmatch(r"total [01]/1, quartiles [01]/1, L [01]/1, Diggle [01]/1", t) for t in place), place
    assert "1 random halves, each learned and the other compared, both ways (2)" in rows[4]


def test_fit_and_the_records_refuse_what_they_cannot_read(tmp_path):
    """``--fit`` fits one node an object: instances of EXT_mesh_gpu_instancing, a table, a missing mesh are
    refused in one line, exit 2; a node whose record attributes have the wrong shape too."""
    xz = np.random.default_rng(1).uniform(0, 10, (20, 2))
    _foreign_instanced(tmp_path / "rocks.glb", np.stack([xz[:, 0], np.zeros(20), xz[:, 1]], 1))
    (tmp_path / "plot.csv").write_text("x,z\n" + "".join(f"{a},{b}\n" for a, b in xz))
    for args, message in (((tmp_path / "rocks.glb", "--fit"), r"rocks\.glb: object 1 \(node .*\): an instance of "
                                                              r"EXT_mesh_gpu_instancing; fit expects one node an object"),
                          ((tmp_path / "plot.csv", "--fit"), r"plot\.csv: fit: expected a \.glb"),
                          ((tmp_path / "rocks.glb", "--fit", "--mesh", tmp_path / "none.obj"), r"none\.obj: no such mesh file")):
        res = run("learn", *args, "-o", tmp_path / "o.toml")
        assert res.returncode == 2 and "Traceback" not in res.stderr, res.stderr
        assert len(res.stderr.strip().splitlines()) == 1 and re.search(message, res.stderr), res.stderr
    import pygltflib

    g = pygltflib.GLTF2().load(str(tmp_path / "rocks.glb"))  # the library's offsets, one number short an instance
    blob = g.binary_blob()
    d = np.zeros((20, 3), np.float32).tobytes()
    g.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(d)))
    g.accessors.append(pygltflib.Accessor(bufferView=len(g.bufferViews) - 1, componentType=5126, count=20, type="VEC3"))
    a = len(g.accessors) - 1
    g.nodes[1].extensions["EXT_mesh_gpu_instancing"]["attributes"].update(_AXIAL_D12=a, _AXIAL_D34=a, _AXIAL_D5=a)
    g.buffers[0].byteLength = len(blob) + len(d)
    g.set_binary_blob(blob + d)
    g.save(str(tmp_path / "odd.glb"))
    res = run("learn", tmp_path / "odd.glb", "-o", tmp_path / "o.toml")
    assert res.returncode == 2 and "Traceback" not in res.stderr, res.stderr
    assert re.search(r"odd\.glb: node .*: _AXIAL_D12: expected VEC4, found 3 components", res.stderr), res.stderr


def test_a_gltf_scenes_own_ground_is_no_object(tmp_path):
    """An editor's export of a patch holds its ground beside the pines (a flat box 100 x 80): the ground is no
    object and no kind of its own, and its footprint is the example's ground (the window), in a .glb and in a
    text .gltf.  The library's own instanced export of the landscape (its terrain a node beside the layers'):
    four layers, not five, each with the marks of its records (the terrain, a node without records, hid them)."""
    import trimesh

    from axialdeform.core.io.example import read_example

    rng = np.random.default_rng(5)
    editor = trimesh.Scene()
    editor.add_geometry(trimesh.creation.box((100.0, 0.2, 80.0)), node_name="Ground")
    for i in range(300):
        editor.add_geometry(trimesh.creation.box((0.5, 3.0, 0.5)), node_name=f"Pine.{i:03d}",
                            transform=trimesh.transformations.translation_matrix((rng.uniform(-45, 45), 1.5, rng.uniform(-35, 35))))
    editor.export(tmp_path / "patch.glb")
    editor.export(tmp_path / "patch.gltf")
    for name in ("patch.glb", "patch.gltf"):
        ex = read_example(tmp_path / name)
        assert len(ex.xz) == 300 and ex.kind is None, name
        assert ex.window == pytest.approx((-50.0, -40.0, 50.0, 40.0)), name
    res = run("learn", tmp_path / "patch.glb", "-o", tmp_path / "patch.toml", "--mesh", "stone")
    assert res.returncode == 0 and "layer: learned from 300 objects" in res.stdout, res.stderr
    alone = trimesh.Scene()
    alone.add_geometry(trimesh.creation.box((100.0, 0.2, 80.0)), node_name="Ground")
    alone.export(tmp_path / "alone.glb")
    res = run("learn", tmp_path / "alone.glb", "-o", tmp_path / "alone.toml")
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1
    assert "no placed objects beside the ground: every node (Ground) covers a quarter of the scene" in res.stderr
    land = tmp_path / "land.glb"
    assert run("export", ROOT / "examples" / "landscape" / "landscape.toml", "--instanced", "-o", land).returncode == 0
    ex = read_example(land)
    assert sorted(set(ex.kind)) == ["grass", "leaves", "stones", "trunks"] and ex.records is not None


def test_which_nodes_are_the_ground():
    """A flat box over most of the scene is ground; as wide a box that is taller than wide (a great tree's
    crown) is not, nor an instance (a point), nor a node of no bounds (NaN: an empty mesh)."""
    from axialdeform.core.io.example_gltf import ground_nodes

    nan = np.full((2, 3), np.nan)
    boxes = np.array([[[-50, 0, -40], [50, 1, 40]],  # the ground
                      [[-30, 0, -30], [30, 70, 30]],  # a crown as wide as much of the scene, taller than wide
                      [[10, 0, 10], [10, 0, 10]],  # an instance
                      nan, [[0, 0, 0], [1, 3, 1]]], np.float64)
    assert ground_nodes(boxes).tolist() == [True, False, False, False, False]

"""The AXIALDEFORM_bend glTF extension (docs/gltf/AXIALDEFORM_bend): every instanced export
carries it, it validates against its JSON schema, the Khronos validator reports 0 errors, and
it holds what a loader needs (the axis, a tree's axes, the numbers per instance)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import jsonschema
import numpy as np
import pygltflib
import pytest

import axialdeform as ad
from axialdeform.core.io.gltf import BEND_EXTENSION, INSTANCING

from conftest import validate_gltf

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "docs" / "gltf" / "AXIALDEFORM_bend" / "schema" / "node.AXIALDEFORM_bend.schema.json")
                    .read_text())
TREE_AXES = ROOT / "examples" / "forest" / "tree-axes.toml"


def cli(*args):
    r = subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r


CASES = {
    "stone16": ("stone", [], []),
    "framed19": ("stone", ["--axis", "oriented"], ["--twist", 0.5, "--taper", 0.2, "--scale", "0.8:1.2"]),
    "leaves22": ("leafcard", [], ["--tint", 0.3]),
    "tree": ("tree", ["--axes", TREE_AXES], []),
}


def bend_objects(glb: Path) -> list[dict]:
    g = pygltflib.GLTF2().load(str(glb))
    assert BEND_EXTENSION in g.extensionsUsed and BEND_EXTENSION not in (g.extensionsRequired or [])
    return [(n, n.extensions[BEND_EXTENSION]) for n in g.nodes if BEND_EXTENSION in (n.extensions or {})]


@pytest.mark.parametrize("case", CASES)
def test_every_instanced_export_carries_a_valid_extension(tmp_path, case):
    mesh, axis, opts = CASES[case]
    adp, glb = tmp_path / "p.adp", tmp_path / "p.glb"
    cli("random", mesh, *axis, "-n", 7, "--seed", 1, *opts, "-o", adp)
    cli("export", mesh, adp, *axis, "--instanced", "-o", glb)
    [(node, ext)] = bend_objects(glb)
    jsonschema.validate(ext, SCHEMA)
    assert INSTANCING in node.extensions  # always beside the instancing
    base = ad.load_mesh(mesh, **({axis[0].lstrip("-"): str(axis[1])} if axis else {}))
    params = ad.read_params(adp, mesh=base)
    assert ext["numbersPerInstance"] == params.shape[1]
    a = base.axis
    assert np.allclose(ext["axis"]["frame"], a.matrix) and ext["axis"]["lo"] == a.lo and ext["axis"]["length"] == a.length
    assert ext["axis"]["center"] == list(a.line) and ext["fingerprint"] == base.fingerprint.hex()
    if base.tree is not None:
        assert ext["axes"]["count"] == base.tree.count == 10 and ext["axes"]["parents"] == list(base.tree.parents)
    else:
        assert "axes" not in ext
    [report] = validate_gltf(glb)
    assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]


def test_a_scene_file_export_has_the_extension_on_every_layer(tmp_path):
    glb = tmp_path / "scene.glb"
    cli("export", ROOT / "examples" / "forest" / "forest.toml", "--instanced", "-o", glb)
    found = bend_objects(glb)
    assert found and all(jsonschema.validate(ext, SCHEMA) is None for _n, ext in found)
    assert validate_gltf(glb)[0]["issues"]["numErrors"] == 0


def test_the_schema_refuses_what_a_loader_could_not_use():
    good = {"numbersPerInstance": 16, "axis": {"frame": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "lo": -1.0, "length": 2.0,
                                               "center": [0.0, 0.0]}}
    jsonschema.validate(good, SCHEMA)
    for bad in ({**good, "numbersPerInstance": 3}, {**good, "axis": {**good["axis"], "length": 0}},
                {**good, "axis": {**good["axis"], "frame": [[1, 0, 0]]}}, {"axis": good["axis"]},
                {**good, "fingerprint": "xyz"}):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(bad, SCHEMA)


def _spec_only_glb(path: Path, ext_change=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """A GLB written from docs/gltf/AXIALDEFORM_bend alone (pygltflib and numpy, no axialdeform): a
    box lying diagonally (30 degrees about z), its framed axis, 5 instances; no extras."""
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    frame = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    local = np.array([[x, y, z] for x in (0.0, 4.0) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    positions = (local @ frame).astype(np.float32)  # rows: local coordinates back to model space
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                      [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], dtype=np.uint32)
    rng = np.random.default_rng(3)
    n = 5
    offsets = rng.uniform(-0.3, 0.3, (n, 10)).astype(np.float32)
    translation = rng.uniform(-5, 5, (n, 3)).astype(np.float32)
    angles = np.zeros((n, 3), dtype=np.float32)
    rotation = np.tile(np.array([0, 0, 0, 1], dtype=np.float32), (n, 1))
    arrays = [(positions, "VEC3"), (faces.reshape(-1), "SCALAR"), (translation, "VEC3"), (rotation, "VEC4"),
              (offsets[:, :4].copy(), "VEC4"), (offsets[:, 4:8].copy(), "VEC4"), (offsets[:, 8:].copy(), "VEC2"),
              (angles, "VEC3")]
    blob, views, accessors = b"", [], []
    for k, (a, kind) in enumerate(arrays):
        data = a.tobytes()
        views.append(pygltflib.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(data)))
        acc = pygltflib.Accessor(bufferView=k, componentType=5125 if a.dtype == np.uint32 else 5126,
                                 count=len(a), type=kind)
        if k == 0:
            acc.min, acc.max = positions.min(axis=0).tolist(), positions.max(axis=0).tolist()
        accessors.append(acc)
        blob += data + b"\0" * (-len(data) % 4)
    ext = {"numbersPerInstance": 16, "axis": {"frame": frame.tolist(), "lo": 0.0, "length": 4.0, "center": [0.0, 0.0]}}
    if ext_change:
        ext_change(ext)
    names = ["TRANSLATION", "ROTATION", "_AXIAL_D12", "_AXIAL_D34", "_AXIAL_D5", "_AXIAL_ANGLES"]
    gltf = pygltflib.GLTF2(
        scene=0, scenes=[pygltflib.Scene(nodes=[0])], buffers=[pygltflib.Buffer(byteLength=len(blob))],
        bufferViews=views, accessors=accessors,
        meshes=[pygltflib.Mesh(primitives=[pygltflib.Primitive(attributes=pygltflib.Attributes(POSITION=0),
                                                               indices=1, mode=4)])],
        nodes=[pygltflib.Node(mesh=0, extensions={INSTANCING: {"attributes": {k: 2 + i for i, k in enumerate(names)}},
                                                  BEND_EXTENSION: ext})],
        extensionsUsed=[INSTANCING, BEND_EXTENSION])
    gltf.set_binary_blob(blob)
    gltf.save_binary(str(path))
    params = np.concatenate([offsets, translation, angles], axis=1)
    return positions, faces, params, ext


def test_python_reads_a_file_written_from_the_extensions_spec_alone(tmp_path):
    """No extras: the bend is read from AXIALDEFORM_bend (the frame, lo, length, axis line) and the
    instances bend as axialdeform bends the same mesh in the same frame."""
    from axialdeform.core.io.gltf import read_instanced_glb

    positions, faces, params, ext = _spec_only_glb(tmp_path / "spec.glb")
    mesh, got = read_instanced_glb(tmp_path / "spec.glb")
    assert np.array_equal(np.asarray(got), params)
    assert mesh.axis.framed and np.allclose(mesh.axis.matrix, ext["axis"]["frame"])
    assert (mesh.axis.lo, mesh.axis.length) == (0.0, 4.0) and np.allclose(mesh.axis.line, (0.0, 0.0))
    ours = ad.core.BaseMesh(positions, ad.core.mesh.area_weighted_normals(positions, faces), faces).with_axis(
        np.asarray(ext["axis"]["frame"]))
    want, _ = ad.deform(ours, params)
    bent, _ = ad.deform(mesh, got)
    assert np.abs(bent - want).max() < 1e-5 * 4.0


@pytest.mark.parametrize("change,words", [
    (lambda e: e["axis"]["frame"][2].__setitem__(2, "nan"), "axis frame: expected 3 finite number"),
    (lambda e: e["axis"].__setitem__("frame", [[1, 0, 0], [1, 0, 0], [0, 0, 1]]), "axis frame: the frame is not orthogonal"),
    (lambda e: e["axis"].__setitem__("length", 0.0), "axis length: expected 1 finite positive number"),
    (lambda e: e["axis"].__setitem__("center", [0.0]), "axis center: expected 2 finite number"),
    (lambda e: e["axis"].__setitem__("center", "0,0"), "axis center: expected 2 finite number"),
    (lambda e: e.__setitem__("fingerprint", 12345), "fingerprint: expected 64 lower-case hex digits"),
    (lambda e: e.__setitem__("numbersPerInstance", 19), "numbersPerInstance: 19, but the instance attributes hold 16"),
    (lambda e: e.__setitem__("numbersPerInstance", 17), "numbersPerInstance: expected 16, 19 or 22"),
    (lambda e: e.__setitem__("numbersPerInstance", 26), "numbersPerInstance 26 is 2 axes an instance, but the extension has no axes"),
    (lambda e: e.__setitem__("axis", None), "axis: expected an object"),
])
def test_a_broken_extension_is_refused_naming_the_field(tmp_path, change, words):
    from axialdeform.core.io.gltf import read_instanced_glb

    _spec_only_glb(tmp_path / "bad.glb", change)
    with pytest.raises(ad.core.GltfError, match="bad.glb: node .*AXIALDEFORM_bend: " + words.replace("(", r"\(")):
        read_instanced_glb(tmp_path / "bad.glb")


def test_a_negative_accessor_count_and_a_numeric_fingerprint_are_refused_in_words(tmp_path):
    from axialdeform.core.io.gltf import read_instanced_glb

    _spec_only_glb(tmp_path / "n.glb")
    g = pygltflib.GLTF2().load(str(tmp_path / "n.glb"))
    g.accessors[2].count = -3  # TRANSLATION
    g.save(str(tmp_path / "neg.glb"))
    with pytest.raises(ad.core.GltfError, match=r"neg.glb: TRANSLATION: accessor 2 count: expected a whole number"):
        read_instanced_glb(tmp_path / "neg.glb")
    g = pygltflib.GLTF2().load(str(tmp_path / "n.glb"))
    del g.nodes[0].extensions[BEND_EXTENSION]  # a file of this library's extras only
    g.nodes[0].extras = {"axialdeform": {"mesh_fingerprint": 12345}}
    g.save(str(tmp_path / "fp.glb"))
    with pytest.raises(ad.core.GltfError, match="fp.glb: extras mesh_fingerprint: expected a hex string"):
        read_instanced_glb(tmp_path / "fp.glb")


CASES_FILE = ROOT / "js" / "test" / "cases" / "bend-cases.json"


@pytest.mark.parametrize("case", json.loads(CASES_FILE.read_text())["cases"], ids=lambda c: "/".join(map(str, c["path"])))
def test_both_readers_refuse_the_shared_corpus_of_broken_extensions(tmp_path, case):
    """The same broken AXIALDEFORM_bend objects the npm module's node tests refuse (js/test/cases):
    Python refuses each too, naming the same field."""
    from axialdeform.core.io.gltf import read_instanced_glb

    def change(ext):
        at = ext
        for key in case["path"][:-1]:
            at = at[key]
        if case.get("delete"):
            del at[case["path"][-1]]
        else:
            at[case["path"][-1]] = case["value"]

    _spec_only_glb(tmp_path / "bad.glb", change)
    with pytest.raises(ad.core.GltfError) as info:
        read_instanced_glb(tmp_path / "bad.glb")
    assert "AXIALDEFORM_bend: " in str(info.value) and case["expect"] in str(info.value), str(info.value)


def test_a_node_with_more_than_64_axes_worth_of_attributes_is_refused_before_reading_them(tmp_path, monkeypatch):
    from axialdeform.core.io import gltf_read

    _spec_only_glb(tmp_path / "n.glb")
    g = pygltflib.GLTF2().load(str(tmp_path / "n.glb"))
    attrs = g.nodes[0].extensions[INSTANCING]["attributes"]
    for j in range(1, 100):  # 99 child axes, every attribute the same (small) accessor
        attrs.update({f"_AXIAL_A{j}_D12": 4, f"_AXIAL_A{j}_D34": 5, f"_AXIAL_A{j}_D5": 6})
    g.save(str(tmp_path / "many.glb"))
    monkeypatch.setattr(gltf_read, "read_accessor", lambda *a: pytest.fail("an accessor was read before the refusal"))
    with pytest.raises(ad.core.GltfError, match="many.glb: EXT_mesh_gpu_instancing attributes: .* expected at most 64"):
        gltf_read.read_instanced_glb(tmp_path / "many.glb")


# ------------------------------------- found by tools/fuzz_specs.py (both readers, the tree specs)


def test_fuzz_both_readers_of_the_extension_and_the_tree_specs_briefly(tmp_path):
    """200 corrupted instanced GLBs through Python's reader and the npm plugin (same verdict for each
    file: both draw it or both refuse it in words), 200 corrupted tree specs; in a fresh process
    (the fuzzer forks, and this one may hold GL contexts)."""
    proc = subprocess.run([sys.executable, str(ROOT / "tools" / "fuzz_specs.py"), "--cases", "200", "--seed", "5",
                           "--node", "--keep", str(tmp_path)], capture_output=True, text=True, timeout=600,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    assert "Python read_instanced_glb: 200 files" in out and "npm AxialGLTFPlugin: 200 files" in out, out
    assert "the two readers differ on 0" in out and "fuzz trees: 200 cases" in out, out
    for line in (ln for ln in out.splitlines() if ln.startswith("fuzz")):
        assert "crash 0, garbage 0, hang 0, memory 0" in line, out


def test_what_the_fuzzer_found_is_refused_in_words(tmp_path):
    """Each was a crash, a wrong number or a disagreement of the two readers before its fix:
    pygltflib read a bufferView "0" as 0 (three does not), a negative
    byteOffset read the bytes before the view, an unaligned one made three throw a RangeError, a
    TOML table as an axis frame a TypeError, a missing TRANSLATION was refused though
    EXT_mesh_gpu_instancing makes it optional."""
    from axialdeform.core.io.gltf import read_instanced_glb

    sys.path.insert(0, str(ROOT / "tools"))
    import fuzz_specs  # its GLB splitter and joiner: the JSON exactly as written, no pygltflib between

    def corrupt(name, change):
        _spec_only_glb(tmp_path / "ok.glb")
        doc, blob = fuzz_specs.split_glb((tmp_path / "ok.glb").read_bytes())
        change(doc)
        (tmp_path / name).write_bytes(fuzz_specs.join_glb(doc, blob))
        return tmp_path / name

    with pytest.raises(ad.core.GltfError, match=r"str.glb: _AXIAL_D12: accessor 4 bufferView: expected a whole number, found '4'"):
        read_instanced_glb(corrupt("str.glb", lambda d: d["accessors"][4].update(bufferView="4")))
    with pytest.raises(ad.core.GltfError, match=r"byteOffset: expected whole numbers >= 0"):
        read_instanced_glb(corrupt("neg.glb", lambda d: d["accessors"][5].update(byteOffset=-4)))
    with pytest.raises(ad.core.GltfError, match=r"byteOffset: expected a multiple of 4"):
        read_instanced_glb(corrupt("odd.glb", lambda d: d["accessors"][5].update(byteOffset=2)))
    with pytest.raises(ad.core.GltfError, match=r"_AXIAL_D12: expected VEC4, found 3 components"):
        read_instanced_glb(corrupt("type.glb", lambda d: d["accessors"][4].update(type="VEC3")))
    no_t = corrupt("no-t.glb", lambda d: d["nodes"][0]["extensions"][INSTANCING]["attributes"].pop("TRANSLATION"))
    mesh, params = read_instanced_glb(no_t)
    assert np.array_equal(np.asarray(params)[:, 10:13], np.zeros((5, 3)))
    (tmp_path / "ax.toml").write_text('[[axis]]\npart = "trunk"\n[[axis]]\npart = "branch1"\nparent = "trunk"\n'
                                      'axis = {a = 1}\n')
    with pytest.raises(ad.core.MeshError, match=r"ax.toml: axis 2 \(branch1\): axis: expected a frame name or nine"):
        ad.load_mesh("tree", axes=tmp_path / "ax.toml")


def test_a_generated_scene_export_carries_the_recipe_validator_clean(tmp_path):
    """export SCENE.toml --generated: each generated layer's node holds its recipe, the generator's numbers and
    its ground maps (schema-valid), a small fallback of instances (the tile at the extent's centre, bent as
    the Python library makes it), and the file is clean for the Khronos validator."""
    from axialdeform.core.generate import generate_tiles, recipe_uniforms, tiles_around
    from axialdeform.core.io.gltf import read_instanced_glb

    scene_dir = tmp_path / "s"
    scene_dir.mkdir()
    for f in ("terrain.png", "stone_density.png", "grass.obj"):
        (scene_dir / f).write_bytes((ROOT / "examples" / "landscape" / f).read_bytes())
    (scene_dir / "hills.toml").write_text("""
[terrain]
heightmap = "terrain.png"
height_scale = 6.0
extent = [40.0, 30.0]
[[layer]]
name = "stones"
mesh = "stone"
[layer.generate]
rate = 1.2
tile = 8.0
min_distance = 0.4
seed = 4
scale = [0.2, 0.45]
density = "stone_density.png"
altitude = [0.0, 2.5]
extent = [-20, -15, 20, 15]
[[layer]]
name = "grass"
mesh = "grass.obj"
[layer.generate]
rate = 3.0
tile = 8.0
tint = 0.5
extent = [-20, -15, 20, 15]
""")
    glb = tmp_path / "hills.glb"
    cli("export", scene_dir / "hills.toml", "--generated", "-o", glb)
    found = dict((n.name, ext) for n, ext in bend_objects(glb))
    assert set(found) == {"stones", "grass"}
    scene = ad.Scene.load(scene_dir / "hills.toml")
    g = pygltflib.GLTF2().load(str(glb))
    for layer in scene.layers:
        ext = found[layer.name]
        jsonschema.validate(ext, SCHEMA)
        gen = ext["generate"]
        assert gen["uniforms"] == json.loads(json.dumps(recipe_uniforms(layer.generate.generate, layer.mesh,
                                                                         layer.generate.maps)))
        assert gen["recipe"]["rate"] == layer.generate.generate.rate and gen["recipe"]["reach"] == layer.generate.reach
        assert ("heights" in gen) and (("density" in gen) == (layer.name == "stones"))
        acc = g.accessors[gen["heights"]["accessor"]]
        assert acc.count == gen["heights"]["cols"] * gen["heights"]["rows"] and acc.type == "SCALAR"
        # the fallback: the first tile near the extent's centre that keeps any, as the library makes it
        _mesh, fallback = read_instanced_glb(glb, node=layer.name, fallback=True)
        tiles = tiles_around(layer.generate.generate, 0.0, 0.0, layer.generate.reach)
        first = next(p for t in tiles if len(p := generate_tiles(layer.generate.generate, layer.mesh, [t],
                                                                   layer.generate.maps)))
        assert 0 < len(fallback) == len(first) < len(layer.params)
        assert np.allclose(fallback, first, atol=1e-6)
    [report] = validate_gltf(glb)
    assert report["issues"]["numErrors"] == 0 and report["issues"]["numWarnings"] == 0, report["issues"]["messages"][:5]
    # a layer of trees: its child-axis table travels as an accessor too (schema-valid, validator-clean)
    (scene_dir / "trees.toml").write_text(f"""
[[layer]]
name = "trees"
mesh = "tree"
axes = "{(ROOT / 'examples' / 'forest' / 'tree-axes.toml').as_posix()}"
[layer.generate]
rate = 0.02
tile = 16.0
bend = [0.03, 0.25]
extent = [-16, -16, 16, 16]
""")
    cli("export", scene_dir / "trees.toml", "--generated", "-o", tmp_path / "trees.glb")
    [(_n, ext)] = bend_objects(tmp_path / "trees.glb")
    jsonschema.validate(ext, SCHEMA)
    assert ext["generate"]["children"]["rows"] == 9 and ext["generate"]["children"]["cols"] == 26
    assert validate_gltf(tmp_path / "trees.glb")[0]["issues"]["numErrors"] == 0
    r = subprocess.run([sys.executable, "-m", "axialdeform", "export", "stone", "--generated", "-o", str(tmp_path / "x.glb")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "--generated writes a scene file's generated layers" in r.stderr, r.stderr
    r = subprocess.run([sys.executable, "-m", "axialdeform", "export", str(ROOT / "examples" / "forest" / "forest.toml"),
                        "--generated", "-o", str(tmp_path / "x.glb")], capture_output=True, text=True)
    assert r.returncode == 2 and "this scene has none" in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "x.glb").exists()

"""The Blender add-on (blender/axialdeform_blender), checked in Blender itself: ``bpy`` from the package
index in its own environment (``.venv-blender``, made by the README's test command: bpy pins a numpy
the rest of the suite does not use), driven by ``bl_checks.py`` in a subprocess.  Geometry Nodes must
bend every instance as ``ad.deform`` does, export back exactly, and render what ``render`` draws."""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.io.gltf_read import read_instanced_glb
from axialdeform.core.transforms import angles_from_matrices, rotation_matrices
from axialdeform.core.wind import apply_wind

from helpers.models import blended

ROOT = Path(__file__).resolve().parents[2]
CHECKS = Path(__file__).with_name("bl_checks.py")

pytestmark = pytest.mark.slow


def blender_python() -> str:
    """The Python with ``bpy``: $AXIALDEFORM_BLENDER_PYTHON, else the README's ``.venv-blender``.  Missing, the
    tests fail (never skip): the README's test command makes it."""
    path = os.environ.get("AXIALDEFORM_BLENDER_PYTHON") or str(ROOT / ".venv-blender" / "bin" / "python")
    if not Path(path).exists():
        pytest.fail(f"no Python with bpy at {path}: run the README's test command (it makes .venv-blender)")
    return path


def run(*args, timeout=600, env=None) -> subprocess.CompletedProcess:
    proc = subprocess.run([blender_python(), str(CHECKS), *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT, env=env)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc


def _glb_json(path) -> dict:
    data = Path(path).read_bytes()
    (length,) = struct.unpack_from("<I", data, 12)
    return json.loads(data[20:20 + length])


def _length(mesh) -> float:
    return float(mesh.tree.axes[0].length if getattr(mesh, "tree", None) is not None else mesh.axis.length)


def _compare(mesh, params, got, i=0):
    """Blender's evaluated vertices and corner normals against ad.deform."""
    pos, nrm = ad.deform(mesh, params)
    pos, nrm = pos.reshape(-1, 3), nrm.reshape(-1, 3)
    assert got[f"pos{i}"].shape == pos.shape
    err = np.abs(got[f"pos{i}"] - pos).max() / _length(mesh)
    nerr = np.abs(got[f"nrm{i}"] - nrm[got[f"corner{i}"]]).max()
    return err, nerr


CASES = {
    "stones": lambda: (ad.load_mesh("stone"), dict(bend=0.2)),
    "framed_extended_tinted": lambda: (ad.load_mesh("leaf", axis="oriented"),
                                       dict(bend=0.2, twist=0.8, taper=0.3, scale=(0.5, 1.5), tint=0.5)),
    "tree_anchored": lambda: (ad.load_mesh("tree", axes="parts"), dict(bend=(0.1, 0.3, 0.3), droop=0.3)),
    "tree_extended_tinted": lambda: (ad.load_mesh("tree", axes="parts"),
                                     dict(bend=(0.1, 0.3), twist=0.5, taper=0.3, scale=(0.6, 1.4), tint=0.4)),
    # vertices blending two chains (AxisTree.blend): a second level for each depth of the second chain
    "tree_blended": lambda: (blended(ad.load_mesh("tree", axes="parts")), dict(bend=(0.1, 0.3, 0.3), droop=0.3)),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_geometry_nodes_bend_as_the_library(tmp_path, case):
    mesh, variation = CASES[case]()
    params = ad.random_params(mesh, 12, seed=4, variation=ad.Variation(**variation))
    glb = ad.export_glb(tmp_path / "in.glb", mesh, params, layout="instanced")
    run("evaluate", glb, "--out", tmp_path / "out.npz")
    got = np.load(tmp_path / "out.npz")
    assert int(got["instances0"]) == len(params)  # one object, every instance a point
    err, nerr = _compare(mesh, params, got)
    print(f"{case}: vertices {err:.1e} L, normals {nerr:.1e} from ad.deform")
    assert err <= 1e-5, f"{case}: vertices {err:.2e} L from ad.deform"
    assert nerr <= 1e-4, f"{case}: normals {nerr:.2e} from ad.deform"


@pytest.mark.parametrize("case", ["stones", "tree_anchored", "tree_blended"])
def test_the_wind_is_an_animated_input(tmp_path, case):
    mesh, variation = CASES[case]()
    params = ad.random_params(mesh, 10, seed=2, variation=ad.Variation(**variation))
    glb = ad.export_glb(tmp_path / "in.glb", mesh, params, layout="instanced")
    wind = ad.Wind(direction=(1.0, 0.0, 0.4), strength=0.2, gustiness=0.6, frequency=0.5, wavelength=8.0)
    t = 1.37
    run("evaluate", glb, "--out", tmp_path / "out.npz", "--time", t, "--wind", "1,0,0.4,0.2,0.6,0.5,8")
    got = np.load(tmp_path / "out.npz")
    axes = mesh.tree if getattr(mesh, "tree", None) is not None else mesh.axis
    moved = apply_wind(wind, axes, params, t)
    err, nerr = _compare(mesh, moved, got)
    still, _ = _compare(mesh, params, got)
    assert still > 100 * 1e-5, "the wind did not move anything"
    print(f"{case} in the wind: vertices {err:.1e} L, normals {nerr:.1e} from ad.deform of apply_wind")
    assert err <= 1e-5, f"{case}: vertices in the wind {err:.2e} L from ad.deform of apply_wind"
    assert nerr <= 1e-4


def test_import_edit_export_round_trip(tmp_path):
    mesh = ad.load_mesh("tree", axes="parts")
    params = np.asarray(ad.random_params(mesh, 8, seed=9, variation=ad.Variation(bend=(0.1, 0.3), tint=0.3)))
    glb = ad.export_glb(tmp_path / "in.glb", mesh, params, layout="instanced")
    run("edit", glb, "--out", tmp_path)
    k = mesh.axis_count
    want = params.copy()
    want[2, 8:10] = np.float32([0.3, -0.2])
    want[3, 10 * k + 3:10 * k + 6] = np.float32([0.1, 1.2, -0.3])
    want[0, 10 * k] += np.float32(1.5)
    turned = rotation_matrices(np.array([0.0, 0.7, 0.0])) @ rotation_matrices(want[5, 10 * k + 3:10 * k + 6].astype(np.float64))
    want[5, 10 * k + 3:10 * k + 6] = angles_from_matrices(turned)
    want = np.delete(want, 1, axis=0)
    for name in ("gltf.glb", "ours.glb"):  # Blender's glTF exporter (the hooks) and the add-on's own
        back_mesh, back = read_instanced_glb(tmp_path / name)
        assert back_mesh.fingerprint == mesh.fingerprint
        assert back_mesh.tree.to_json()["parents"] == mesh.tree.to_json()["parents"]
        back = np.asarray(back)
        np.testing.assert_array_equal(np.delete(back, 4, axis=0), np.delete(want, 4, axis=0), err_msg=name)
        np.testing.assert_allclose(back[4], want[4], rtol=0, atol=1e-6, err_msg=name)  # turned (Blender's numpy)
    doc = _glb_json(tmp_path / "gltf.glb")
    node = next(nd for nd in doc["nodes"] if "AXIALDEFORM_bend" in nd.get("extensions", {}))
    assert not {"matrix", "rotation", "translation", "scale"} & set(node), node  # the file's frame: no turn
    report = json.loads(subprocess.run(["node", str(ROOT / "tests/gltf-validator/validate.js"),
                                        str(tmp_path / "gltf.glb")], capture_output=True, text=True,
                                       check=True).stdout)
    assert report["issues"]["numErrors"] == 0 and report["issues"]["numWarnings"] == 0, report["issues"]["messages"]
    # three.js draws the edited instances: the npm plugin's records of Blender's export
    lines = subprocess.run(["node", str(Path(__file__).with_name("plugin_records.mjs")), str(tmp_path / "gltf.glb")],
                           capture_output=True, text=True, check=True).stdout.splitlines()
    drawn = [json.loads(x) for x in lines]
    assert len(drawn) == len(mesh.parts)  # three draws each part (a primitive) with the same records
    for part in drawn:
        assert part["count"] == len(want) and part["numbersPerInstance"] == want.shape[1]
        np.testing.assert_array_equal(np.float32(part["data"]).reshape(want.shape), back)
    _, varied = read_instanced_glb(tmp_path / "varied.glb")
    varied = np.asarray(varied)
    np.testing.assert_array_equal(varied[:, 10 * k:], back[:, 10 * k:])  # where each stands, its look: kept
    fresh = ad.random_params(mesh, len(want), seed=5, variation=ad.Variation(bend=(0.2, 0.3)))
    # the library's rules (its random_params in Blender's Python: another numpy, the last float32 bit may differ)
    np.testing.assert_allclose(varied[:, :10 * k], np.asarray(fresh)[:, :10 * k], rtol=0, atol=1e-6 * _length(mesh))
    assert np.abs(varied[:, :10 * k] - want[:, :10 * k]).max() > 0.01 * _length(mesh)  # drawn again


@pytest.mark.parametrize("name", ["leafcard", "tree"])
def test_the_look_travels_there_and_back(tmp_path, name):
    """A textured cut-out (leafcard) and a tree of vertex colours and ten parts: their parts, materials,
    texture pixels, UVs and colours come back from Blender as they went in."""
    mesh = ad.load_mesh(name, **({"axes": "parts"} if name == "tree" else {}))
    params = ad.random_params(mesh, 4, seed=3)
    glb = ad.export_glb(tmp_path / "in.glb", mesh, params, layout="instanced")
    run("through", glb, "--out", tmp_path / "out.glb")
    before, _ = read_instanced_glb(glb)
    after, back = read_instanced_glb(tmp_path / "out.glb")
    np.testing.assert_array_equal(np.asarray(back), np.asarray(params))
    assert [(p.name, p.start, p.count) for p in after.parts] == [(p.name, p.start, p.count) for p in before.parts]
    for a, b in zip(after.parts, before.parts):
        np.testing.assert_array_equal(a.material.base_color, b.material.base_color)
        assert a.material.alpha_mode == b.material.alpha_mode
        assert (a.material.texture is None) == (b.material.texture is None)
        if b.material.texture is not None:
            np.testing.assert_array_equal(a.material.texture, b.material.texture)
    for key in ("uvs", "colors"):
        assert (getattr(after, key) is None) == (getattr(before, key) is None), key
        if getattr(before, key) is not None:
            np.testing.assert_array_equal(getattr(after, key), getattr(before, key))


def test_a_mesh_and_its_parameter_file_import(tmp_path):
    mesh = ad.load_mesh("leaf")
    params = ad.random_params(mesh, 6, seed=8, variation=ad.Variation(bend=0.2, twist=0.4, scale=(0.8, 1.2)))
    adp = ad.write_params(tmp_path / "leaves.adp", params, mesh)
    leaf = ROOT / "axialdeform" / "meshes" / "leaf.obj"
    run("evaluate", adp, "--mesh", leaf, "--out", tmp_path / "out.npz")
    err, nerr = _compare(ad.load_mesh(leaf), params, np.load(tmp_path / "out.npz"))
    assert err <= 1e-5 and nerr <= 1e-4, (err, nerr)


def test_an_exported_scene_glb_opens_as_one_object_per_layer(tmp_path):
    """``export SCENE.toml --instanced``: a GLB of four instanced nodes becomes four objects, each bent as
    the library bends that layer."""
    from axialdeform.core.io.gltf import export_scene

    loaded = ad.Scene.load(ROOT / "examples" / "landscape" / "landscape.toml")
    glb = export_scene(tmp_path / "scene.glb", loaded, layout="instanced")
    run("evaluate", glb, "--out", tmp_path / "out.npz")
    got = np.load(tmp_path / "out.npz")
    layers = sorted((layer for layer in loaded.layers if len(layer.params)), key=lambda layer: layer.name)
    assert len([k for k in got.files if k.startswith("pos")]) == len(layers) == 4
    for i, layer in enumerate(layers):
        assert int(got[f"instances{i}"]) == len(layer.params)
        err, _ = _compare(layer.mesh, layer.params, got, i)
        assert err <= 1e-5, f"layer {layer.name}: {err:.2e} L"


def test_a_scene_file_imports_layer_by_layer(tmp_path):
    src = ROOT / "examples" / "landscape" / "landscape.toml"  # a terrain and four layers
    loaded = ad.Scene.load(src)
    t = 0.75
    run("evaluate", src, "--out", tmp_path / "out.npz", "--time", t)
    got = np.load(tmp_path / "out.npz")
    layers = sorted((layer for layer in loaded.layers if len(layer.params)), key=lambda layer: layer.name)
    assert any(layer.wind for layer in layers) and loaded.wind is not None  # the scene's wind comes along
    for i, layer in enumerate(layers):
        params = apply_wind(loaded.wind if layer.wind else None, layer.mesh.axis, layer.params, t)
        err, _ = _compare(layer.mesh, params, got, i)
        assert err <= 1e-5, f"{src.name} layer {layer.name}: {err:.2e} L"


@pytest.mark.parametrize("name", ["tree", "leafcard"])
def test_cycles_draws_what_render_draws(tmp_path, name):
    """A Cycles CPU render of a few bent, twisted trees (or textured cut-out leaves: the texture's alpha
    makes the silhouette, so its orientation shows) from render's camera: the same silhouette."""
    from PIL import Image

    mesh = ad.load_mesh(name, **({"axes": "parts"} if name == "tree" else {}))
    bend = (0.15, 0.4, 0.4) if name == "tree" else 0.15
    params = ad.random_params(mesh, 4, seed=6, variation=ad.Variation(bend=bend, twist=0.6, scale=(0.8, 1.2)))
    glb = ad.export_glb(tmp_path / "in.glb", mesh, params, layout="instanced")
    pos, _ = ad.deform(mesh, params)
    lo, hi = pos.reshape(-1, 3).min(0), pos.reshape(-1, 3).max(0)
    center, radius = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2
    eye = center + np.array([0.4, 0.5, 2.2]) * radius
    size = (200, 150)
    camera = ad.Camera(eye=tuple(eye), target=tuple(center), fovy=40.0)
    ours = ad.render_image(mesh, params, size=size, camera=camera,
                           look=ad.Look(ground=False, shadow=False, background=(1.0, 1.0, 1.0)))
    contrast = np.abs(ours.astype(int) - 255).max(axis=2)  # against the white background
    # half coverage, as Cycles' alpha > 0.5: half the contrast of the object's own pixels
    ours_mask = contrast > 0.5 * np.percentile(contrast[contrast > 12], 90)
    run("render", glb, "--out", tmp_path / "cycles.png", "--eye=" + ",".join(map(str, eye)),
        "--target=" + ",".join(map(str, center)), "--fov", 40, "--size", f"{size[0]},{size[1]}")
    Image.fromarray(ours).save(tmp_path / "render.png")
    cycles = np.asarray(Image.open(tmp_path / "cycles.png"))
    theirs_mask = cycles[..., 3] > 127
    iou = (ours_mask & theirs_mask).sum() / (ours_mask | theirs_mask).sum()
    assert ours_mask.mean() > 0.05, "render drew almost nothing"
    print(f"{name}: silhouette IoU {iou:.3f}")
    assert iou >= 0.9, f"silhouette IoU {iou:.3f}"


def test_the_zip_installs_as_a_blender_extension(tmp_path):
    """tools/build_blender_addon.py's zip, installed as users install it (an extension, its own module
    ``bl_ext.user_default.axialdeform_blender``), imports and exports through Blender's glTF exporter."""
    built = subprocess.run([sys.executable, str(ROOT / "tools" / "build_blender_addon.py"), "-o", str(tmp_path)],
                           capture_output=True, text=True, check=True).stdout.strip()
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 5, seed=1)
    glb = ad.export_glb(tmp_path / "in.glb", mesh, params, layout="instanced")
    env = {**os.environ, "BLENDER_USER_RESOURCES": str(tmp_path / "user")}
    proc = run("install", built, "--glb", glb, "--out", tmp_path / "out.glb", env=env)
    line = next(x for x in proc.stdout.splitlines() if x.startswith("INSTALLED "))
    report = json.loads(line[len("INSTALLED "):])
    assert report["addons"] == ["bl_ext.user_default.axialdeform_blender"], report
    assert len(report["layers"]) == 1
    _, back = read_instanced_glb(tmp_path / "out.glb")
    np.testing.assert_array_equal(np.asarray(back), np.asarray(params))


def test_a_bad_file_is_refused_in_the_librarys_words(tmp_path):
    """Import of a broken file: the operator cancels with the library's message (file, field, what was
    expected), and nothing is added."""
    mesh = ad.load_mesh("stone")
    glb = ad.export_glb(tmp_path / "in.glb", mesh, ad.random_params(mesh, 3, seed=1), layout="instanced")
    data = bytearray(glb.read_bytes())
    doc = _glb_json(glb)
    doc["nodes"][0]["extensions"]["AXIALDEFORM_bend"]["axis"]["length"] = -1.0
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    (length,) = struct.unpack_from("<I", data, 12)
    rest = data[20 + length:]
    bad = tmp_path / "bad.glb"
    bad.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + len(rest)) + struct.pack("<I4s", len(text), b"JSON")
                    + text + rest)
    proc = run("evaluate", bad, "--out", tmp_path / "out.npz")
    assert "RESULT ['CANCELLED']" in proc.stdout, proc.stdout[-2000:]
    assert "bad.glb: node" in proc.stdout + proc.stderr and "length" in proc.stdout + proc.stderr
    assert not [k for k in np.load(tmp_path / "out.npz").files if k.startswith("pos")]


def test_the_docs_blender_block_runs_in_blender(tmp_path):
    """docs/blender.md's ``python blender`` block, as written, in Blender with the add-on (beside the files it
    names: the README's commands write stones.adp and stones.glb)."""
    import re

    [code] = re.findall(r"^```python blender\n(.*?)^```", (ROOT / "docs" / "blender.md").read_text(encoding="utf-8"),
                        re.S | re.M)
    for name in ("examples", "axialdeform"):
        (tmp_path / name).symlink_to(ROOT / name)
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 500, seed=0)
    ad.write_params(tmp_path / "stones.adp", params, mesh)
    ad.export_glb(tmp_path / "stones.glb", mesh, params, layout="instanced")
    (tmp_path / "block.py").write_text(code, encoding="utf-8")
    proc = subprocess.run([blender_python(), str(CHECKS), "block", "block.py"], capture_output=True, text=True,
                          timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    layers = json.loads(next(x for x in proc.stdout.splitlines() if x.startswith("LAYERS "))[7:])
    assert sorted(n for _, n in layers) == [500, 500, 2000], layers  # stones twice, the forest's trees
    _, back = read_instanced_glb(tmp_path / "edited.glb", node="trees")
    assert len(back) == 2000

"""Scene files: TOML layers, terrain, camera, light, wind;
render / bake / export accept them; errors name the file, the line and the key."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
from PIL import Image

import axialdeform as ad
from axialdeform.cli import main
from axialdeform.core.scene import load_scene

from conftest import assert_valid_gltf

LANDSCAPE = __import__("pathlib").Path(__file__).resolve().parents[2] / "examples" / "landscape" / "landscape.toml"


def write_scene(folder, body: str, name: str = "scene.toml"):
    path = folder / name
    path.write_text(textwrap.dedent(body).lstrip("\n"))
    return path


@pytest.fixture
def small(tmp_path):
    """A scene in its own folder: a height-map terrain, a parameter-file layer and a scatter layer."""
    folder = tmp_path / "s"
    folder.mkdir()
    x = np.linspace(0, 1, 24)
    hm = (255 * (0.3 + 0.3 * np.outer(np.sin(3 * x[:18]), np.cos(2 * x)))).astype(np.uint8)
    Image.fromarray(hm).save(folder / "hm.png")
    stone = ad.load_mesh("stone")
    ad.write_params(folder / "stones.adp", ad.random_params(stone, 12, seed=1, spacing=3.0), stone)
    path = write_scene(folder, """
        up = "y"
        [terrain]
        heightmap = "hm.png"
        height_scale = 3.0
        extent = 20.0
        [camera]
        elevation = 40.0
        [wind]
        strength = 0.2
        [[layer]]
        name = "stones"
        mesh = "stone"
        params = "stones.adp"
        [[layer]]
        name = "leaves"
        mesh = "leaf"
        color = [0.8, 0.4, 0.1]
        wind = true
        [layer.scatter]
        count = 40
        min_distance = 0.8
        anchor = "origin"
        scale = [0.5, 1.0]
        seed = 5
        """)
    return path


def test_a_scene_loads_with_paths_relative_to_its_file(small, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # not the scene's folder
    scene = load_scene(small)
    assert [layer.name for layer in scene.layers] == ["stones", "leaves"]
    assert scene.layers[0].params.shape == (12, 16)
    assert scene.layers[1].params.shape == (40, 19) and scene.layers[1].wind and scene.layers[1].color == (0.8, 0.4, 0.1)
    assert isinstance(scene.wind, ad.core.wind.Wind) and scene.wind.strength == 0.2
    assert scene.camera == ad.core.CameraSpec(elevation=40.0)
    # the scatter layer is exactly axialdeform.scatter on the terrain
    expected = ad.scatter(small.parent / "hm.png", "leaf", 40, placement=ad.core.Placement(min_distance=0.8, anchor="origin",
                                                                                           height_scale=3.0,
                                                                                      extent=[20.0]), variation=ad.Variation(scale=(0.5,
                                                                                                                                    1.0)),
                          seed=5)
    assert np.array_equal(scene.layers[1].params, expected)
    assert np.array_equal(scene.layers[0].params, ad.read_params(small.parent / "stones.adp"))


def _error(tmp_path, body, name="scene.toml"):
    path = write_scene(tmp_path, body, name)
    with pytest.raises(ad.core.SceneError) as info:
        load_scene(path)
    return str(info.value)


def test_unknown_key_names_file_line_and_key(tmp_path):
    msg = _error(tmp_path, """
        [[layer]]
        mesh = "stone"
        params = "x.adp"

        [[layer]]
        mesh = "leaf"
        colour = [1, 0, 0]
        """)
    assert msg.startswith(f"{tmp_path / 'scene.toml'}:7: key 'colour'") and "unknown key" in msg
    msg = _error(tmp_path, """
        up = "y"
        [camera]
        elevation = 30
        zoom = 2
        """)
    assert ":4: key 'zoom'" in msg and "elevation" in msg  # says what is allowed


def test_missing_layer_file_names_file_line_and_key(tmp_path):
    msg = _error(tmp_path, """
        [[layer]]
        name = "a"
        mesh = "stone"

        params = "nowhere.adp"
        """)
    assert "scene.toml:5: key 'params'" in msg and "nowhere.adp" in msg and "no such file" in msg


def test_include_cycle_names_file_line_and_key(tmp_path):
    write_scene(tmp_path, 'include = ["a.toml"]\n', "b.toml")
    write_scene(tmp_path, '# a comment\n\ninclude = ["b.toml"]\n', "a.toml")
    msg = _error(tmp_path, 'up = "y"\ninclude = ["a.toml"]\n')
    assert "b.toml:1: key 'include'" in msg and "cycle" in msg and "a.toml" in msg


def test_include_adds_layers_and_bad_values_are_caught(tmp_path):
    stone = ad.load_mesh("stone")
    ad.write_params(tmp_path / "p.txt", ad.random_params(stone, 3, seed=2), stone)
    write_scene(tmp_path, '[[layer]]\nname = "inc"\nmesh = "stone"\nparams = "p.txt"\n', "inc.toml")
    path = write_scene(tmp_path, 'include = ["inc.toml"]\n[[layer]]\nname = "own"\nmesh = "stone"\nparams = "p.txt"\n')
    assert [layer.name for layer in load_scene(path).layers] == ["inc", "own"]
    msg = _error(tmp_path, 'include = ["inc.toml"]\n[[layer]]\nname = "inc"\nmesh = "stone"\nparams = "p.txt"\n', "dup.toml")
    assert "dup.toml:3: key 'name'" in msg
    msg = _error(tmp_path, '[[layer]]\nmesh = "stone"\n[layer.scatter]\ncount = 5\nmin_distance = 1\n', "noterrain.toml")
    assert "terrain" in msg
    msg = _error(tmp_path, '[terrain]\nheightmap = "missing.png"\n', "t.toml")
    assert "t.toml:2: key 'heightmap'" in msg
    msg = _error(tmp_path, 'up = "y"\n[[layer]\n', "broken.toml")
    assert "broken.toml" in msg and "TOML" in msg


@pytest.mark.slow
def test_cli_render_bake_export_accept_a_scene(small, tmp_path, capsys, validate):  # noqa: F811
    png = tmp_path / "scene.png"
    assert main(["render", str(small), "-o", str(png), "--size", "160x120"]) == 0
    image = np.asarray(Image.open(png).convert("RGB")).astype(int)
    assert image.shape == (120, 160, 3)
    leafy = (image[..., 0] - image[..., 2]) > 60  # the orange leaves layer is drawn in its colour
    assert leafy.sum() > 5 and image.std() > 10
    npz = tmp_path / "scene.npz"
    assert main(["bake", str(small), "-o", str(npz)]) == 0
    baked = np.load(npz)
    scene = load_scene(small)
    for layer in scene.layers:
        still, _ = ad.deform(layer.mesh.axis, layer.mesh.positions, layer.mesh.normals, layer.params)
        expected, _ = ad.bake(layer.mesh, layer.params, "cpu", options=ad.RenderOptions(wind=scene.wind if layer.wind else None, time=0.0))
        assert np.array_equal(baked[f"positions_{layer.name}"], expected)
        # the [wind] reaches the layers with wind = true only
        assert np.array_equal(expected, still) == (not layer.wind)
    glb = tmp_path / "scene.glb"
    assert main(["export", str(small), "-o", str(glb)]) == 0
    (report,) = validate(glb)
    assert_valid_gltf(report, allowed_infos=("BUFFER_VIEW_TARGET_MISSING",))
    import trimesh

    loaded = trimesh.load(glb)
    assert set(loaded.geometry) == {"terrain", "stones", "leaves"}
    assert len(loaded.geometry["leaves"].faces) == 40 * len(ad.load_mesh("leaf").faces)
    capsys.readouterr()
    # a scene with PARAMS, or a mesh without: one line, status 2
    assert main(["render", str(small), str(tmp_path / "x.adp"), "-o", str(png)]) == 2
    assert main(["render", "stone", "-o", str(png)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("axialdeform render: error: PARAMS") for line in err)


def test_scene_error_from_the_cli_is_one_line(tmp_path, capsys):
    path = write_scene(tmp_path, '[[layer]]\nmesh = "stone"\nparams = "gone.adp"\n')
    assert main(["render", str(path), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"axialdeform render: error: {path}:3: key 'params': no such file {tmp_path / 'gone.adp'}"


def test_the_landscape_scene_loads():
    scene = load_scene(LANDSCAPE, scale_counts=0.1)
    assert [layer.name for layer in scene.layers] == ["stones", "grass", "trunks", "leaves"]
    assert scene.terrain is not None and all(len(layer.params) > 0 for layer in scene.layers)


@pytest.mark.slow
def test_view_command_shows_a_scene_headless(small, tmp_path):
    import subprocess
    import sys

    shot = tmp_path / "view.png"
    proc = subprocess.run([sys.executable, "-m", "axialdeform", "view", str(small), "--headless", "--frames", "2",
                           "--size", "160x120", "--screenshot", str(shot)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "12 instances" in proc.stdout  # the first layer is the viewer's own
    image = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    assert ((image[..., 0] - image[..., 2]) > 60).sum() > 3  # the orange leaves of the second layer are drawn too


def test_time_moves_the_scene_wind_and_needs_one(small, tmp_path, capsys):
    a, b = tmp_path / "a.npz", tmp_path / "b.npz"
    assert main(["bake", str(small), "-o", str(a)]) == 0
    assert main(["bake", str(small), "-o", str(b), "--time", "1.3"]) == 0
    a, b = np.load(a), np.load(b)
    assert np.array_equal(a["positions_stones"], b["positions_stones"])  # wind = false
    assert not np.array_equal(a["positions_leaves"], b["positions_leaves"])  # wind = true: moved
    still = write_scene(small.parent, small.read_text().replace("[wind]\nstrength = 0.2\n", ""), "still.toml")
    capsys.readouterr()
    assert main(["render", str(still), "-o", str(tmp_path / "x.png"), "--time", "1.0"]) == 2
    assert "--time" in capsys.readouterr().err and not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("body, line, key", [
    ('up = 3', 1, "up"),
    ('[[layer]]\nmesh = "stone"\ncolor = "red"\nparams = "x"', 3, "color"),
    ('[terrain]\nheightmap = "hm.png"\n[[layer]]\nmesh = "stone"\n[layer.scatter]\ncount = "many"', 6, "count"),
    ('[terrain]\nheightmap = "hm.png"\n[[layer]]\nmesh = "stone"\n[layer.scatter]\ncount = 5\nscale = [0, 1]', 7, "scale"),
    ('[terrain]\nheightmap = "hm.png"\n[[layer]]\nmesh = "stone"\n[layer.scatter]\ncount = 5\nanchor = "top"', 7, "anchor"),
    ('[terrain]\nheightmap = "hm.png"\nextent = -3', 3, "extent"),
    ('[camera]\neye = [0, 0, 1]', 2, "eye"),
    ('[wind]\nstrength = -1', 2, "strength"),
    ('[terrain]\nheightmap = "hm.png"\n[[layer]]\nmesh = "stone"\n[layer.scatter]\ncount = 500\nmin_distance = 3',
     5, "scatter"),  # too few fit: the recipe's table
])
def test_bad_values_name_their_line_and_key(tmp_path, body, line, key):
    Image.fromarray(np.full((8, 8), 128, dtype=np.uint8)).save(tmp_path / "hm.png")
    msg = _error(tmp_path, body + "\n")
    assert msg.startswith(f"{tmp_path / 'scene.toml'}:{line}: key '{key}': "), msg


@pytest.mark.slow
def test_export_a_scene_instanced(small, tmp_path, capsys, validate):  # noqa: F811
    """``export SCENE --instanced``: per layer its base mesh once on a node with
    EXT_mesh_gpu_instancing, the terrain once; each layer reads back bit for bit."""
    from axialdeform.core.io.gltf import INSTANCING, read_instanced_glb

    glb = tmp_path / "inst.glb"
    assert main(["export", str(small), "-o", str(glb), "--instanced"]) == 0
    assert "instanced" in capsys.readouterr().out
    (report,) = validate(glb)
    assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]
    assert report["issues"]["numWarnings"] == 0, report["issues"]["messages"][:5]
    scene = load_scene(small)
    import pygltflib

    g = pygltflib.GLTF2.load(str(glb))
    inst = {n.name: n for n in g.nodes if (n.extensions or {}).get(INSTANCING)}
    assert set(inst) == {"stones", "leaves"} and g.extensionsUsed == [INSTANCING, "AXIALDEFORM_bend"]
    assert [n.name for n in g.nodes if n.mesh is not None and n.name not in inst] == ["terrain"]
    for layer in scene.layers:
        mesh, params = read_instanced_glb(glb, node=layer.name)
        assert mesh.fingerprint == layer.mesh.fingerprint and np.array_equal(params, layer.params)
        extras = inst[layer.name].extras["axialdeform"]
        assert extras["layer"] == layer.name and extras["count"] == len(layer.params)
    leaves = g.meshes[inst["leaves"].mesh].primitives[0]
    color = g.materials[leaves.material].pbrMetallicRoughness.baseColorFactor
    assert np.allclose(color[:3], (0.8, 0.4, 0.1))  # the layer's colour
    import trimesh

    loaded = trimesh.load(glb)  # trimesh ignores the extension: each base mesh once
    assert {"terrain", "stones", "leaves"} <= {n for n in loaded.graph.nodes_geometry}
    assert sum(len(geom.faces) for geom in loaded.geometry.values()) == (
        len(scene.terrain.faces) + len(ad.load_mesh("stone").faces) + len(ad.load_mesh("leaf").faces))
    with pytest.raises(ad.AxialDeformError, match="name one with node="):
        read_instanced_glb(glb)


@pytest.mark.slow
def test_viewer_keys_act_on_every_layer_of_a_scene(small):
    """N (new shapes), UP/DOWN (bend) and V (wind) reach every layer, not only the first."""
    from axialdeform.viewer import Viewer, ViewerSettings

    scene = ad.Scene.load(small)
    v = Viewer.create(scene, headless=True, size=(96, 72), settings=ViewerSettings(seed=4),
                      look=ad.Look(fast=True))  # N: seed 5 (the file: 1)
    try:
        (leaves, renderer, base), = v.layers
        assert leaves.name == "leaves" and "12 instances + 40 in 1 more layer" in v.status()
        v.step()
        assert renderer.wind is scene.wind  # the leaves sway (wind = true), the stones do not
        own0, other0 = v.renderer.instances.read().copy(), renderer.instances.read().copy()
        v.on_key_event("N", v.wnd.keys.ACTION_PRESS, None)
        v.step()
        own1, other1 = v.renderer.instances.read(), renderer.instances.read()
        for before, after in ((own0, own1), (other0, other1)):
            assert not np.allclose(before[:, :10], after[:, :10])  # new shapes ...
            assert np.array_equal(before[:, 10:], after[:, 10:])  # ... in the same places
        v.on_key_event("UP", v.wnd.keys.ACTION_PRESS, None)
        v.step()
        np.testing.assert_allclose(renderer.instances.read()[:, :10], base[:, :10] * 1.25, rtol=1e-6, atol=1e-7)
        np.testing.assert_allclose(v.renderer.instances.read()[:, :10], v.base[:, :10] * 1.25, rtol=1e-6, atol=1e-7)
        v.on_key_event("V", v.wnd.keys.ACTION_PRESS, None)  # wind off: every layer
        v.step()
        assert renderer.wind is None and v.renderer.wind is None and not v.scene_wind_on
        v.on_key_event("V", v.wnd.keys.ACTION_PRESS, None)
        v.step()
        assert renderer.wind is scene.wind and v.renderer.wind is None  # the stones' layer has no wind
    finally:
        v.release()
        v.wnd.destroy()


def test_the_viewer_stands_a_scene_on_renders_ground(tmp_path):
    """The viewer fits its ground plane by render's rule (gl/scene.py ground_spheres): under every layer of a
    scene, not only its first."""
    from axialdeform.core.bounds import ground_square, stack_spheres
    from axialdeform.gl.scene import ground_spheres
    from axialdeform.viewer import Viewer

    stone = ad.load_mesh("stone")
    near = ad.random_params(stone, 20, seed=1, placement="disc")
    far = ad.random_params(stone, 20, seed=2, placement="disc")
    far.position[:, 0] += 40.0  # the second layer stands well beside the first
    ad.write_params(tmp_path / "near.adp", near, stone)
    ad.write_params(tmp_path / "far.adp", far, stone)
    (tmp_path / "two.toml").write_text('[[layer]]\nname = "near"\nmesh = "stone"\nparams = "near.adp"\n'
                                       '[[layer]]\nname = "far"\nmesh = "stone"\nparams = "far.adp"\n')
    scene = ad.Scene.load(tmp_path / "two.toml")
    center, radius = ground_square(*stack_spheres(ground_spheres(scene)))
    assert center[0] > 15.0  # between the two layers: a ground under the first alone would not be
    v = Viewer.create(scene, headless=True, size=(64, 48), look=ad.Look(fast=True))
    try:
        np.testing.assert_allclose(v.ground.center, center)
        assert v.ground.radius == pytest.approx(radius)
    finally:
        v.release()
        v.wnd.destroy()

"""The command line end to end, including its error exits."""

import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import axialdeform as ad
from axialdeform.cli import build_parser, main

from conftest import data_mesh


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True, cwd=cwd)


@pytest.mark.slow
def test_demo_writes_a_png_and_says_where(tmp_path):
    res = run("demo", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    out = tmp_path / "axialdeform-demo.png"
    assert str(out) in res.stdout
    img = np.asarray(Image.open(out))
    assert img.shape[1] == 2 * img.shape[0] * 4 // 3 and img.std() > 10


def test_random_info_convert_render_bake(tmp_path, capsys):
    params = tmp_path / "p.adp"
    assert main(["random", "stone", "-n", "300", "--seed", "4", "--bend", "0.2", "--placement", "disc", "-o", str(params)]) == 0
    assert main(["info", str(params)]) == 0
    out = capsys.readouterr().out
    assert "instances: 300" in out and "checksum:  CRC-32" in out and "OK" in out and "axis x" in out
    assert main(["convert", str(params), str(tmp_path / "p.txt")]) == 0
    assert main(["convert", str(tmp_path / "p.txt"), str(tmp_path / "q.adp"), "--mesh", "stone", "--quantize"]) == 0
    assert (tmp_path / "q.adp").stat().st_size < params.stat().st_size / 1.9
    assert np.array_equal(ad.read_params(tmp_path / "p.txt"), ad.read_params(params))
    for mode in ("solid", "flat", "wireframe"):
        png = tmp_path / f"{mode}.png"
        assert main(["render", "stone", str(tmp_path / "p.txt"), "-o", str(png), "--mode", mode, "--size", "200x150"]) == 0
        assert Image.open(png).size == (200, 150)
    assert main(["bake", "stone", str(params), "-o", str(tmp_path / "cpu.npz")]) == 0
    assert main(["bake", "stone", str(params), "-o", str(tmp_path / "gpu.npz"), "--engine", "gpu"]) == 0
    cpu, gpu = np.load(tmp_path / "cpu.npz"), np.load(tmp_path / "gpu.npz")
    assert cpu["positions"].shape == (300, 58, 3) and cpu["positions"].dtype == np.float32
    L = ad.load_mesh("stone").axis.length
    assert np.abs(cpu["positions"] - gpu["positions"]).max() <= 1e-5 * L
    assert np.abs(cpu["normals"] - gpu["normals"]).max() <= 1e-5


@pytest.mark.parametrize("fmt", ["obj", "ply", "glb"])
def test_bake_to_a_folder_of_meshes(tmp_path, fmt):
    stone = ad.load_mesh("stone")
    values = ad.random_params(stone, 5, seed=1, variation=ad.Variation(bend=0.2))
    ad.write_params(tmp_path / "p.txt", values)
    assert main(["bake", "stone", str(tmp_path / "p.txt"), "-o", str(tmp_path / "out"), "--format", fmt]) == 0
    files = sorted((tmp_path / "out").iterdir())
    assert len(files) == 5
    expected, _ = ad.deform(stone.axis, stone.positions, stone.normals, values)
    back = ad.load_mesh(files[3])
    assert back.vertex_count == 58 and np.allclose(back.positions, expected[3], atol=1e-5)


@pytest.mark.slow
def test_off_origin_ply_with_normals_along_each_axis(tmp_path):
    """The 'done when' check: meshes not in the repository, axes x, y, z, off the origin."""
    import trimesh

    base = ad.load_mesh(data_mesh("base/rock_caustics.obj"))
    for k, perm in enumerate(([0, 1, 2], [1, 0, 2], [1, 2, 0])):
        tm = base.to_trimesh(base.positions[:, perm] + [100.0, -50.0, 25.0], base.normals[:, perm])
        mesh_path = tmp_path / f"rock_{k}.ply"
        mesh_path.write_bytes(trimesh.exchange.ply.export_ply(tm, vertex_normal=True))
        mesh = ad.load_mesh(mesh_path)
        assert mesh.axis.index == k and mesh.normals_from_file
        params = tmp_path / f"p{k}.adp"
        assert main(["random", str(mesh_path), "-n", "1000", "--seed", str(k), "--bend", "0.2", "-o", str(params)]) == 0
        assert main(["bake", str(mesh_path), str(params), "-o", str(tmp_path / "g.npz"), "--engine", "gpu", "--overwrite"]) == 0
        assert main(["bake", str(mesh_path), str(params), "-o", str(tmp_path / "c.npz"), "--engine", "cpu", "--overwrite"]) == 0
        g, c = np.load(tmp_path / "g.npz"), np.load(tmp_path / "c.npz")
        ref, ref_n = ad.deform(mesh.axis, mesh.positions, mesh.normals, ad.read_params(params))
        assert np.abs(g["positions"] - ref).max() <= 1e-5 * mesh.axis.length
        assert np.array_equal(c["positions"], ref) and np.array_equal(c["normals"], ref_n)


@pytest.mark.parametrize("args,message", [
    (["render", "stone", "{tmp}/missing.adp", "-o", "{tmp}/x.png"], "no such parameter file"),
    (["render", "{tmp}/missing.obj", "{tmp}/p.txt", "-o", "{tmp}/x.png"], "no such mesh file"),
    (["render", "leaf", "{tmp}/p.adp", "-o", "{tmp}/x.png"], "made for a different base mesh"),
    (["render", "stone", "{tmp}/bad.txt", "-o", "{tmp}/x.png"], "line 1: expected 16 numbers, found 2"),
    (["render", "stone", "{tmp}/p.txt", "-o", "{tmp}/x.png", "--size", "big"], "size: expected WIDTHxHEIGHT"),
    (["info", "{tmp}/cut.adp"], "truncated"),
    (["convert", "{tmp}/p.txt", "{tmp}/p.xyz"], "unknown parameter file type"),
    (["bake", "stone", "{tmp}/p.txt", "-o", "{tmp}/p.txt/x.npz"], "Not a directory|not a folder"),
    (["random", "{tmp}/bad.txt", "-n", "3", "-o", "{tmp}/r.adp"], "unsupported mesh file type"),
])
@pytest.mark.slow
def test_user_errors_exit_2_with_one_line(tmp_path, args, message):
    stone = ad.load_mesh("stone")
    values = ad.random_params(stone, 4, seed=1)
    ad.write_params(tmp_path / "p.adp", values, stone)
    ad.write_params(tmp_path / "p.txt", values)
    (tmp_path / "bad.txt").write_text("1 2\n")
    (tmp_path / "cut.adp").write_bytes((tmp_path / "p.adp").read_bytes()[:50])
    res = run(*[a.format(tmp=tmp_path) for a in args])
    assert res.returncode == 2, (res.stdout, res.stderr)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.stderr, res.stderr
    assert lines[0].startswith("axialdeform ") and "error" in lines[0]
    import re

    assert re.search(message, lines[0]), lines[0]


def test_ignore_mesh_mismatch(tmp_path):
    stone = ad.load_mesh("stone")
    ad.write_params(tmp_path / "p.adp", ad.random_params(stone, 4, seed=1), stone)
    assert main(["render", "leaf", str(tmp_path / "p.adp"), "-o", str(tmp_path / "x.png"), "--size", "64x48",
                 "--ignore-mesh-mismatch"]) == 0


@pytest.mark.slow
def test_help_everywhere():
    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices
    assert {"demo", "random", "render", "bake", "info", "convert"} <= set(commands)
    for name in commands:
        res = run(name, "--help")
        assert res.returncode == 0 and "usage: axialdeform " + name in res.stdout, name
    res = run()
    assert res.returncode == 2 and "usage" in res.stderr


def test_info_gives_a_checksum_verdict_on_a_corrupt_file(tmp_path):
    stone = ad.load_mesh("stone")
    path = ad.write_params(tmp_path / "p.adp", ad.random_params(stone, 10, seed=1), stone)
    data = bytearray(path.read_bytes())
    data[300] ^= 0x01
    (tmp_path / "bad.adp").write_bytes(bytes(data))
    res = run("info", tmp_path / "bad.adp")
    assert res.returncode == 2
    assert "instances: 10" in res.stdout and "MISMATCH" in res.stdout and "axis x" in res.stdout
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "checksum" in lines[0] and "Traceback" not in res.stderr
    ok = run("info", path)
    assert ok.returncode == 0 and "OK" in ok.stdout and "MISMATCH" not in ok.stdout


def test_import_is_lazy_and_every_public_name_resolves():
    """``import axialdeform`` (every CLI start, every bench child) loads no GL,
    mesh or matrix library until one is used; the public names all resolve,
    and importing a submodule does not shadow a function of the same name."""
    code = (
        "import sys, axialdeform as ad\n"
        "heavy = sorted(m for m in ('moderngl', 'trimesh', 'pyrr', 'PIL', 'importlib.metadata') if m in sys.modules)\n"
        "assert not heavy, heavy\n"
        "import axialdeform.core.deform, axialdeform.core.bake\n"
        "assert callable(ad.deform) and callable(ad.bake), (ad.deform, ad.bake)\n"
        "missing = [n for n in ad.__all__ if not hasattr(ad, n)]\n"
        "assert not missing, missing\n"
        "assert set(ad.__all__) <= set(dir(ad))\n"
        "assert ad.core.params.FIELDS == ad.core.FIELDS and ad.__version__\n"
        "try:\n    ad.no_such_name\nexcept AttributeError as e:\n    assert 'no_such_name' in str(e)\n"
        "else:\n    raise SystemExit('no AttributeError')\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def _subparsers():
    import argparse

    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices


def test_every_command_is_its_own_module():
    import importlib

    from axialdeform.cli import COMMANDS

    choices = _subparsers()
    assert set(COMMANDS) == set(choices)
    for name in COMMANDS:
        module = importlib.import_module(f"axialdeform.cli.{name}")
        assert choices[name].get_default("handler") is module.run


def test_every_argument_states_its_default():
    import argparse

    missing = []
    for name, sub in _subparsers().items():
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            text = (action.help or "") % {"default": action.default, "prog": sub.prog, "choices": action.choices}
            positional = not action.option_strings
            if positional and action.nargs != "?":
                ok = bool(text)  # required: it has no default, but it says what it is
            else:
                ok = "default" in text or "required" in text
            if not ok:
                missing.append(f"{name} {'/'.join(action.option_strings) or action.dest}: {text!r}")
    assert missing == []


def test_render_with_eye_target_fov(tmp_path):
    params = tmp_path / "p.adp"
    assert main(["random", "stone", "-n", "50", "--seed", "3", "-o", str(params)]) == 0
    images = {}
    for name, extra in (("auto", []), ("near", ["--eye", "0,3,6", "--target", "0,0,0", "--fov", "50"]),
                        ("far", ["--eye", "0,300,600", "--target", "0,0,0"]), ("narrow", ["--fov", "10"])):
        out = tmp_path / f"{name}.png"
        # --fast: no ground, so what differs from the background is stone
        assert main(["render", "stone", str(params), "-o", str(out), "--size", "160x120", "--fast", *extra]) == 0
        images[name] = np.asarray(Image.open(out)).astype(int)
    background = images["far"][0, 0]
    covered = {k: (np.abs(v - background).max(axis=-1) > 12).mean() for k, v in images.items()}
    assert covered["far"] < 0.01  # the stones are a speck from 670 units away
    assert covered["near"] > covered["auto"]  # closer and wider: more of the picture is stone
    assert not np.array_equal(images["narrow"], images["auto"])


@pytest.mark.parametrize("args,message", [
    (["--eye", "1,2,3", "--target", "1,2,3"], "two different points"),
    (["--eye", "0,5,0", "--target", "0,0,0"], "parallel to the up axis"),
    (["--fov", "180"], "--fov"),
])
def test_render_camera_errors_are_one_line(tmp_path, capsys, args, message):
    params = tmp_path / "p.adp"
    ad.write_params(params, ad.random_params(ad.load_mesh("stone"), 4, seed=1), ad.load_mesh("stone"))
    assert main(["render", "stone", str(params), "-o", str(tmp_path / "x.png"), *args]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err
    assert not (tmp_path / "x.png").exists()


def test_view_of_a_file_shows_no_made_up_seed(tmp_path, capsys):
    params = tmp_path / "p.adp"
    assert main(["random", "stone", "-n", "20", "--seed", "5", "-o", str(params)]) == 0
    capsys.readouterr()
    assert main(["view", "stone", str(params), "--headless", "--frames", "1", "--size", "64x48"]) == 0
    title = capsys.readouterr().out
    assert "20 instances" in title and "seed" not in title
    assert main(["view", "stone", "-n", "20", "--seed", "7", "--headless", "--frames", "1", "--size", "64x48"]) == 0
    assert "seed 7" in capsys.readouterr().out


def test_baked_outputs_have_a_triangle_budget(tmp_path, capsys):
    """bake and export --baked refuse more than --max-triangles triangles
    (instances x triangles of the mesh) before any work, in one line; the
    option raises it; --instanced has no such limit."""
    adp = tmp_path / "s.adp"
    assert main(["random", "stone", "-n", "50", "-o", str(adp)]) == 0  # 50 x 112 = 5600 triangles
    for argv in (["bake", "stone", str(adp), "-o", str(tmp_path / "b.npz")],
                 ["bake", "stone", str(adp), "-o", str(tmp_path / "folder")],
                 ["export", "stone", str(adp), "-o", str(tmp_path / "b.glb")]):
        capsys.readouterr()
        assert main(argv + ["--max-triangles", "5000"]) == 2
        err = capsys.readouterr().err
        assert "5600 triangles to bake, over the limit of 5000" in err and "Traceback" not in err
        assert not (tmp_path / argv[4].split("/")[-1]).exists()  # nothing written
        assert main(argv + ["--max-triangles", "5600"]) == 0
    assert main(["export", "stone", str(adp), "-o", str(tmp_path / "i.glb"), "--instanced", "--max-triangles", "1"]) == 0


def test_info_prints_the_axes_found_from_the_shape(tmp_path, monkeypatch):
    """``info MESH --axes skeleton`` prints the tree the skeleton gives a one-piece wood; an unknown rule
    reads as a file that is not there: exit 2, one line, no traceback."""
    import subprocess
    import sys

    from helpers.one_piece import one_piece_tree

    path = tmp_path / "wood.obj"
    mesh = one_piece_tree()
    with open(path, "w") as f:
        f.writelines(f"v {x:.7g} {y:.7g} {z:.7g}\n" for x, y, z in mesh.positions)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in mesh.faces)
    env = {**__import__("os").environ, "AXIALDEFORM_CACHE": str(tmp_path / "cache")}
    out = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(path), "--axes", "skeleton"],
                         capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    assert "5 axes (trunk, branch1 <- trunk" in out.stdout
    bad = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(path), "--axes", "bones"],
                         capture_output=True, text=True, env=env)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and "bones" in bad.stderr
    saved = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(path), "--axes", "skeleton", "--save-axes",
                            str(tmp_path / "wood.toml")], capture_output=True, text=True, env=env)
    assert saved.returncode == 0 and "wrote" in saved.stdout and "[[branch]]" in (tmp_path / "wood.toml").read_text()
    again = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(path), "--axes", str(tmp_path / "wood.toml")],
                           capture_output=True, text=True, env=env)
    assert again.returncode == 0 and "5 axes (trunk, branch1 <- trunk" in again.stdout
    for args in (["--axes", "parts"], ["--axes", "skeleton"]):  # a skeleton's branches only; never over a file
        refused = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(path), *args, "--save-axes",
                                  str(tmp_path / "wood.toml")], capture_output=True, text=True, env=env)
        assert refused.returncode == 2 and "--save-axes" in refused.stderr and "Traceback" not in refused.stderr

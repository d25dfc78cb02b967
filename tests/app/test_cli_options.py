"""Every option does what it says: a scene's camera from --eye/--target/--fov, a negative vector after
its option, --bend a level in view as in random and scatter, the bundled meshes in the help, and web's
line saying what a generated layer is."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

from axialdeform.cli import join_vector_values
from axialdeform.core.io.mesh import BUNDLED_MESHES

ROOT = Path(__file__).resolve().parents[2]

SCENE = """
[[layer]]
name = "stones"
mesh = "stone"
[layer.generate]
rate = 1.0
tile = 8.0
seed = 2
extent = [-6, -6, 6, 6]
"""


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


def test_negative_vectors_stay_values():
    assert join_vector_values(["render", "s.toml", "--eye", "-2,8,12", "--target", "-1.5,0,-.5"]) == \
        ["render", "s.toml", "--eye=-2,8,12", "--target=-1.5,0,-.5"]
    assert join_vector_values(["render", "--eye", "-o"]) == ["render", "--eye", "-o"]  # not numbers: left alone


def test_a_scenes_camera_from_the_command_line(tmp_path):
    (tmp_path / "s.toml").write_text(SCENE)
    (tmp_path / "c.toml").write_text("[camera]\neye = [-2.0, 8.0, 12.0]\ntarget = [0.5, 0.0, -1.0]\nfov = 50.0\n" + SCENE)
    size = ["--size", "96x72"]
    assert cli("render", "s.toml", "-o", "auto.png", *size, cwd=tmp_path).returncode == 0
    r = cli("render", "s.toml", "-o", "args.png", *size, "--eye", "-2,8,12", "--target", "0.5,0,-1", "--fov", "50",
            cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert cli("render", "c.toml", "-o", "file.png", *size, cwd=tmp_path).returncode == 0
    read = lambda n: np.asarray(Image.open(tmp_path / n))  # noqa: E731
    assert not np.array_equal(read("args.png"), read("auto.png"))  # before, the options were ignored
    assert np.array_equal(read("args.png"), read("file.png"))  # what the scene file's own [camera] draws
    r = cli("render", "s.toml", "-o", "x.png", *size, "--fov", "200", cwd=tmp_path)
    assert r.returncode == 2 and "--fov" in r.stderr and "Traceback" not in r.stderr


def test_view_takes_a_bend_a_level(tmp_path):
    r = cli("view", "tree", "--axes", ROOT / "examples" / "forest" / "tree-axes.toml", "--bend", "0.03,0.2", "-n", "5",
            "--headless", "--frames", "1", "--size", "32x24")
    assert r.returncode == 0, r.stderr


def test_the_help_names_every_bundled_mesh():
    for command in ("render", "random", "view", "scatter", "fit", "web", "bench"):
        text = " ".join(cli(command, "--help").stdout.split())
        assert all(f"'{name}'" in text for name in BUNDLED_MESHES), (command, text[:400])


def test_web_says_what_a_generated_layer_is(tmp_path):
    (tmp_path / "s.toml").write_text(SCENE)
    r = cli("web", "s.toml", "-o", "page", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "generated layer as recipes" in r.stdout and "quantized" not in r.stdout and "render draws the extent" in r.stdout


def test_float32_max_numbers_get_one_line_from_every_command(tmp_path):
    (tmp_path / "big.txt").write_text(("3.4028235e38 " * 16 + "\n") * 2)
    for command in (["render", "stone", "big.txt", "-o", "b.png"], ["export", "stone", "big.txt", "-o", "b.glb"],
                    ["bake", "stone", "big.txt", "-o", "b.npz"], ["web", "stone", "big.txt", "-o", "b.html"]):
        r = cli(*command, cwd=tmp_path)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, (command, r.stderr)
        assert "d1u" in r.stderr and "big.txt" in r.stderr


def test_a_walk_stops_at_the_worlds_edge_and_a_huge_wind_is_refused(tmp_path):
    (tmp_path / "s.toml").write_text(SCENE)
    r = cli("view", "s.toml", "--headless", "--frames", "2", "--size", "32x24", "--walk", "1e30,0", cwd=tmp_path)
    assert r.returncode == 0, r.stderr  # before: an AttributeError
    held = int(r.stdout.split(" instances")[0].rsplit(" ", 1)[1].replace(",", ""))
    assert held > 0  # at the edge (x = 65 536 cells) the tiles within reach are still made
    r = cli("render", "s.toml", "-o", "w.png", "--size", "32x24", "--wind", "1e308", cwd=tmp_path)
    assert r.returncode == 2 and "wind strength: expected at most 100" in r.stderr and len(r.stderr.splitlines()) == 1

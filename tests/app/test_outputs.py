"""An output never holds an input and scene files are
bounded (item 3): each attack of the issue, as a command a user types."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad


def run(*args, cwd):
    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=300)


def refused(proc, *words):
    assert proc.returncode == 2, (proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    for w in words:
        assert w in lines[0], lines[0]


@pytest.fixture
def folder(tmp_path):
    ad.write_params(tmp_path / "p.adp", ad.random_params(ad.load_mesh("stone"), 20, seed=1))
    return tmp_path


@pytest.mark.slow
def test_web_never_replaces_its_inputs_nor_an_existing_file_without_overwrite(folder):
    assert run("web", "stone", "p.adp", "-o", "site", cwd=folder).returncode == 0
    before = {p: p.read_bytes() for p in (folder / "site").rglob("*") if p.is_file()}
    (folder / "site" / "params.adp").write_bytes((folder / "p.adp").read_bytes())  # the user's own copy
    # the attack: the inputs live in the output folder
    refused(run("web", "site/mesh.glb", "site/params.adp", "-o", "site", cwd=folder), "site/mesh.glb", "input")
    # a hard link of an input is the input
    (folder / "site2").mkdir()
    os.link(folder / "p.adp", folder / "site2" / "params.adp")
    refused(run("web", "stone", "p.adp", "-o", "site2", cwd=folder), "site2/params.adp", "input")
    # a file that exists is not replaced without --overwrite: the user's own, or an earlier export's
    (folder / "site" / "index.html").write_text("<h1>my own page</h1>")
    refused(run("web", "stone", "p.adp", "-o", "site", cwd=folder), "site/index.html: exists", "--overwrite")
    assert (folder / "site" / "index.html").read_text() == "<h1>my own page</h1>"
    (folder / "mine.html").write_text("<h1>mine</h1>")
    refused(run("web", "stone", "p.adp", "-o", "mine.html", cwd=folder), "mine.html", "--overwrite")
    assert (folder / "mine.html").read_text() == "<h1>mine</h1>"
    # --overwrite replaces them (never an input)
    ok = run("web", "stone", "p.adp", "-o", "site", "--overwrite", cwd=folder)
    assert ok.returncode == 0, ok.stderr
    assert (folder / "site" / "index.html").read_text() != "<h1>my own page</h1>"
    refused(run("web", "stone", "p.adp", "-o", "site", cwd=folder), "exists", "--overwrite")  # an export's own too
    assert run("web", "stone", "p.adp", "-o", "page.html", cwd=folder).returncode == 0
    refused(run("web", "stone", "p.adp", "-o", "page.html", cwd=folder), "page.html: exists", "--overwrite")
    assert run("web", "stone", "p.adp", "-o", "page.html", "--overwrite", cwd=folder).returncode == 0
    refused(run("web", "site/mesh.glb", "site/params.adp", "-o", "site", "--overwrite", cwd=folder), "input")
    assert set(before) <= {p for p in (folder / "site").rglob("*") if p.is_file()}


@pytest.mark.slow
def test_bake_overwrite_never_removes_its_input_mesh(folder):
    assert run("bake", "stone", "p.adp", "-o", "out", cwd=folder).returncode == 0
    mesh = folder / "out" / "instance_000005.obj"
    data = mesh.read_bytes()
    refused(run("bake", mesh, "p.adp", "-o", "out", "--overwrite", "--ignore-mesh-mismatch", cwd=folder),
            "instance_000005.obj", "input", "--overwrite")
    assert mesh.read_bytes() == data
    os.link(mesh, folder / "linked.obj")  # a hard link outside: the file inside is still the input
    refused(run("bake", "linked.obj", "p.adp", "-o", "out", "--overwrite", "--ignore-mesh-mismatch", cwd=folder),
            "input")
    assert mesh.read_bytes() == data


def test_a_scene_knows_every_file_it_read(folder):
    (folder / "s.toml").write_text('[[layer]]\nname = "a"\nmesh = "stone"\nparams = "p.adp"\n')
    scene = ad.Scene.load(folder / "s.toml")
    names = {Path(p).name for p in scene.sources}
    assert {"s.toml", "p.adp", "stone.obj"} <= names


def test_scene_includes_and_nesting_are_bounded(folder):
    from axialdeform.core.io.scene import MAX_INCLUDE_DEPTH

    n = MAX_INCLUDE_DEPTH + 5
    for k in range(n):
        (folder / f"s{k}.toml").write_text(f'include = ["s{k + 1}.toml"]\n' if k + 1 < n else
                                           '[[layer]]\nname = "a"\nmesh = "stone"\nparams = "p.adp"\n')
    with pytest.raises(ad.core.SceneError, match=f"includes nested {MAX_INCLUDE_DEPTH} deep"):
        ad.Scene.load(folder / "s0.toml")
    assert ad.Scene.load(folder / f"s{n - MAX_INCLUDE_DEPTH + 1}.toml").count == 20  # within the limit: fine
    # 24 files each including the next one TWICE (no cycle): 2**24 reads before; each is read once now,
    # and the layers of a file included twice are in the scene once
    for k in range(24):
        (folder / f"d{k}.toml").write_text(f'include = ["d{k + 1}.toml", "d{k + 1}.toml"]\n')
    (folder / "d24.toml").write_text('[[layer]]\nname = "a"\nmesh = "stone"\nparams = "p.adp"\n')
    from axialdeform.core.io.scene import MAX_INCLUDED_FILES, parse_scene

    recipe = parse_scene(folder / "d0.toml")
    assert len(recipe.included) == 25 and [layer.name for layer in recipe.layers] == ["a"]
    assert ad.Scene.load(folder / "d0.toml").count == 20
    # a scene that reads more files than the bound, side by side (no deep chain): refused in one line
    wide = MAX_INCLUDED_FILES + 2
    for k in range(wide):
        (folder / f"w{k}.toml").write_text("")
    (folder / "wide.toml").write_text("include = [" + ", ".join(f'"w{k}.toml"' for k in range(wide)) + "]\n")
    with pytest.raises(ad.core.SceneError, match=f"wide.toml:1: key 'include': the scene reads more than {MAX_INCLUDED_FILES}"):
        ad.Scene.load(folder / "wide.toml")
    (folder / "deep.toml").write_text("x = " + "[" * 600 + "]" * 600 + "\n")
    with pytest.raises(ad.core.SceneError, match="deep.toml: not a scene file: values nested too deep"):
        ad.Scene.load(folder / "deep.toml")
    refused(run("render", "deep.toml", "-o", "r.png", cwd=folder), "deep.toml", "nested too deep")


def _textured_model(folder: Path) -> None:
    """m.obj -> lib.txt (its material library, a name a parameter file could take) -> tex.png."""
    from PIL import Image

    (folder / "m.obj").write_text("mtllib lib.txt\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                  "usemtl mat\nf 1/1 2/2 3/3\nf 1/1 3/3 4/2\nf 1/1 4/2 2/3\nf 2/1 4/2 3/3\n")
    (folder / "lib.txt").write_text("newmtl mat\nKd 1 1 1\nmap_Kd tex.png\n")
    Image.new("RGB", (4, 4), (200, 100, 50)).save(folder / "tex.png")
    assert {Path(p).name for p in ad.load_mesh(folder / "m.obj").sources} == {"m.obj", "lib.txt", "tex.png"}


def test_no_output_replaces_a_file_an_input_names(folder):
    """Through a material library, a texture, a scene's height map, density map or layer mesh, or a
    symlink to one of them: every command refuses in one line and the file stays what it was."""
    _textured_model(folder)
    ad.write_params(folder / "m.adp", ad.random_params(ad.load_mesh(folder / "m.obj"), 5, seed=2))
    before = {n: (folder / n).read_bytes() for n in ("m.obj", "lib.txt", "tex.png")}
    refused(run("render", "m.obj", "m.adp", "-o", "tex.png", "--size", "32x24", cwd=folder), "tex.png", "input")
    refused(run("random", "m.obj", "-n", "3", "-o", "lib.txt", cwd=folder), "lib.txt", "input")
    # --overwrite replaces an output that exists, never an input
    refused(run("random", "m.obj", "-n", "3", "-o", "lib.txt", "--overwrite", cwd=folder), "lib.txt", "input")
    refused(run("render", "m.obj", "m.adp", "-o", "tex.png", "--overwrite", cwd=folder), "tex.png", "input")
    (folder / "link.png").symlink_to(folder / "tex.png")
    refused(run("render", "m.obj", "m.adp", "-o", "link.png", "--size", "32x24", cwd=folder), "link.png", "input")
    # a scene: its terrain's height map, a layer's density map and a layer's mesh
    from PIL import Image

    Image.fromarray(((np.add.outer(np.arange(16), np.arange(16)) * 8) % 256).astype(np.uint8)).save(folder / "hm.png")
    Image.new("L", (8, 8), 255).save(folder / "density.png")
    shutil.copy(Path(__file__).resolve().parents[1] / "data" / "meshes" / "gltf" / "cubevc.glb", folder / "cube.glb")
    (folder / "s.toml").write_text(
        '[terrain]\nheightmap = "hm.png"\nextent = 8.0\n'
        '[[layer]]\nname = "a"\nmesh = "m.obj"\n[layer.scatter]\ncount = 5\ndensity = "density.png"\n'
        '[[layer]]\nname = "b"\nmesh = "cube.glb"\n[layer.scatter]\ncount = 3\n')
    more = {n: (folder / n).read_bytes() for n in ("hm.png", "density.png")}
    refused(run("render", "s.toml", "-o", "hm.png", "--size", "32x24", cwd=folder), "hm.png", "input")
    refused(run("render", "s.toml", "-o", "density.png", "--size", "32x24", cwd=folder), "density.png", "input")
    (folder / "hm-link.png").symlink_to(folder / "hm.png")
    refused(run("render", "s.toml", "-o", "hm-link.png", "--size", "32x24", cwd=folder), "hm-link.png", "input")
    refused(run("render", "s.toml", "-o", "tex.png", "--size", "32x24", cwd=folder), "tex.png", "input")
    more["cube.glb"] = (folder / "cube.glb").read_bytes()
    refused(run("export", "s.toml", "-o", "cube.glb", cwd=folder), "cube.glb", "input")
    for name, data in {**before, **more}.items():
        assert (folder / name).read_bytes() == data, name
    assert run("render", "s.toml", "-o", "ok.png", "--size", "32x24", cwd=folder).returncode == 0  # the scene is fine


def test_a_page_carries_no_file_from_outside_the_scenes_folder(folder):
    """A scene naming ../ (or an absolute path) would put that file into a page meant to be shared:
    refused in one line unless --allow-outside; the bundled meshes are the package's, always fine."""
    (folder / "inner").mkdir()
    (folder / "inner" / "s.toml").write_text('[[layer]]\nname = "a"\nmesh = "stone"\nparams = "../p.adp"\n')
    refused(run("web", "inner/s.toml", "-o", "page.html", cwd=folder), "inner/s.toml", "outside the scene's folder",
            "--allow-outside")
    assert not (folder / "page.html").exists()
    (folder / "inner" / "t.toml").write_text(f'[[layer]]\nname = "a"\nmesh = "stone"\nparams = "{folder / "p.adp"}"\n')
    refused(run("web", "inner/t.toml", "-o", "page.html", cwd=folder), "outside the scene's folder")
    assert run("web", "inner/s.toml", "-o", "page.html", "--allow-outside", cwd=folder).returncode == 0
    shutil.copy(folder / "p.adp", folder / "inner" / "p.adp")
    (folder / "inner" / "u.toml").write_text('[[layer]]\nname = "a"\nmesh = "stone"\nparams = "p.adp"\n')
    assert run("web", "inner/u.toml", "-o", "page2.html", cwd=folder).returncode == 0


def _existing_output_cases(tmp: Path):
    """Every command that writes, each aimed at a file that exists (and is no input)."""
    ad.write_params(tmp / "p.adp", ad.random_params(ad.load_mesh("stone"), 4, seed=1))
    (tmp / "s.toml").write_text('[[layer]]\nname = "a"\nmesh = "stone"\nparams = "p.adp"\n')
    ad.load_mesh("stone").to_trimesh().export(str(tmp / "v.obj"))
    (tmp / "surface.obj").write_text("v -5 0 -5\nv 5 0 -5\nv 5 0 5\nv -5 0 5\nf 1 3 2\nf 1 4 3\n")
    small = ["--size", "32x24"]
    return {
        "demo": (["demo", "-n", "4", *small, "-o", "{out}"], "out.png"),
        "random": (["random", "stone", "-n", "3", "-o", "{out}"], "out.adp"),
        "scatter": (["scatter", "surface.obj", "stone", "-n", "3", "-o", "{out}"], "out.adp"),
        "render": (["render", "stone", "p.adp", *small, "-o", "{out}"], "out.png"),
        "render scene": (["render", "s.toml", *small, "-o", "{out}"], "out.png"),
        "bake": (["bake", "stone", "p.adp", "-o", "{out}"], "out.npz"),
        "bake scene": (["bake", "s.toml", "-o", "{out}"], "out.npz"),
        "bake folder": (["bake", "stone", "p.adp", "-o", "{out}"], "outdir/instance_000000.obj"),
        "convert": (["convert", "p.adp", "{out}"], "out.txt"),
        "export": (["export", "stone", "p.adp", "-o", "{out}"], "out.glb"),
        "export scene": (["export", "s.toml", "-o", "{out}"], "out.glb"),
        "fit": (["fit", "stone", "v.obj", "-o", "{out}"], "out.adp"),
        "view": (["view", "stone", "p.adp", "--headless", "--frames", "1", *small, "--screenshot", "{out}"], "out.png"),
        "web page": (["web", "stone", "p.adp", "-o", "{out}"], "out.html"),
        "web folder": (["web", "stone", "p.adp", "-o", "{out}"], "site/index.html"),
        "bench --report-from": (["bench", "--report-from", "bench-details.json", "--out", "{out}"], "rep/bench.md"),
    }


EXISTING = ["demo", "random", "scatter", "render", "render scene", "bake", "bake scene", "bake folder", "convert",
            "export", "export scene", "fit", "view", "web page", "web folder", "bench --report-from"]


@pytest.mark.parametrize("case", EXISTING)
def test_one_rule_for_an_output_that_exists(tmp_path, monkeypatch, capsys, case):
    """Every command that writes refuses an output that exists, in one line naming it and --overwrite,
    and leaves it as it was; with --overwrite it replaces it."""
    from axialdeform.cli import main

    monkeypatch.chdir(tmp_path)
    argv, target = _existing_output_cases(tmp_path)[case]
    if case == "bench --report-from":
        import matplotlib  # noqa: F401  the test extra's (axialdeform[bench]): its plots are among the outputs
        shutil.copy(Path(__file__).resolve().parents[2] / "docs" / "benchmarks" / "bench-details.json", tmp_path)
    path = tmp_path / target
    path.parent.mkdir(exist_ok=True)
    path.write_bytes(b"the user's own file\n")
    out = path.parent.name if "folder" in case or case.startswith("bench") else target
    argv = [a.replace("{out}", out) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "exist" in err[0] and "--overwrite" in err[0] and target.split("/")[-1] in err[0], err
    assert path.read_bytes() == b"the user's own file\n"
    assert main([*argv, "--overwrite"]) == 0, capsys.readouterr().err
    assert path.read_bytes() != b"the user's own file\n"

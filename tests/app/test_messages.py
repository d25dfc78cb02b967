"""Messages are one line in the user's words: a file name
with a newline or an escape sequence is printed escaped, and an output in a
missing folder names that folder, never the temporary file."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import axialdeform as ad


def run(*args, cwd):
    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=300)


def test_control_characters_in_a_file_name_are_escaped(tmp_path):
    name = "bad\nname\x1b[31m.adp"
    (tmp_path / name).write_bytes(b"")
    proc = run("info", name, cwd=tmp_path)
    assert proc.returncode == 2
    line = proc.stderr
    assert line.count("\n") == 1 and "\x1b" not in line, repr(line)
    assert "bad\\nname\\x1b[31m.adp" in line


@pytest.mark.parametrize("command", [
    ["random", "stone", "-n", "3", "-o", "missing/p.adp"],
    ["convert", "p.adp", "missing/p.txt"],
    ["export", "stone", "p.adp", "-o", "missing/p.glb"],
])
def test_an_output_in_a_missing_folder_names_the_folder(tmp_path, command):
    ad.write_params(tmp_path / "p.adp", ad.random_params(ad.load_mesh("stone"), 3, seed=1))
    proc = run(*command, cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert "its folder missing does not exist" in proc.stderr and "axtmp" not in proc.stderr, proc.stderr


@pytest.mark.parametrize("command", [["render", "stone", "h.adp", "-o", "h.png", "--size", "32x24"],
                                     ["web", "stone", "h.adp", "-o", "h.html"],
                                     ["view", "stone", "h.adp", "--headless", "--frames", "1", "--size", "32x24"]])
def test_huge_but_finite_parameters_are_named_like_other_bad_values(tmp_path, command):
    params = ad.random_params(ad.load_mesh("stone"), 4, seed=1)
    params[2, 11] = 3e38  # finite float32, but no picture can project it
    ad.write_params(tmp_path / "h.adp", params)
    proc = run(*command, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert "h.adp: instance 2, field py = 3e+38; expected at most 1e+18" in proc.stderr.splitlines()[-1]


def test_a_camera_far_from_the_origin_is_a_camera(tmp_path):
    """Positions a million units out draw (the view's translation is not its conditioning)."""
    params = ad.random_params(ad.load_mesh("stone"), 4, seed=1)
    params[:, 10] += 1e6
    ad.write_params(tmp_path / "far.adp", params)
    proc = run("render", "stone", "far.adp", "-o", "far.png", "--size", "32x24", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("content,words", [
    (b'{"asset": ', "not a glTF file: its JSON is not valid (line 1, column 11"),
    (b"[1, 2]", "not a glTF file: its JSON is a list, expected an object"),
    (b"\xff\xfe{}", "not a glTF file: byte 0 of its JSON is not UTF-8 text"),
])
def test_a_gltf_that_is_not_json_is_said_in_words(tmp_path, content, words):
    """Said before trimesh, which would look for a ``model.gltf`` the input never mentions."""
    (tmp_path / "m.gltf").write_bytes(content)
    proc = run("random", "m.gltf", "-n", "2", "-o", "p.adp", cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert f"m.gltf: {words}" in proc.stderr and "model.gltf" not in proc.stderr and "Error" not in proc.stderr


def test_pygltflib_says_nothing_of_its_own(tmp_path, stone):
    """A GLB that pygltflib warns about (a header version it does not know, an
    unknown chunk) read by the instanced reader: no stray lines, the result."""
    import struct

    from axialdeform.core.io.gltf import export_instanced

    good = tmp_path / "i.glb"
    export_instanced(good, stone, ad.random_params(stone, 2, seed=1))
    data = bytearray(good.read_bytes())
    data[4:8] = struct.pack("<I", 3)  # pygltflib: "does not support version ... larger than v2"
    data += struct.pack("<I", 4) + b"XTRA" + b"\0" * 4  # pygltflib: "Ignoring chunk 2 with unknown type"
    data[8:12] = struct.pack("<I", len(data))
    odd = tmp_path / "odd.glb"
    odd.write_bytes(bytes(data))
    proc = subprocess.run([sys.executable, "-W", "default", "-c",
                           "from axialdeform.core.io.gltf import read_instanced_glb as r; "
                           f"m, p = r({str(odd)!r}); print(p.shape)"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "(2, 16)" and proc.stderr == "", proc.stderr


@pytest.mark.parametrize("argv,words", [
    (["random", "stone", "--axis", "1,0,0,0,1,0,0,0,nan", "-n", "3", "-o", "x.adp"], "argument --axis"),
    (["random", "stone", "-n", "abc", "-o", "x.adp"], "argument -n/--count"),
    (["render", "stone", "p.adp", "--mode", "shiny", "-o", "x.png"], "argument --mode"),
])
def test_a_bad_argument_is_one_line(argv, words, tmp_path):
    """argparse's refusals too: one line naming the argument, exit status 2, no usage block."""
    proc = subprocess.run([sys.executable, "-m", "axialdeform", *argv], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and words in lines[0] and "--help" in lines[0], proc.stderr


def test_an_axes_files_bad_entry_names_the_file(tmp_path):
    (tmp_path / "ax.toml").write_text('[[axis]]\npart = "trunk"\n[[axis]]\npart = "nope"\nparent = "trunk"\n')
    proc = subprocess.run([sys.executable, "-m", "axialdeform", "random", "tree", "--axes", "ax.toml", "-n", "2", "-o",
                           "t.adp"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert "ax.toml: " in lines[0] and "no part 'nope'" in lines[0], lines[0]


def test_no_warning_before_the_error_that_refuses_a_gltf(tmp_path):
    """A glTF with morph targets is drawn in its rest pose, with a warning; one that is refused
    anyway (here: no POSITION data) gets the error alone, not a warning line before it."""
    import json
    import warnings

    import axialdeform as ad

    data = json.loads((Path(__file__).resolve().parents[1] / "data" / "meshes" / "gltf" / "validator"
                       / "valid.gltf").read_text())
    assert any("targets" in p for m in data["meshes"] for p in m["primitives"])  # morph targets
    for m in data["meshes"]:
        for p in m["primitives"]:
            p["attributes"].pop("POSITION", None)
    (tmp_path / "bad.gltf").write_text(json.dumps(data))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(ad.AxialDeformError, match="bad.gltf"):
            ad.load_mesh(tmp_path / "bad.gltf")
    assert [str(w.message) for w in caught if "not supported" in str(w.message)] == []


def test_a_full_disk_is_said_in_words(tmp_path, monkeypatch, capsys):
    """ENOSPC (and its kin) as a sentence naming the file, not 'PATH No space left on device'."""
    import errno

    from axialdeform.cli import main
    from axialdeform.cli import random as random_cmd

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "r.adp"))

    monkeypatch.setattr(random_cmd, "write_param_chunks", full)
    assert main(["random", "stone", "-n", "3", "-o", str(tmp_path / "r.adp")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"axialdeform random: error: {tmp_path / 'r.adp'}: the disk is full; expected room for the output "
                   "(free some space or write elsewhere)"], err


@pytest.mark.parametrize("argv,words", [
    (["render", "stone", "{tmp}/nope.adp", "-o", "{tmp}/x.png"], "nope.adp: no such parameter file"),
    (["render", "stone", "{tmp}/p.adp", "-o", "{tmp}/x.png", "--size", "800"], "size: expected WIDTHxHEIGHT"),
])
def test_options_and_files_are_checked_before_the_mesh_is_loaded(argv, words, tmp_path, monkeypatch, capsys):
    from axialdeform.cli import _common, main

    ad.write_params(tmp_path / "p.adp", ad.random_params(ad.load_mesh("stone"), 3, seed=1))
    monkeypatch.setattr(_common, "load_mesh", lambda *a, **k: pytest.fail("the mesh was loaded first"))
    assert main([a.format(tmp=tmp_path) for a in argv]) == 2
    assert words in capsys.readouterr().err


def test_a_mistyped_bundled_name_says_the_bundled_names():
    with pytest.raises(ad.core.MeshError, match=r"stones: no such mesh file; did you mean the bundled mesh 'stone'\? "
                                                 r"\(bundled: stone, leaf, leafcard, tree\)"):
        ad.load_mesh("stones")

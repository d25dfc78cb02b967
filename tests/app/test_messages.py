"""Messages are one line in the user's words (issue 23, item 7): a file name
with a newline or an escape sequence is printed escaped, and an output in a
missing folder names that folder, never the temporary file."""

from __future__ import annotations

import subprocess
import sys

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

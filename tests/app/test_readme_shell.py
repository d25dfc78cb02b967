"""The README's shell lines that need no display run as written, in a fresh
folder: a newcomer's first commands must work."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BLOCKS = re.findall(r"^```sh\n(.*?)^```", (ROOT / "README.md").read_text(encoding="utf-8"), re.S | re.M)
#: every `axialdeform ...` line of the README but the interactive viewer (a window)
LINES = [cmd for block in BLOCKS for cmd in (line.split("#")[0].strip() for line in block.splitlines())
         if cmd.startswith("axialdeform ") and not (" view " in cmd and "--headless" not in cmd)]


def test_the_readme_has_command_lines():
    assert len(LINES) >= 4, LINES


@pytest.mark.slow
def test_readme_command_lines_run_in_a_fresh_folder(tmp_path):
    (tmp_path / "examples").symlink_to(ROOT / "examples")  # the README's paths are the repository's
    for line in LINES:
        args = shlex.split(line)[1:]
        proc = subprocess.run([sys.executable, "-m", "axialdeform", *args], cwd=tmp_path, capture_output=True,
                              text=True, timeout=600)
        assert proc.returncode == 0, f"{line}\n{proc.stderr}"
        out = args[args.index("-o") + 1] if "-o" in args else None
        if out:
            assert (tmp_path / out).exists() and (tmp_path / out).stat().st_size > 0, line

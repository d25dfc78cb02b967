"""The linters hold the whole tree: ruff (the Python, by pyproject.toml's [tool.ruff]) and ESLint
(the npm module and the page's JavaScript, by js/eslint.config.js).  A finding fails the test with
the linter's own report."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_ruff_finds_nothing():
    r = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "--output-format", "concise", "."],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr


def test_eslint_finds_nothing():
    eslint = ROOT / "js" / "node_modules" / "eslint" / "bin" / "eslint.js"
    assert eslint.is_file(), "js/node_modules/eslint is missing: the README's test command runs `npm ci --prefix js`"
    r = subprocess.run([shutil.which("node"), str(eslint), "-c", "js/eslint.config.js", "js", "axialdeform/web"],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr


def test_the_linters_catch_a_finding(tmp_path):
    """Both really fail: an unused name in a Python and in a JavaScript file."""
    (tmp_path / "bad.py").write_text("import os\n")
    r = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "--isolated", "bad.py"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 1 and "F401" in r.stdout, r.stdout + r.stderr
    eslint = ROOT / "js" / "node_modules" / "eslint" / "bin" / "eslint.js"
    r = subprocess.run([shutil.which("node"), str(eslint), "-c", "js/eslint.config.js", "--stdin", "--stdin-filename",
                        "js/test/probe.mjs"], input="const unused = 1;\n", cwd=ROOT, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 1 and "no-unused-vars" in r.stdout, r.stdout + r.stderr

"""The three layers, read from the source: every import of every module
(top-level or inside functions, relative or absolute) is parsed with ``ast``.

* ``core`` imports nothing from ``gl``, the application (``cli``, ``bench``,
  ``viewer``, ``web``, ``widget``) or moderngl / moderngl_window / glcontext;
* ``gl`` imports nothing from the application, nor argparse or tqdm;
* outside ``cli/`` nothing imports argparse or tqdm or calls ``print(``
  (examples, tools and tests are programs and may).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from helpers.modules import PACKAGE, imported_modules, package_modules

ROOT = Path(__file__).resolve().parents[2]
APPLICATION = ("cli", "bench", "viewer", "web", "widget")
GL_LIBRARIES = ("moderngl", "moderngl_window", "glcontext")
CLI_LIBRARIES = ("argparse", "tqdm")


def calls_print(tree: ast.AST) -> list[int]:
    return [n.lineno for n in ast.walk(tree)
            if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "print"]


def _under(name: str, roots) -> bool:
    return any(name == r or name.startswith(r + ".") for r in roots)


def violations(source: str, module: str, is_package: bool = False) -> list[str]:
    """Every way ``module`` (dotted name, e.g. ``axialdeform.core.mesh``) crosses a layer."""
    tree = ast.parse(source)
    imports = imported_modules(tree, module, is_package)
    layer = module.split(".")[1] if module.count(".") >= 1 else ""
    app = tuple(f"axialdeform.{a}" for a in APPLICATION)
    found = []
    if layer == "core":
        for name in sorted(imports):
            if _under(name, ("axialdeform.gl",) + app + GL_LIBRARIES):
                found.append(f"{module}: the core imports {name}")
    if layer == "gl":
        for name in sorted(imports):
            if _under(name, app + CLI_LIBRARIES):
                found.append(f"{module}: gl imports {name}")
    if layer != "cli":
        for name in sorted(imports):
            if _under(name, CLI_LIBRARIES):
                found.append(f"{module}: {name} outside cli/")
        for line in calls_print(tree):
            found.append(f"{module}:{line}: print( outside cli/")
    return found


def test_the_package_has_the_three_layers():
    names = {m for _, m, _ in package_modules()}
    for layer in ("axialdeform.core", "axialdeform.gl", "axialdeform.cli", "axialdeform.bench", "axialdeform.viewer"):
        assert layer in names


def test_no_module_crosses_a_layer_upwards():
    found = []
    for path, module, is_package in package_modules():
        found += violations(path.read_text(encoding="utf-8"), module, is_package)
    assert found == []


@pytest.mark.parametrize("module,source,expected", [
    ("axialdeform.core.bad", "import moderngl\n", "the core imports moderngl"),
    ("axialdeform.core.bad", "def f():\n    from ..gl import renderer\n", "the core imports axialdeform.gl"),
    ("axialdeform.core.bad", "from .. import gl\n", "the core imports axialdeform.gl"),
    ("axialdeform.core.bad", "from axialdeform.cli import main\n", "the core imports axialdeform.cli"),
    ("axialdeform.core.bad", "import axialdeform.viewer\n", "the core imports axialdeform.viewer"),
    ("axialdeform.core.bad", "from moderngl_window import geometry\n", "the core imports moderngl_window"),
    ("axialdeform.gl.bad", "from ..bench import run_bench\n", "gl imports axialdeform.bench"),
    ("axialdeform.gl.bad", "def f():\n    from tqdm import tqdm\n", "gl imports tqdm"),
    ("axialdeform.gl.bad", "from ..web import x\n", "gl imports axialdeform.web"),
    ("axialdeform.bench.bad", "import argparse\n", "argparse outside cli/"),
    ("axialdeform.viewer", "def f():\n    print('hi')\n", "print( outside cli/"),
    ("axialdeform.core", "from .mesh import load_mesh\nfrom ..gl import camera\n", "the core imports axialdeform.gl"),
])
def test_a_bad_module_is_caught(module, source, expected):
    is_package = module == "axialdeform.core"
    found = violations(source, module, is_package)
    assert any(expected in f for f in found), found


@pytest.mark.parametrize("module,source", [
    ("axialdeform.core.ok", "import numpy\nfrom .mesh import load_mesh\nfrom . import params\n"),
    ("axialdeform.gl.ok", "import moderngl\nfrom ..core.errors import AxialDeformError\n"),
    ("axialdeform.cli.ok", "import argparse\nfrom tqdm import tqdm\nprint('x')\nfrom ..bench import run_bench\n"),
    ("axialdeform.bench.ok", "from ..gl.renderer import AxialRenderer\nfrom .plan import METHODS\n"),
])
def test_a_good_module_passes(module, source):
    assert violations(source, module) == []


def test_the_architecture_page_names_every_module():
    readme = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    missing = [str(p.relative_to(PACKAGE)) for p in sorted(PACKAGE.rglob("*.py"))
               if str(p.relative_to(PACKAGE)) not in readme]
    assert missing == []

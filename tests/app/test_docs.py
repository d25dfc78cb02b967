"""The docs: the API reference builds from the docstrings with ``mkdocs
build --strict`` (a broken link, a missing object or a docstring that does
not parse as numpydoc fails), and every Python block of the docs pages runs."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = sorted((ROOT / "docs").glob("*.md"))
# web.md's blocks are notebook cells, run one after the other in a notebook (tests/web/test_notebook.py
# runs the widget in a real JupyterLab): here they run together, in order, in one interpreter
BLOCKS = [(p.name, i, code) for p in PAGES if p.name != "web.md"
          for i, code in enumerate(re.findall(r"^```python\n(.*?)^```", p.read_text(encoding="utf-8"), re.S | re.M))]
CELLS = re.findall(r"^```python\n(.*?)^```", (ROOT / "docs" / "web.md").read_text(encoding="utf-8"), re.S | re.M)


@pytest.mark.slow
def test_the_api_reference_builds_strict(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-4000:]
    page = (tmp_path / "site" / "api" / "scene" / "index.html").read_text(encoding="utf-8")
    for name in ("Scene", "Look", "render_image", "light_dir"):  # generated from the docstrings
        assert name in page, name


def test_every_api_page_is_in_the_navigation():
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    for page in sorted((ROOT / "docs" / "api").glob("*.md")):
        assert f"api/{page.name}" in nav, page.name


@pytest.mark.slow
@pytest.mark.parametrize("page,index,code", BLOCKS, ids=[f"{p}-{i}" for p, i, _ in BLOCKS])
def test_docs_python_block_runs(page, index, code, tmp_path):
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]


@pytest.mark.slow
def test_the_notebook_cells_run_in_order(tmp_path):
    """The notebook page's cells (show, update, a scene file) run one after the other."""
    assert len(CELLS) >= 2
    (tmp_path / "examples").symlink_to(ROOT / "examples")  # the cells' paths are the repository's
    proc = subprocess.run([sys.executable, "-c", "\n".join(CELLS)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]


def test_the_products_names_have_numpydoc_sections():
    """Every function and class of the top level that takes arguments documents them
    (``Parameters``, or ``Attributes`` for a value object): the API reference reads them."""
    import inspect
    import warnings

    import axialdeform as ad

    missing = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in ad.__all__:
            obj = getattr(ad, name)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            try:
                takes = [p for p in inspect.signature(obj).parameters if p not in ("self", "cls")]
            except ValueError:  # an exception class: no signature of its own
                continue
            doc = inspect.getdoc(obj) or ""
            if takes and "Parameters\n----------" not in doc and "Attributes\n----------" not in doc:
                missing.append(name)
    assert missing == [], missing


#: a citation of the project's tracker ("issue 16", "Issue #32"): the docs and the code say what a change is
TRACKER = re.compile(r"\b[Ii]ssues? ?#?\d+\b")


def test_docs_and_sources_cite_no_tracker():
    """The docs, README files, sources, shaders, tools and examples say what they mean, not which ticket
    brought it: a reader of the repository has no tracker."""
    folders = ("docs", "axialdeform", "glsl", "js/src", "js/test", "tools", "examples")
    files = [ROOT / "README.md", ROOT / "js" / "README.md"]
    files += [p for f in folders for p in (ROOT / f).rglob("*")
              if p.suffix in (".md", ".py", ".js", ".mjs", ".glsl", ".vert", ".frag", ".geom", ".comp", ".toml", ".html")
              and "node_modules" not in p.parts and "vendor" not in p.parts]
    found = [f"{p.relative_to(ROOT)}:{n}" for p in files
             for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1) if TRACKER.search(line)]
    assert found == []
    assert TRACKER.search("the goal (issue 32): median") and TRACKER.search("see Issue #7")  # it can fail


def _public_callables():
    """``(label, function, its docs)`` of every name of ``axialdeform`` and every public method of its classes."""
    import inspect

    import axialdeform as ad

    for name in ad.__all__:
        obj = getattr(ad, name)
        if inspect.isclass(obj):
            yield name, obj.__init__ if "__init__" in vars(obj) else None, (obj.__doc__ or "") + (obj.__init__.__doc__ or "")
            for attr, value in vars(obj).items():
                fn = value.__func__ if isinstance(value, (classmethod, staticmethod)) else value
                if not attr.startswith("_") and inspect.isfunction(fn):
                    yield f"{name}.{attr}", fn, fn.__doc__ or ""
        elif callable(obj):
            yield name, obj, obj.__doc__ or ""


def test_every_public_callable_documents_every_parameter():
    """The API's own reference: each parameter of every public function and method (and of a class's
    constructor, its dataclass fields included) is named in its docstring."""
    import inspect

    missing = []
    for label, fn, doc in _public_callables():
        if fn is None:
            continue
        try:
            params = inspect.signature(fn).parameters.values()
        except (TypeError, ValueError):
            continue
        for p in params:
            name = p.name.lstrip("_")
            if p.name in ("self", "cls") or p.kind == p.VAR_POSITIONAL:
                continue
            if not re.search(rf"\b{re.escape(name)}\b", doc):
                missing.append(f"{label}: {p.name}")
    assert missing == []
    assert any(label == "render_image" for label, _, _ in _public_callables())  # it looks where it should

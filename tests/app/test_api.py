"""The curated API: a small top level (the product), every other public name
listed by the ``__init__`` of its layer and living in the module named there,
old top-level names kept one release as deprecated aliases."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

import axialdeform as ad

PACKAGE = Path(ad.__file__).resolve().parent


def test_the_top_level_is_small_and_every_name_resolves():
    assert len(ad.__all__) <= 25, ad.__all__
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # none of them is a deprecated alias
        for name in ad.__all__:
            assert getattr(ad, name) is not None, name


@pytest.mark.parametrize("layer", ["core", "gl"])
def test_each_layer_lists_its_names_and_each_has_one_home(layer):
    """Every name a layer's ``__init__`` lists is defined (not imported) in
    the module it names, and appears in that module's ``__all__``."""
    pkg = importlib.import_module(f"axialdeform.{layer}")
    assert pkg.__all__, layer
    for name in pkg.__all__:
        home = pkg._NAMES[name]
        module = importlib.import_module(f"axialdeform.{layer}.{home}")
        assert name in module.__all__, f"{name} is not in axialdeform.{layer}.{home}.__all__"
        tree = ast.parse((PACKAGE / layer / (home.replace(".", "/") + ".py")).read_text(encoding="utf-8"))
        defined = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
        defined |= {t.id for n in tree.body if isinstance(n, (ast.Assign, ast.AnnAssign))
                    for t in (n.targets if isinstance(n, ast.Assign) else [n.target]) if isinstance(t, ast.Name)}
        imported = {a.asname or a.name for n in tree.body if isinstance(n, ast.ImportFrom) for a in n.names}
        # a name re-exported from its real home (record columns through params) is listed under that home
        assert name in defined or name in imported, f"{name}: not defined in axialdeform.{layer}.{home}"
        assert getattr(pkg, name) is getattr(module, name)


def test_old_top_level_names_warn_and_name_their_new_home():
    for old, new in ad._DEPRECATED.items():
        with pytest.warns(DeprecationWarning, match=f"axialdeform.{old} is deprecated.*use {new.replace('.', '[.]')}"):
            value = getattr(ad, old)
        home, _, attr = new.rpartition(".")
        assert value is getattr(importlib.import_module(home), attr)
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        _ = ad.no_such_name


def test_importing_the_package_stays_light():
    code = ("import sys, axialdeform\n"
            "print(','.join(m for m in ('trimesh', 'moderngl_window', 'scipy', 'PIL', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", out

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

import numpy as np
import pytest

import axialdeform as ad

PACKAGE = Path(ad.__file__).resolve().parent


def test_the_top_level_is_small_and_every_name_resolves():
    assert len(ad.__all__) <= 26, ad.__all__  # 25, then learn_layer (scenery by example)
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


def test_fields_as_keywords_still_work_with_a_deprecation_warning(ctx, stone):
    """Options come in one spelling, the value objects; the keyword soup of earlier releases still gives the same
    result for one release, with a DeprecationWarning that names the value object and points at the caller."""
    old_spelling = {"bend": 0.3}
    with pytest.warns(DeprecationWarning, match=r"random_params\(bend=\.\.\.\): .*variation=axialdeform\.Variation") as rec:
        old = ad.random_params(stone, 20, seed=3, **old_spelling)
    assert rec[0].filename == __file__  # the user's line, not the library's
    np.testing.assert_array_equal(old, ad.random_params(stone, 20, seed=3, variation=ad.Variation(bend=0.3)))
    with pytest.warns(DeprecationWarning, match=r"iter_random_params\(twist=\.\.\.\)") as rec:
        pieces = list(ad.core.variation.iter_random_params(stone, 9, seed=1, chunk=4, **{"twist": 0.4}))
    np.testing.assert_array_equal(np.concatenate(pieces), ad.random_params(stone, 9, seed=1, variation=ad.Variation(twist=0.4)))
    heights = np.zeros((8, 8))
    place = ad.core.Placement(min_distance=0.5, extent=10.0)
    old_spelling = {"min_distance": 0.5, "extent": 10.0}
    with pytest.warns(DeprecationWarning, match=r"scatter\(min_distance=\.\.\., extent=\.\.\.\): .*=axialdeform\.core\.Placement") as rec:
        old = ad.scatter(heights, stone, 12, ad.Variation(bend=0.2), seed=2, **old_spelling)
    assert rec[0].filename == __file__
    np.testing.assert_array_equal(old, ad.scatter(heights, stone, 12, ad.Variation(bend=0.2), place, seed=2))
    params = ad.random_params(stone, 3, seed=1)
    with pytest.warns(DeprecationWarning, match=r"render_image\(up=\.\.\.\): .*options=axialdeform\.RenderOptions") as rec:
        old = ad.render_image(stone, params, (64, 48), look=ad.Look(fast=True), ctx=ctx, **{"up": "z"})
    assert rec[0].filename == __file__
    new = ad.render_image(stone, params, (64, 48), look=ad.Look(fast=True), ctx=ctx, options=ad.RenderOptions(up="z"))
    np.testing.assert_array_equal(old, new)
    with pytest.warns(DeprecationWarning, match=r"AxialRenderer\(culling=\.\.\.\)") as rec:
        ad.AxialRenderer(ctx, stone, params, **{"culling": False}).release()
    assert rec[0].filename == __file__


def test_the_viewer_takes_its_settings_as_one_value(stone):
    """Viewer.create's own settings are ONE value (ViewerSettings); as keywords they still work, with a warning."""
    from axialdeform.viewer import Viewer, ViewerSettings

    params = ad.random_params(stone, 10, seed=2)
    with pytest.warns(DeprecationWarning, match=r"Viewer\.create\(seed=\.\.\., mode=\.\.\.\): .*ViewerSettings") as rec:
        v = Viewer.create(stone, params, headless=True, size=(48, 32), **{"seed": 7, "mode": "wireframe"})
    assert rec[0].filename == __file__
    try:
        assert v.seed == 7 and v.mode == "wireframe"
    finally:
        v.release()
        v.wnd.destroy()
    v = Viewer.create(stone, params, headless=True, size=(48, 32), settings=ViewerSettings(seed=7, mode="wireframe"))
    try:
        assert v.seed == 7 and v.mode == "wireframe"
    finally:
        v.release()
        v.wnd.destroy()
    with pytest.raises(ad.core.ArgumentError, match="settings: expected an axialdeform.viewer.ViewerSettings"):
        Viewer.create(stone, params, headless=True, size=(48, 32), settings={"seed": 7})

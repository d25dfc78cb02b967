"""One table, one generator: the recipe's keys (core/recipe.py), the record (core/record.py) and the wind's
uniforms (core/wind.py) are written into the JavaScript module, its types, the glTF extension's schema, the
docs and glsl/scene.vert's declarations by tools/make_tables.py,
whose --check fails when a written file drifts; the two readers test a key's kind by one rule."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from axialdeform.core import recipe as R
from axialdeform.core.errors import ParamError
from axialdeform.core.generate import Generate, recipe_json

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "make_tables.py"
WRITTEN = ("js/src/core/record.js", "js/src/index.d.ts", "docs/gltf/AXIALDEFORM_bend/schema/node.AXIALDEFORM_bend.schema.json",
           "docs/generate.md", "glsl/scene.vert")


def _tool():
    spec = importlib.util.spec_from_file_location("make_tables", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _run(*args):
    return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True)


def test_the_written_files_are_what_the_tables_give():
    done = _run("--check")
    assert done.returncode == 0, done.stderr


def test_check_fails_on_drift_and_a_run_writes_them_back(tmp_path):
    for rel in WRITTEN + ("glsl/generate.glsl",):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / rel, tmp_path / rel)
    dts = tmp_path / "js/src/index.d.ts"
    dts.write_text(dts.read_text().replace("  tint_hue?: number;\n", ""))
    schema = tmp_path / WRITTEN[2]
    schema.write_text(schema.read_text().replace('"exclusiveMaximum": 1', '"maximum": 1'))
    vert = tmp_path / "glsl/scene.vert"
    vert.write_text(vert.read_text().replace("uniform float u_wind_gust;", "uniform float u_wind_gusts;"))
    done = _run("--check", "--root", str(tmp_path))
    assert done.returncode == 1
    assert "index.d.ts" in done.stderr and "schema.json" in done.stderr and "scene.vert" in done.stderr
    assert "record.js" not in done.stderr
    assert _run("--root", str(tmp_path)).returncode == 0
    assert _run("--check", "--root", str(tmp_path)).returncode == 0
    for rel in WRITTEN:
        assert (tmp_path / rel).read_text() == (ROOT / rel).read_text(), rel


def test_a_new_key_in_the_table_reaches_every_written_file(monkeypatch):
    """A row added to RECIPE is in the module's table, its type, the schema (recipe and numbers) and the docs."""
    tool = _tool()
    row = R.RecipeKey("wobble", "amount", 0.0, "how much each instance wobbles", True, uniform="wobble")
    monkeypatch.setattr(tool, "RECIPE", R.RECIPE + (row,))
    monkeypatch.setattr(tool, "struct_fields", lambda text: [("seed", "uint"), ("wobble", "float")])
    out = tool.outputs(ROOT)
    by = {str(k): v for k, v in out.items()}
    assert '"name": "wobble", "kind": "amount"' in by["js/src/core/record.js"]
    assert "  wobble?: number;" in by["js/src/index.d.ts"] and "  wobble: number;" in by["js/src/index.d.ts"]
    schema = json.loads(by[WRITTEN[2]])["properties"]["generate"]["properties"]
    assert schema["recipe"]["properties"]["wobble"]["maximum"] == 1
    assert schema["uniforms"]["properties"]["wobble"] == {"type": "number", "minimum": 0, "maximum": 1}
    assert "wobble" not in schema["uniforms"]["required"]  # a file written before it still reads
    assert "| `wobble` | an amount in [0, 1] | `0` | how much each instance wobbles | yes |" in by["docs/generate.md"]


def test_generate_is_the_table():
    """Generate's fields are RECIPE's keys in order, with their defaults; recipe_json carries the json ones."""
    fields = dataclasses.fields(Generate)
    assert [f.name for f in fields] == [k.name for k in R.RECIPE]
    for f, k in zip(fields, R.RECIPE):
        assert (f.default is dataclasses.MISSING) == (k.default is R.REQUIRED)
        if k.default is not R.REQUIRED:
            assert f.default == k.default
    assert list(recipe_json(Generate(rate=1.0), 3.0)) == [k.name for k in R.RECIPE if k.json] + ["reach"]
    for k in R.RECIPE:
        assert k.kind in R.KINDS
        assert k.name in Generate.__doc__


SAMPLES = [0, 0.5, 1, 1.5, -1, 4294967296, 3, True, None, "bottom", "top", math.inf, [], [0.5], [0.2, 0.1], [0.1, 0.2],
           [0.0, 95.0], [-1.0, 2.0], [0.5, 0.5, 0.5], [2.0, 0.5, 0.5], [0.1, 0.2, 0.3, 0.4], "x"]


@pytest.mark.parametrize("kind", sorted(R.KINDS))
def test_the_module_tests_each_kind_by_the_python_rule(kind):
    """js/src/core/limits.js's accepts gives the verdict of core.recipe.accepts on the same values."""
    script = ("import { accepts } from './js/src/core/limits.js';\n"
              f"const values = {json.dumps([v if v != math.inf else 'INF' for v in SAMPLES])}"
              ".map((v) => (v === 'INF' ? Infinity : v));\n"
              f"console.log(JSON.stringify(values.map((v) => accepts({json.dumps(kind)}, v))));\n")
    done = subprocess.run(["node", "--input-type=module", "-e", script], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    js = json.loads(done.stdout)
    py = [R.accepts(kind, tuple(v) if isinstance(v, list) else v) for v in SAMPLES]
    assert js == py, [(v, a, b) for v, a, b in zip(SAMPLES, py, js) if a != b]
    assert any(py) and not all(py)


def test_a_key_is_refused_by_its_kind():
    with pytest.raises(ParamError, match=r"generate: taper: expected a number in \[0, 1\), found 1\.0"):
        Generate(rate=1.0, taper=1.0)
    with pytest.raises(ParamError, match="generate: anchor: expected one of bottom, center, origin"):
        Generate(rate=1.0, anchor="top")
    assert Generate(rate=1.0, bend=[0.2]).bend == 0.2 and Generate(rate=1.0, bend=[0.2, 0.1]).bend == (0.2, 0.1)


def test_the_wind_uniforms_are_the_table(ctx):
    """What a windy program is given is core.wind's table: every name declared, and nothing else of the wind."""
    import axialdeform as ad
    from axialdeform.core.wind import WIND_UNIFORMS, Wind
    from axialdeform.gl.shaders import build_program

    program = build_program(ctx, "scene.vert", "scene.frag", defines={"AXIAL_WIND": "1"})
    assert list(Wind(strength=0.2).uniforms(1.5)) == [f"u_wind_{n}" for n, _, _ in WIND_UNIFORMS]
    for name in Wind(strength=0.2).uniforms(1.5):
        assert name in program, name
    assert ad.Wind(strength=0.2, wavelength=4.0).uniforms(0.0)["u_wind_wavenumber"] == 0.25
    program.release()

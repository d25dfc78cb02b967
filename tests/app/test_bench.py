"""``axialdeform bench --quick``: structure of the outputs, never speed.

One quick run (through the CLI, as a subprocess) is shared by the tests of
this module; the Python API is checked on a tiny run of its own.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import axialdeform as ad
from axialdeform import bench

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    cache = tmp_path_factory.mktemp("bench-cache")
    proc = subprocess.run(
        [sys.executable, "-m", "axialdeform", "bench", "--quick", "--no-progress", "--out", str(out / "report"),
         "--json", str(out / "bench.json"), "--cache", str(cache)],
        capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out, cache, proc


@pytest.mark.slow
def test_json_records_have_exactly_the_keys(quick):
    out, _, _ = quick
    records = json.loads((out / "bench.json").read_text())
    assert isinstance(records, list)
    assert len(records) == len(bench.METHODS) * len(bench.QUICK_COUNTS) * len(bench.BENCH_MODES)
    seen = set()
    for r in records:
        assert set(r) == set(bench.RECORD_KEYS)
        assert r["method"] in ("same", "loaded", "axial", "axial-quantized")
        assert r["mode"] in ("solid", "wireframe")
        assert r["count"] in bench.QUICK_COUNTS
        assert isinstance(r["file_bytes"], int) and r["file_bytes"] > 0
        for k in ("first_frame_s", "frame_s", "shapes_per_s"):
            assert isinstance(r[k], float) and r[k] > 0
        assert r["shapes_per_s"] == pytest.approx(r["count"] / r["frame_s"])
        seen.add((r["method"], r["count"], r["mode"]))
    assert len(seen) == len(records)


@pytest.mark.slow
def test_file_bytes_relationships(quick):
    out, _, _ = quick
    records = json.loads((out / "bench.json").read_text())
    by = {(r["method"], r["count"], r["mode"]): r["file_bytes"] for r in records}
    mesh_bytes = ad.core.bundled_mesh_path("stone").stat().st_size
    header, trailer, table = 96, 4, 128  # binary .adp: header, CRC-32, quantization table
    for mode in bench.BENCH_MODES:
        # the same files are read in both modes
        assert by[("same", 100, mode)] == by[("same", 1000, mode)] == mesh_bytes
        assert by[("loaded", 1000, mode)] > by[("loaded", 100, mode)] > by[("axial", 100, mode)]
        for n in bench.QUICK_COUNTS:
            assert by[("axial", n, mode)] == mesh_bytes + header + 64 * n + trailer
            assert by[("axial-quantized", n, mode)] == mesh_bytes + header + table + 32 * n + trailer
            assert by[("loaded", n, mode)] > 10 * by[("axial", n, mode)]


@pytest.mark.slow
def test_axial_bytes_are_mesh_plus_param_file(quick):
    _, cache, _ = quick
    records = json.loads((quick[0] / "bench.json").read_text())
    mesh_bytes = ad.core.bundled_mesh_path("stone").stat().st_size
    for n in bench.QUICK_COUNTS:
        (folder,) = [p for p in cache.iterdir() if p.name.startswith(f"stone-{n}-")]
        adp, adpq = folder / "params.adp", folder / "params-quantized.adp"
        assert ad.read_params(adp).shape == (n, 16)
        assert ad.read_params(adpq).shape == (n, 16)
        objs = sorted((folder / "objs").iterdir())
        assert len(objs) == n  # one real OBJ file per instance
        r = {(x["method"], x["mode"]): x["file_bytes"] for x in records if x["count"] == n}
        assert r[("axial", "solid")] == mesh_bytes + adp.stat().st_size
        assert r[("axial-quantized", "solid")] == mesh_bytes + adpq.stat().st_size
        assert r[("loaded", "solid")] == sum(p.stat().st_size for p in objs)


@pytest.mark.slow
def test_loaded_files_are_the_cpu_deformed_instances(quick):
    _, cache, _ = quick
    (folder,) = [p for p in cache.iterdir() if p.name.startswith("stone-100-")]
    stone = ad.load_mesh("stone")
    params = ad.read_params(folder / "params.adp", stone)
    positions, normals = ad.deform(stone.axis, stone.positions, stone.normals, params[[0, 57]])
    for k, i in enumerate((0, 57)):
        m = ad.load_mesh(folder / "objs" / f"instance_{i:06d}.obj")
        assert m.vertex_count == stone.vertex_count
        assert (m.faces == stone.faces).all()
        assert abs(m.positions - positions[k]).max() < 1e-6


@pytest.mark.slow
def test_report_structure(quick):
    out, _, _ = quick
    report = (out / "report" / "bench.md").read_text()
    for heading in ("## Machine and settings", "## Goals", "## Table 1", "## Table 2", "## Time to the first frame",
                    "## Time per later frame", "## Ratios", "## Where the first frame's time goes", "## Fig. 9",
                    "## Deformation throughput", "## Paired frame times"):
        assert heading in report, heading
    # the thesis's numbers beside ours
    for thesis in ("103906", "1450", "9100", "7120", "8900", "4.65"):
        assert thesis in report, thesis
    assert "GL renderer:" in report and "CPU:" in report
    assert "axialdeform bench --quick" in report  # the exact command
    for method in bench.METHODS:
        assert f"| {method} |" in report
    details = json.loads((out / "report" / "bench-details.json").read_text())
    assert details["leaf"]["count"] == 1000
    assert {g["goal"] for g in details["goals"]} >= {"axial frame_s / same frame_s",
                                                     "axial first_frame_s / same first_frame_s"}
    # the first-frame goal at every count and mode, its numbers from the records
    records = {(r["method"], r["count"], r["mode"]): r for r in json.loads((out / "bench.json").read_text())}
    ff = [g for g in details["goals"] if g["goal"] == "axial first_frame_s / same first_frame_s"]
    assert {(g["count"], g["mode"]) for g in ff} == {(c, m) for c in bench.QUICK_COUNTS for m in bench.BENCH_MODES}
    for g in ff:
        a, s = records[("axial", g["count"], g["mode"])], records[("same", g["count"], g["mode"])]
        assert g["measured"] == pytest.approx(a["first_frame_s"] / s["first_frame_s"], abs=6e-4)
        assert g["extra_ms"] == pytest.approx((a["first_frame_s"] - s["first_frame_s"]) * 1e3, abs=1e-3)
        assert g["met"] == (g["measured"] <= 1.05)
    assert {r["engine"] for r in details["throughput"]} == {"cpu (numpy deform)", "gpu (AxialRenderer.capture)"}
    assert {r["mode"] for r in details["paired"]} == set(bench.BENCH_MODES)
    # the same parameters give the same shapes: CPU-deformed files against the vertex shader, wireframe
    (wire,) = [r for r in details["pictures"] if r["mode"] == "wireframe"]
    assert wire["differing_pixels"] < 0.01


@pytest.mark.slow
def test_plots_are_pngs(quick):
    out, _, _ = quick
    report = (out / "report" / "bench.md").read_text()
    for name in ("fig5-first-frame.png", "fig6-frame-time.png"):
        path = out / "report" / name
        assert path.read_bytes()[:8] == PNG_MAGIC
        assert f"({name})" in report
    frames = sorted(p.name for p in (out / "report" / "frames").iterdir())
    assert "leaf-1000-solid.png" in frames
    for method in bench.METHODS:
        assert f"{method}-1000-solid.png" in frames
    assert not list((out / "report").glob("*.part"))  # atomic writes leave nothing behind


@pytest.mark.slow
def test_python_api_returns_the_records(tmp_path):
    records = bench.run_bench(counts=(20,), modes=("wireframe",), methods=("axial", "loaded"), frames=2, warmup=0,
                              repeats=1, size=(64, 48), cache=tmp_path, leaf=False, throughput=False, progress=False)
    assert [(r["method"], r["count"], r["mode"]) for r in records] == [("loaded", 20, "wireframe"),
                                                                      ("axial", 20, "wireframe")]
    assert all(list(r) == list(bench.RECORD_KEYS) for r in records)


def test_bad_method_is_an_axialdeform_error(tmp_path):
    with pytest.raises(ad.AxialDeformError, match="method"):
        bench.run_bench(methods=("fastest",), cache=tmp_path, progress=False)


def test_cli_registers_bench():
    from axialdeform.cli import COMMANDS, build_parser
    from axialdeform.cli import bench as cli_bench

    assert "bench" in COMMANDS
    args = build_parser().parse_args(["bench", "--quick"])
    assert args.handler is cli_bench.run
    assert args.out is None  # resolved to ./axialdeform-bench/ by the handler


@pytest.mark.slow
def test_children_import_the_parents_axialdeform(tmp_path, monkeypatch):
    """Run from a folder holding something else called axialdeform (a source
    checkout, say): the children must still import what the parent imports."""
    decoy = tmp_path / "cwd" / "axialdeform"
    decoy.mkdir(parents=True)
    (decoy / "__init__.py").write_text("raise ImportError('the decoy axialdeform was imported')\n")
    monkeypatch.chdir(decoy.parent)
    records = bench.run_bench(counts=(10,), modes=("solid",), methods=("axial",), frames=1, warmup=0, repeats=1,
                              size=(32, 24), cache=tmp_path / "cache", leaf=False, throughput=False, progress=False)
    assert [r["method"] for r in records] == ["axial"]

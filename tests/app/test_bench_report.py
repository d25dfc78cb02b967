"""The bench report states only what was measured: its numbers come from the
measurements (checked here against the committed measurements and against
synthetic ones), it renders again from a saved bench-details.json, and a
bench stopped with Ctrl-C keeps what it measured."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import axialdeform as ad
from axialdeform.bench import report, stats
from axialdeform.cli import main

ROOT = Path(__file__).resolve().parents[2]
COMMITTED = ROOT / "docs" / "benchmarks" / "bench-details.json"


@pytest.fixture(scope="module")
def details():
    return report.load_details(COMMITTED)


def _case(method, count, mode, first, frame=0.01, file_bytes=1000, stages=None):
    stages = stages or {"imported": 0.1, "context": 0.15, "read": 0.2, "uploaded": 0.21, "first_frame": first}
    return {"method": method, "count": count, "mode": mode, "file_bytes": file_bytes, "first_frame_s": first,
            "frame_s": frame, "shapes_per_s": count / frame, "repeats": 3, "stages_s": stages,
            "first_frame_min_s": first, "first_frame_max_s": first}


def test_first_frame_goal_at_every_count_from_the_numbers():
    st = [_case("same", 10, "solid", 0.400), _case("axial", 10, "solid", 0.410),
          _case("same", 20, "solid", 0.400), _case("axial", 20, "solid", 0.460),
          _case("same", 20, "wireframe", 0.500), _case("axial", 20, "wireframe", 0.450)]
    goals = [g for g in stats.goals(st, None, 100) if g["goal"] == "axial first_frame_s / same first_frame_s"]
    got = {(g["count"], g["mode"]): (g["measured"], g["met"], g["extra_ms"]) for g in goals}
    assert got == {(10, "solid"): (1.025, True, pytest.approx(10.0)),
                   (20, "solid"): (1.15, False, pytest.approx(60.0)),
                   (20, "wireframe"): (0.9, True, pytest.approx(-50.0))}


def test_bytes_per_instance_from_the_file_sizes():
    st = [_case("axial", 10, "solid", 1, file_bytes=100 + 96 + 640 + 4),
          _case("axial", 30, "solid", 1, file_bytes=100 + 96 + 1920 + 4)]
    (g,) = [g for g in stats.goals(st, None, 100) if g["goal"].startswith("axial: parameter bytes")]
    assert g["measured"] == 64.0 and g["met"]
    st[1]["file_bytes"] += 20 * 5  # 5 bytes more per instance
    (g,) = [g for g in stats.goals(st, None, 100) if g["goal"].startswith("axial: parameter bytes")]
    assert g["measured"] == 69.0 and not g["met"]


def test_missed_goal_is_explained_by_measured_stages():
    st = [_case("same", 10, "solid", 0.40), _case("axial", 10, "solid", 0.50,
          stages={"imported": 0.1, "context": 0.15, "read": 0.3, "uploaded": 0.31, "first_frame": 0.5})]
    d = {"stats": st, "settings": {"mesh_bytes": 100}}
    d = report.with_goals(d)
    text = "\n".join(report._missed(d, {(s["method"], s["count"], s["mode"]): s for s in st}))
    assert "1.25" in text and "`read`: +100.0 ms" in text


@pytest.mark.slow
def test_report_numbers_are_the_measurements(details, tmp_path):
    path = report.write_report(details, tmp_path)
    text = path.read_text()
    by = {(s["method"], s["count"], s["mode"]): s for s in details["stats"]}
    rows = {}
    for line in text.splitlines():
        m = re.match(r"\| (\d+) \| (solid|wireframe) \| ([\d.]+) \| ([+-][\d.]+) ms \|", line)
        if m:
            rows[(int(m[1]), m[2])] = (float(m[3]), float(m[4]))
    assert len(rows) == len(details["settings"]["counts"]) * len(details["settings"]["modes"])
    for (c, mode), (ratio, extra) in rows.items():
        a, s = by[("axial", c, mode)]["first_frame_s"], by[("same", c, mode)]["first_frame_s"]
        assert ratio == pytest.approx(a / s, abs=6e-4)
        assert extra == pytest.approx((a - s) * 1e3, abs=0.06)
    assert "50" not in re.findall(r">= (\d+)", text)  # the old goal (loaded / axial >= 50x) is gone
    for name in ("fig5-first-frame.png", "fig6-frame-time.png"):
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG"


def test_committed_report_is_rendered_from_the_committed_measurements(details):
    plots = {"fig5": "fig5-first-frame.png", "fig6": "fig6-frame-time.png"}  # the plots: test_report_from_cli
    text = report.render(report.with_goals(details), plots)
    assert text == (COMMITTED.parent / "bench.md").read_text()


def test_performance_page_summary_is_rendered_from_the_committed_measurements(details):
    page = (ROOT / "docs" / "performance.md").read_text()
    m = re.search(r"<!-- bench-summary: start.*?-->\n(.*?)<!-- bench-summary: end -->", page, re.S)
    assert m, "docs/performance.md lacks the bench-summary markers"
    assert m[1] == report.summary(details)


@pytest.mark.slow
def test_report_from_cli(details, tmp_path, capsys):
    src = tmp_path / "in" / "bench-details.json"
    src.parent.mkdir()
    src.write_text(COMMITTED.read_text())
    assert main(["bench", "--report-from", str(src), "--out", str(tmp_path / "out")]) == 0
    assert (tmp_path / "out" / "bench.md").read_text() == (COMMITTED.parent / "bench.md").read_text()
    assert src.read_text() == COMMITTED.read_text()  # the input is never rewritten
    assert main(["bench", "--report-from", str(src)]) == 0  # default: beside the JSON
    assert (src.parent / "bench.md").exists()


@pytest.mark.parametrize("content,message", [("{", "invalid JSON"), ("[]", "expected a JSON object"),
                                             ('{"stats": []}', "missing")])
def test_report_from_bad_json_is_one_line(tmp_path, capsys, content, message):
    bad = tmp_path / "bench-details.json"
    bad.write_text(content)
    assert main(["bench", "--report-from", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(bad) in err and message in err


@pytest.mark.slow
def test_ctrl_c_keeps_what_was_measured(tmp_path):
    """SIGINT during a bench: exit 130, and ./axialdeform-bench/ (the default
    folder) holds the report and JSON of the cases finished before it."""
    proc = subprocess.Popen([sys.executable, "-m", "axialdeform", "bench", "--quick", "--counts", "20,40", "--no-leaf",
                             "--no-throughput", "--no-progress", "--cache", str(tmp_path / "cache")],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            # Ctrl-C as a terminal gives it, even where this run was started with SIGINT ignored
                            # (a background job of a shell without job control): Python then installs no handler
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    out = tmp_path / "axialdeform-bench"
    # the second method's picture exists once its child has drawn: the first case is finished by then
    marker = out / "frames" / "loaded-20-solid.png"
    deadline = time.monotonic() + 240
    while not marker.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert proc.poll() is None, "the bench ended before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr[-2000:]
    assert f"writing the report into {out}" in stderr
    assert "kept what was measured" in stderr
    d = json.loads((out / "bench-details.json").read_text())
    assert d["interrupted"] is True
    cases = {(s["method"], s["count"], s["mode"]) for s in d["stats"]}
    assert ("same", 20, "solid") in cases
    assert len(cases) < 16  # 4 methods x 2 counts x 2 modes were planned
    text = (out / "bench.md").read_text()
    assert "Stopped early" in text and f"{len(cases)} method × count × mode cases" in text


def test_report_without_matplotlib_keeps_the_run(details, tmp_path, monkeypatch):
    """After ``pip install .`` (no ``bench`` extra) the report is written with its
    tables and says how to get the plots: a measured run is never lost."""
    def no_matplotlib():
        raise ad.AxialDeformError("the bench plots need matplotlib")

    monkeypatch.setattr(report, "import_pyplot", no_matplotlib)
    path = report.write_report(details, tmp_path / "out")
    text = path.read_text()
    assert "axialdeform[bench]" in text and "| method | mode |" in text
    assert not list((tmp_path / "out").glob("*.png"))

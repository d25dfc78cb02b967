"""The bench's statistics: records and per-case statistics from the raw
measurements, the paired frame-time ratios, and the goals -- every number
the report states, computed from the measurements only (so that a report can
be rendered again from a saved ``bench-details.json``)."""

from __future__ import annotations

import statistics

import numpy as np

from .plan import BENCH_MODES, METHODS

RECORD_KEYS = ("method", "count", "mode", "file_bytes", "first_frame_s", "frame_s", "shapes_per_s")
#: the thesis's numbers (§3.1): Table 1 in KB by count, Table 2 shapes per second, Fig. 9 seconds
THESIS = {
    "table1_kb": {
        "same": {100: 10.4, 1000: 10.4, 10000: 10.4},
        "loaded": {100: 1039, 1000: 10391, 10000: 103906},
        "axial": {100: 24.8, 1000: 158, 10000: 1450},
    },
    "table2_shapes_per_s": {"same": 9100, "loaded": 7120, "axial": 8900},
    "fig9_leaf_first_frame_s": 4.65,
}
#: limits of the goals: ``first_frame_ratio`` is the thesis's claim (bending costs
#: nothing before the first frame: axial / same = 1.00) with 5 % for noise
GOALS = {"first_frame_ratio": 1.05, "frame_ratio": 1.05, "bytes_lossless": 64, "bytes_quantized": 32, "leaf_s": 0.5}
#: the count of the frame-time goal (or the largest count run)
GOAL_COUNT = 10000
STAGES = ("imported", "context", "read", "uploaded", "first_frame")


def case_stats(m: str, c: int, mode: str, runs: list[dict], frames: list[float] | None, file_bytes: int) -> dict:
    """Statistics of one method x count x mode from its first-frame processes
    (``runs``) and its interleaved frame times (``frames``; ``None`` when the
    run was stopped before them: the first-frame processes' frames are used)."""
    first = [r["first_frame_s"] for r in runs]
    separate = [f for r in runs for f in r["frames"]]
    source = "interleaved" if frames else "separate"
    frame = list(frames) if frames else separate
    rec = {"method": m, "count": c, "mode": mode, "file_bytes": int(file_bytes),
           "first_frame_s": statistics.median(first), "frame_s": statistics.median(frame)}
    rec["shapes_per_s"] = c / rec["frame_s"]
    stage = {k: statistics.median(r["stamps"][k] for r in runs) for k in runs[0]["stamps"]}
    return {**rec, "repeats": len(runs), "frames_interleaved": len(frames or ()), "frame_source": source,
            "first_frame_min_s": min(first), "first_frame_max_s": max(first),
            "frame_q25_s": float(np.quantile(frame, 0.25)), "frame_q75_s": float(np.quantile(frame, 0.75)),
            "stages_s": stage, "info": runs[0]["info"], "first_frame_all_s": first, "frame_all_s": frame,
            "frame_separate_s": statistics.median(r["frame_s"] for r in runs),
            "frame_separate_all_s": [r["frame_s"] for r in runs]}


def sort_key(r: dict):
    return (r["count"], BENCH_MODES.index(r["mode"]), METHODS.index(r["method"]))


def records_from_stats(stats) -> list[dict]:
    """The records (exactly :data:`RECORD_KEYS`) of the statistics, sorted."""
    return [{k: s[k] for k in RECORD_KEYS} for s in sorted(stats, key=sort_key)]


def pair_rows(frames: dict) -> list[dict]:
    """axial against same from the interleaved frames ``{(count, mode): {method: [s, ...]}}``:
    each round drew both within a few milliseconds, so the per-round ratio cancels machine load."""
    rows = []
    for (c, mode), by_method in sorted(frames.items(), key=lambda kv: (kv[0][0], BENCH_MODES.index(kv[0][1]))):
        if "same" not in by_method or "axial" not in by_method:
            continue
        same, axial = np.asarray(by_method["same"]), np.asarray(by_method["axial"])
        ratios = axial / same
        rows.append({"count": c, "mode": mode, "pairs": len(ratios),
                     "same_frame_s": float(np.median(same)), "axial_frame_s": float(np.median(axial)),
                     "ratio_of_medians": float(np.median(axial) / np.median(same)),
                     "median_pair_ratio": float(np.median(ratios)),
                     "pair_ratio_q25": float(np.quantile(ratios, 0.25)),
                     "pair_ratio_q75": float(np.quantile(ratios, 0.75))})
    return rows


def leaf_summary(count: int, file_bytes: int, runs: list[dict]) -> dict:
    first = [r["first_frame_s"] for r in runs]
    return {"count": count, "file_bytes": file_bytes, "first_frame_s": statistics.median(first),
            "first_frame_min_s": min(first), "first_frame_max_s": max(first), "repeats": len(first),
            "frame_s": statistics.median(r["frame_s"] for r in runs),
            "stages_s": {k: statistics.median(r["stamps"][k] for r in runs) for k in runs[0]["stamps"]},
            "thesis_s": THESIS["fig9_leaf_first_frame_s"]}


def bytes_per_instance(stats, method: str, mesh_bytes: int) -> tuple[float, str] | None:
    """Parameter bytes per instance of ``method`` from the records' file
    sizes: the marginal bytes between the two largest counts (the file's fixed
    header cancels), or with one count the whole parameter file / count."""
    sizes = {s["count"]: s["file_bytes"] for s in stats if s["method"] == method}
    if not sizes:
        return None
    cs = sorted(sizes)
    if len(cs) < 2:
        c = cs[0]
        return (sizes[c] - mesh_bytes) / c, f"whole file / count at {c}, header included"
    big, small = cs[-1], cs[-2]
    return (sizes[big] - sizes[small]) / (big - small), f"marginal between {small} and {big}"


def goals(stats, leaf, mesh_bytes: int, paired=None) -> list[dict]:
    """The goals, each ``{goal, target, measured, met, count, mode, note}``:

    * axialdeform's first frame / all-the-same's first frame <= 1.05 at every
      count and mode (the thesis's claim that bending costs nothing before the
      first frame), with axial - same in milliseconds;
    * axial / same time per later frame <= 1.05 at :data:`GOAL_COUNT` (solid);
    * parameter bytes per instance (64 lossless, 32 quantized);
    * the 1 000-leaf scene's first frame <= 0.5 s.
    """
    by = {(s["method"], s["count"], s["mode"]): s for s in stats}
    counts = sorted({s["count"] for s in stats})
    out = []

    def add(name, target, value, ok, count, mode="solid", note="", **more):
        out.append({"goal": name, "target": target, "measured": value, "met": bool(ok), "count": count,
                    "mode": mode, "note": note, **more})

    for c in counts:
        for mode in BENCH_MODES:
            same, axial = by.get(("same", c, mode)), by.get(("axial", c, mode))
            if same and axial:
                ratio = axial["first_frame_s"] / same["first_frame_s"]
                extra_ms = (axial["first_frame_s"] - same["first_frame_s"]) * 1e3
                # the processes ran in turn (same, axial, same, axial, ...): the ratio of each pair
                pairs = [a / s for a, s in zip(axial.get("first_frame_all_s", ()), same.get("first_frame_all_s", ()))]
                spread = (f"; per pair of processes run in turn {min(pairs):.3f} .. {max(pairs):.3f}"
                          if len(pairs) > 1 else "")
                add("axial first_frame_s / same first_frame_s", f"<= {GOALS['first_frame_ratio']}", round(ratio, 3),
                    ratio <= GOALS["first_frame_ratio"], c, mode,
                    f"axial - same = {extra_ms:+.1f} ms (medians of {axial['repeats']} and {same['repeats']} processes"
                    f"{spread})", extra_ms=round(extra_ms, 3))
    if counts:
        c = GOAL_COUNT if GOAL_COUNT in counts else counts[-1]
        same, axial = by.get(("same", c, "solid")), by.get(("axial", c, "solid"))
        if same and axial:
            ratio = axial["frame_s"] / same["frame_s"]
            src = axial.get("frame_source", "interleaved")
            note = ("medians of frames drawn in turn in one process" if src == "interleaved"
                    else "medians of the first-frame processes' later frames (the run stopped before the interleaved ones)")
            pair = next((r for r in paired or () if r["count"] == c and r["mode"] == "solid"), None)
            if pair:
                note += (f"; median of the {pair['pairs']} per-round ratios {pair['median_pair_ratio']:.3f} "
                         f"[quartiles {pair['pair_ratio_q25']:.3f} .. {pair['pair_ratio_q75']:.3f}]")
            add("axial frame_s / same frame_s", f"<= {GOALS['frame_ratio']}", round(ratio, 3),
                ratio <= GOALS["frame_ratio"], c, note=note)
    for m, limit in (("axial", GOALS["bytes_lossless"]), ("axial-quantized", GOALS["bytes_quantized"])):
        b = bytes_per_instance(stats, m, mesh_bytes)
        if b is not None:
            add(f"{m}: parameter bytes per instance", f"<= {limit}", round(b[0], 3), b[0] <= limit,
                max(s["count"] for s in stats if s["method"] == m), note=b[1])
    if leaf:
        add("1000-leaf scene: first frame (s)", f"<= {GOALS['leaf_s']}", round(leaf["first_frame_s"], 3),
            leaf["first_frame_s"] <= GOALS["leaf_s"], leaf["count"])
    return out


def stage_split(stages: dict) -> list[tuple[str, float]]:
    """``[(stage, seconds spent in it), ...]`` from the cumulative stamps."""
    prev, parts = 0.0, []
    for k in STAGES:
        if k in stages:
            parts.append((k, stages[k] - prev))
            prev = stages[k]
    return parts

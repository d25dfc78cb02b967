"""The bench's report: ``bench.md`` and its plots, rendered from the
measurements alone (the ``details`` dict that ``bench-details.json`` holds),
so ``axialdeform bench --report-from bench-details.json`` renders it again.

Every statement of the report is built from numbers of the run; the goals are
computed from the measurements by :func:`axialdeform.bench.stats.goals`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..core.errors import AxialDeformError
from ..core.io import safeio
from ..core.io.atomic import atomic_path, atomic_write_text
from ..core.io.safeio import read_regular
from .plan import BENCH_MODES, METHODS
from .stats import GOAL_COUNT, GOALS, THESIS, goals, records_from_stats, stage_split

_KB = 1024.0
_REQUIRED = ("command", "machine", "settings", "stats", "wall_s")


def load_details(path) -> dict:
    """The measurements of a run, read from its ``bench-details.json``."""

    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise AxialDeformError(f"{path}: cannot read the bench measurements (No such file or directory)")
    # a regular file only (a FIFO or /dev/zero is refused without blocking), of a size whose parse
    # fits in memory (json's objects take up to ~10x the text; a real bench-details.json is < 1 MB)
    data = read_regular(path, max(safeio.memory_available() // 12, 1 << 20), "the JSON written by axialdeform bench "
                                                                       "(bench-details.json)")
    try:
        details = json.loads(bytes(data).decode("utf-8"))
    except (ValueError, UnicodeDecodeError, RecursionError) as exc:
        raise AxialDeformError(f"{path}: expected the JSON written by axialdeform bench (bench-details.json), "
                               f"found invalid JSON ({exc})") from None
    if not isinstance(details, dict):
        raise AxialDeformError(f"{path}: expected a JSON object (bench-details.json), found {type(details).__name__}")
    missing = [k for k in _REQUIRED if k not in details]
    if missing:
        raise AxialDeformError(f"{path}: expected the fields {', '.join(_REQUIRED)} of bench-details.json; "
                               f"missing {', '.join(missing)}")
    if not details["stats"]:
        raise AxialDeformError(f"{path}: stats: expected at least one measured case, found none")
    return details


def with_goals(details: dict) -> dict:
    """``details`` with its goals computed from its measurements."""
    return {**details, "goals": goals(details["stats"], details.get("leaf"), details["settings"]["mesh_bytes"],
                                      details.get("paired"))}


def write_report(details: dict, out, plt=None) -> Path:
    """Write ``bench.md`` and the two plots into the folder ``out``; returns the report's path.
    Without matplotlib (the ``bench`` extra) the report has its tables and says
    where the plots would be: the run is never lost for want of a plot."""

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    try:
        plt = plt or import_pyplot()
    except AxialDeformError:
        plt = None
    plots = plot_files(plt, details["stats"], out) if plt is not None else {
        fig: "plots-need-matplotlib: pip install 'axialdeform[bench]'" for fig in ("fig5", "fig6")}
    path = out / "bench.md"
    atomic_write_text(path, render(with_goals(details), plots))
    return path


def import_pyplot():
    try:
        import matplotlib
    except ImportError:
        raise AxialDeformError(
            "the bench plots need matplotlib, which is not installed; pip install 'axialdeform[bench]'"
        ) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_files(plt, stats, out: Path) -> dict:
    files = {}
    for key, field, title, lo_key, hi_key, bars in (
            ("fig5", "first_frame", "Time to the first frame (cf. thesis Fig. 5)", "first_frame_min_s",
             "first_frame_max_s", "min..max over processes"),
            ("fig6", "frame", "Time per later frame (cf. thesis Fig. 6)", "frame_q25_s", "frame_q75_s",
             "quartiles of the frames")):
        modes = [m for m in BENCH_MODES if any(s["mode"] == m for s in stats)]
        fig, axes = plt.subplots(1, len(modes), figsize=(5.5 * len(modes), 4.2), squeeze=False)
        for ax, mode in zip(axes[0], modes):
            for method in METHODS:
                rows = sorted((s for s in stats if s["method"] == method and s["mode"] == mode), key=lambda s: s["count"])
                if not rows:
                    continue
                x = np.array([s["count"] for s in rows])
                y = np.array([s[f"{field}_s"] for s in rows])
                lo = y - np.array([s[lo_key] for s in rows])
                hi = np.array([s[hi_key] for s in rows]) - y
                ax.errorbar(x, y, yerr=[lo, hi], marker="o", capsize=3, label=method)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("instances")
            ax.set_ylabel(f"seconds (median; bars: {bars})")
            ax.set_title(f"{mode}")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend()
        fig.suptitle(title)
        fig.tight_layout()
        path = out / f"{key}-{'first-frame' if field == 'first_frame' else 'frame-time'}.png"
        with atomic_path(path, suffix=".png") as tmp:
            fig.savefig(tmp, format="png", dpi=100)
        plt.close(fig)
        files[key] = path.name
    return files


def fmt_s(x: float) -> str:
    return f"{x * 1000:.1f} ms" if x < 1 else f"{x:.2f} s"


def _split_text(stages: dict) -> str:
    return ", ".join(f"{k} {v:.3f} s" for k, v in stage_split(stages))


def _missed(details, by) -> list[str]:
    """For each missed goal, the measured numbers behind it (stage by stage where there are stages)."""
    missed = [g for g in details["goals"] if not g["met"]]
    if not missed:
        return []
    out = ["### Missed goals, stage by stage\n"]
    for g in missed:
        c, mode = g["count"], g.get("mode", "solid")
        if g["goal"].startswith("axial first_frame_s"):
            a, s = by[("axial", c, mode)], by[("same", c, mode)]
            sa, ss = dict(stage_split(a["stages_s"])), dict(stage_split(s["stages_s"]))
            diffs = sorted(((sa[k] - ss[k], k) for k in sa if k in ss), reverse=True)
            line = (f"- **axial / same first frame @ {c} {mode}**: {g['measured']} (target {g['target']}); "
                    f"axial {a['first_frame_s']:.3f} s ({_split_text(a['stages_s'])}); same {s['first_frame_s']:.3f} s "
                    f"({_split_text(s['stages_s'])})")
            if diffs:
                line += f"; the largest difference is in `{diffs[0][1]}`: {diffs[0][0] * 1e3:+.1f} ms"
            spread = (f"; the processes' spread: axial {a['first_frame_min_s']:.3f} .. {a['first_frame_max_s']:.3f} s, "
                      f"same {s['first_frame_min_s']:.3f} .. {s['first_frame_max_s']:.3f} s")
            out.append(line + spread + ".")
        elif g["goal"].startswith("1000-leaf") and details.get("leaf"):
            out.append(f"- **1000-leaf first frame**: {g['measured']} s (target {g['target']} s); "
                       f"{_split_text(details['leaf']['stages_s'])}.")
        else:
            out.append(f"- **{g['goal']} @ {c}**: measured {g['measured']}, target {g['target']}"
                       + (f" ({g['note']})" if g.get("note") else "") + ".")
    out.append("")
    return out


def _cell(x, fmt="{:.3f}"):
    return "-" if x is None else fmt.format(x)


def summary(details: dict) -> str:
    """The summary in docs/performance.md of a run: the table at the goal count (solid) and
    the goals' sentences, every number from ``details``."""
    details = with_goals(details)
    st = details["stats"]
    by = {(s["method"], s["count"], s["mode"]): s for s in st}
    counts = sorted({s["count"] for s in st})
    c = GOAL_COUNT if GOAL_COUNT in counts else counts[-1]
    names = {"same": "all the same (no bend)", "loaded": f"load every one ({c:,} OBJ files)",
             "axial": "**axialdeform** (64 B / instance)", "axial-quantized": "**axialdeform, quantized** (32 B / instance)"}
    L = [f"At {c:,} stones, solid:\n", "| method | data read before the first frame | first frame | later frame | shapes / s |",
         "|---|---:|---:|---:|---:|"]
    for m in METHODS:
        s = by.get((m, c, "solid"))
        if s:
            L.append(f"| {names[m]} | {s['file_bytes'] / _KB:,.1f} KB | {s['first_frame_s']:.2f} s | "
                     f"{s['frame_s'] * 1e3:.1f} ms | {s['shapes_per_s']:,.0f} |")
    t1, t2 = THESIS["table1_kb"], THESIS["table2_shapes_per_s"]
    L.append(f"| thesis (2003): all the same / load every one / its method | {t1['same'][10000]:g} / "
             f"{t1['loaded'][10000]:,} / {t1['axial'][10000]:,} KB | | | {t2['same']:,} / {t2['loaded']:,} / {t2['axial']:,} |")
    L.append("")
    ff = [g for g in details["goals"] if g["goal"].startswith("axial first_frame_s")]
    if ff:
        met = sum(g["met"] for g in ff)
        worst = max(ff, key=lambda g: g["measured"])
        extra = [g["extra_ms"] for g in ff]
        L.append(f"First frame, axialdeform / all the same (goal ≤ {GOALS['first_frame_ratio']}): met in {met} of "
                 f"{len(ff)} count × mode cases; the largest ratio is {worst['measured']:.3f} "
                 f"({worst['count']:,} {worst['mode']}); axial − same ranges from {min(extra):+.1f} to "
                 f"{max(extra):+.1f} ms.")
    fr = next((g for g in details["goals"] if g["goal"] == "axial frame_s / same frame_s"), None)
    if fr:
        L.append(f"Later frames, axial / same at {fr['count']:,} solid: {fr['measured']:.3f} (goal ≤ {GOALS['frame_ratio']}).")
    la = [(cc, by[("loaded", cc, "solid")]["first_frame_s"] / by[("axial", cc, "solid")]["first_frame_s"])
          for cc in counts if ("loaded", cc, "solid") in by and ("axial", cc, "solid") in by]
    if la:
        L.append("Loading every file / axialdeform, first frame: "
                 + ", ".join(f"{r:.1f}× at {cc:,}" for cc, r in la) + ".")
    leaf = details.get("leaf")
    if leaf:
        L.append(f"{leaf['count']:,} leaves reach their first frame in {leaf['first_frame_s']:.2f} s "
                 f"(thesis: {leaf['thesis_s']} s).")
    return "\n".join(L) + "\n"


def render(details: dict, plots: dict) -> str:
    """The Markdown text of ``bench.md``."""
    st = details["stats"]
    by = {(s["method"], s["count"], s["mode"]): s for s in st}
    records = records_from_stats(st)
    counts = sorted({s["count"] for s in st})
    modes = [m for m in BENCH_MODES if any(s["mode"] == m for s in st)]
    methods = [m for m in METHODS if any(s["method"] == m for s in st)]
    mc = details["machine"]
    se = details["settings"]
    L = []
    add = L.append
    add("# axialdeform bench: the thesis's evaluation, reproduced\n")
    when = f" on {details['finished_utc']}" if details.get("finished_utc") else ""
    add(f"Measured by `axialdeform bench`{when}; wall time {details['wall_s'] / 60:.1f} min; "
        f"{len(records)} method × count × mode cases.\n")
    add(f"Command: `{details['command']}`\n")
    if details.get("interrupted"):
        add(f"**Stopped early (Ctrl-C)**: this report holds the {len(records)} cases measured before the stop"
            + ("; the later-frame times of some cases come from their first-frame processes (see `frame_source` "
               "in bench-details.json)" if any(s.get("frame_source") == "separate" for s in st) else "") + ".\n")
    add("## Machine and settings\n")
    add(f"- CPU: {mc['cpu']} ({mc['cores']} cores visible), memory {mc.get('memory_gib', '?')} GiB")
    add(f"- GL renderer: {mc.get('gl_renderer')} ({mc.get('gl_version', '?')}), moderngl {mc.get('moderngl', '?')}")
    add(f"- Python {mc['python']}, numpy {mc['numpy']}, trimesh {mc.get('trimesh', '?')}, {mc['platform']}")
    if "trimesh_optional_installed" in mc:
        extra = ", ".join(mc["trimesh_optional_installed"]) or "none (only axialdeform's dependencies)"
        add(f"- installed packages that `import trimesh` loads when present: {extra}")
    add(f"- load average (1, 5, 15 min) before: {details.get('load_average_before')}, after: "
        f"{details.get('load_average_after')}")
    add(f"- mesh: {se['mesh']} ({se['vertices']} vertices, {se['triangles']} triangles, {se['edges']} edges, "
        f"{se['mesh_bytes']} bytes); scene: {se['scene']}; seed {se['seed']}")
    add(f"- target: offscreen {se['size'][0]}x{se['size'][1]}, MSAA samples {se['samples']}, depth test, back faces "
        f"{'culled' if se.get('cull_back_faces') else 'drawn'} (every method alike); camera "
        "framing every instance (`camera.frame_instances`), the same for every method of a count")
    reps = sorted({(s["repeats"]) for s in st})
    add(f"- first frame: up to {se['repeats']} fresh child processes per method x count x mode (this run: "
        f"{', '.join(map(str, reps))}; n in the tables), methods interleaved (same, loaded, axial, "
        "axial-quantized, same, ...); `first_frame_s` is measured by the parent from just before starting the child "
        "to the child's report after `ctx.finish()`")
    add(f"- later frames: per count x mode one process sets up every method and draws them in turn; "
        f"up to {se['warmup']} warm-up rounds, then {se['frames']} timed rounds; `frame_s` is the median"
        + (" (**--quick**)" if se["quick"] else "") + "\n")

    add("## Goals (this machine)\n")
    add("| goal | count | mode | target | measured | met |")
    add("|---|---|---|---|---|---|")
    for g in details["goals"]:
        note = f" ({g['note']})" if g["note"] else ""
        add(f"| {g['goal']} | {g['count']} | {g.get('mode', 'solid')} | {g['target']} | {g['measured']}{note} | "
            f"{'yes' if g['met'] else '**no**'} |")
    add("")
    L.extend(_missed(details, by))

    add("## Table 1: data read before the first frame (KB = 1024 bytes)\n")
    head = "| method | " + " | ".join(f"thesis {c}" for c in (100, 1000, 10000)) + " | " + " | ".join(f"ours {c}" for c in counts) + " |"
    add(head)
    add("|---" * (1 + 3 + len(counts)) + "|")
    for m in methods:
        th = THESIS["table1_kb"].get("axial" if m.startswith("axial") else m, {})
        thesis = " | ".join(f"{th[c]:g}" if c in th and m != "axial-quantized" else "-" for c in (100, 1000, 10000))
        ours = " | ".join(f"{by[(m, c, modes[0])]['file_bytes'] / _KB:,.1f}" if (m, c, modes[0]) in by else "-" for c in counts)
        add(f"| {m} | {thesis} | {ours} |")
    add("\nBytes per instance (file bytes / count):\n")
    add("| method | " + " | ".join(str(c) for c in counts) + " |")
    add("|---" * (1 + len(counts)) + "|")
    for m in methods:
        add(f"| {m} | " + " | ".join(f"{by[(m, c, modes[0])]['file_bytes'] / c:,.1f}" if (m, c, modes[0]) in by else "-"
                                     for c in counts) + " |")
    t1 = THESIS["table1_kb"]
    add(f"\nThesis, 10 000 instances: loaded {t1['loaded'][10000] * _KB / 10000:,.0f} bytes per instance, its method "
        f"{t1['axial'][10000] * _KB / 10000:,.0f} (text parameters).\n")

    add("## Table 2: shapes drawn per second (count / frame time)\n")
    add("| method | thesis | " + " | ".join(f"ours {c} {mode}" for c in counts for mode in modes) + " |")
    add("|---" * (2 + len(counts) * len(modes)) + "|")
    for m in methods:
        th = THESIS["table2_shapes_per_s"].get(m, "-")
        add(f"| {m} | {th} | " + " | ".join(f"{by[(m, c, mode)]['shapes_per_s']:,.0f}" if (m, c, mode) in by else "-"
                                          for c in counts for mode in modes) + " |")
    add("")

    for field, title, fig, lo_key, hi_key, how in (
            ("first_frame", "Time to the first frame (Fig. 5)", "fig5", "first_frame_min_s", "first_frame_max_s",
             "median [min .. max] over fresh processes (n = processes)"),
            ("frame", "Time per later frame (Fig. 6)", "fig6", "frame_q25_s", "frame_q75_s",
             "median [quartiles] of the timed frames (n = frames); per count and mode ONE process draws the methods "
             "in turn (same, loaded, axial, axial-quantized, same, ...)")):
        add(f"## {title}\n")
        add(f"![{title}]({plots.get(fig, '')})\n")
        add(how + "\n")
        add("| method | mode | " + " | ".join(str(c) for c in counts) + " |")
        add("|---" * (2 + len(counts)) + "|")
        for m in methods:
            for mode in modes:
                cells = []
                for c in counts:
                    s = by.get((m, c, mode))
                    if s is None:
                        cells.append("-")
                        continue
                    n = s["repeats"] if field == "first_frame" else len(s["frame_all_s"])
                    cells.append(f"{fmt_s(s[field + '_s'])} [{fmt_s(s[lo_key])} .. {fmt_s(s[hi_key])}] (n={n})")
                add(f"| {m} | {mode} | " + " | ".join(cells) + " |")
        add("")

    add("## Ratios\n")
    add("| count | mode | axial / same first frame | axial − same first frame | axial / same frame time | "
        "axial-quantized / same frame time | loaded / axial first frame | loaded / axial frame time |")
    add("|---|---|---|---|---|---|---|---|")
    for c in counts:
        for mode in modes:
            def g(m, f, c=c, mode=mode):
                return by[(m, c, mode)][f] if (m, c, mode) in by else None

            def ratio(a, b):
                return "-" if a is None or b is None else f"{a / b:.3f}"

            a, s = g("axial", "first_frame_s"), g("same", "first_frame_s")
            add(f"| {c} | {mode} | {ratio(a, s)} | {'-' if a is None or s is None else f'{(a - s) * 1e3:+.1f} ms'} | "
                f"{ratio(g('axial', 'frame_s'), g('same', 'frame_s'))} | "
                f"{ratio(g('axial-quantized', 'frame_s'), g('same', 'frame_s'))} | "
                f"{ratio(g('loaded', 'first_frame_s'), g('axial', 'first_frame_s'))} | "
                f"{ratio(g('loaded', 'frame_s'), g('axial', 'frame_s'))} |")
    add("")

    add("## Where the first frame's time goes (median seconds since the parent started the child)\n")
    add("Stages: `imported` (interpreter + `import axialdeform`), `context` (EGL context + offscreen target), "
        "`read` (files read and parsed; for `loaded` also the uploads, which are interleaved), `uploaded` (program "
        "compiled, buffers filled), `first_frame` (drawn and `ctx.finish()` returned).\n")
    add("| method | count | mode | imported | context | read | uploaded | first_frame | parent saw FIRST | trimesh imported |")
    add("|---|---|---|---|---|---|---|---|---|---|")
    for s in st:
        g = s["stages_s"]
        add(f"| {s['method']} | {s['count']} | {s['mode']} | " + " | ".join(
            f"{g.get(k, float('nan')):.3f}" for k in ("imported", "context", "read", "uploaded", "first_frame"))
            + f" | {s['first_frame_s']:.3f} | {s['info'].get('trimesh_imported')} |")
    add("")
    if details.get("startup_s"):
        add("Process start-up alone (fresh process each, median):\n")
        add("| what | seconds |")
        add("|---|---|")
        for k, v in details["startup_s"].items():
            add(f"| `{k}` | {v:.3f} |")
        add("")

    leaf = details.get("leaf")
    if leaf:
        add("## Fig. 9: the leaf scene\n")
        add(f"{leaf['count']:,} bundled leaves, random placement 'box', axial method, solid, {se['size'][0]}x{se['size'][1]}.\n")
        add("| | thesis | ours (median [min .. max], n) |")
        add("|---|---|---|")
        add(f"| time to first frame | {leaf['thesis_s']} s | {leaf['first_frame_s']:.3f} s "
            f"[{leaf['first_frame_min_s']:.3f} .. {leaf['first_frame_max_s']:.3f}] (n={leaf['repeats']}) |")
        add(f"| data read | - | {leaf['file_bytes'] / _KB:.1f} KB |")
        add(f"| later frame | - | {fmt_s(leaf['frame_s'])} |")
        add("\nStages: " + _split_text(leaf["stages_s"]) + "\n")
        add(f"![leaf scene](frames/leaf-{leaf['count']}-solid.png)\n")

    if details.get("throughput"):
        add("## Deformation throughput (vertices deformed per second)\n")
        add("CPU: `axialdeform.core.deform` (numpy, float64, positions + normals). GPU: `AxialRenderer.capture` (transform "
            "feedback of the drawing vertex shader, including the read-back to numpy).\n")
        add("| engine | instances | vertices | seconds (median [min .. max]) | vertices / s |")
        add("|---|---|---|---|---|")
        for r in details["throughput"]:
            add(f"| {r['engine']} | {r['count']:,} | {r['vertices']:,} | {r['seconds']:.3f} [{r['min_s']:.3f} .. "
                f"{r['max_s']:.3f}] | {r['vertices_per_s']:,.0f} |")
        add("")

    if details.get("paired"):
        add("## Paired frame times: axial against same in one process\n")
        add("From the frame-time processes above: in every round `same` and `axial` are drawn one after the other; "
            "the per-round ratio is axial's frame time over same's in that round.\n")
        add("| count | mode | pairs | same (median) | axial (median) | axial / same: median of pair ratios [quartiles] |")
        add("|---|---|---|---|---|---|")
        for r in details["paired"]:
            add(f"| {r['count']} | {r['mode']} | {r['pairs']} | {fmt_s(r['same_frame_s'])} | {fmt_s(r['axial_frame_s'])} | "
                f"{r['median_pair_ratio']:.3f} [{r['pair_ratio_q25']:.3f} .. {r['pair_ratio_q75']:.3f}] |")
        add("")
    pictures = details.get("pictures") or []
    if pictures:
        pc = pictures[0]["count"]
        add(f"## Pictures (first repeat, {pc:,} instances)\n")
        add("The same parameters drawn by each method (`loaded` = CPU-deformed files, `axial` = the vertex shader); "
            "`same` has no bend.\n")
        for mode in modes:
            add(" ".join(f"![{m} {mode}](frames/{m}-{pc}-{mode}.png)" for m in methods) + "\n")
        for r in pictures:
            add(f"- {r['mode']}: `loaded` and `axial` differ in {100 * r['differing_pixels']:.4f} % of the pixels "
                "(by more than 8 of 255).")
        add("")

    add("## Notes\n")
    add("- `same` reads one mesh file; its placement (positions, angles) is computed in the child.")
    loaded_n = {s["count"]: s["repeats"] for s in st if s["method"] == "loaded" and s["mode"] == modes[0]}
    if loaded_n:
        add("- `loaded` files are written once into the cache by `bake.write_mesh_folder` (what `axialdeform bake MESH "
            "PARAMS -o DIR` writes) and read, parsed, uploaded and drawn one by one in every process; processes per "
            "mode: " + ", ".join(f"{n} at {c:,}" for c, n in sorted(loaded_n.items())) + ".")
    if "axial-quantized" in methods:
        add("- `axial-quantized` reads the 32-byte-per-instance file; "
            + ("the GPU instance buffer is quantized too (16 uint16 per instance)."
               if any(s["info"].get("gpu_quantized") for s in st if s["method"] == "axial-quantized")
               else "it is dequantized to float32 on reading (64 bytes per instance on the GPU)."))
    add("- The camera matrices are computed by the parent and handed to every child (a fixed camera).")
    add("- KB here is 1024 bytes; the thesis does not say which it used.")
    return "\n".join(L) + "\n"

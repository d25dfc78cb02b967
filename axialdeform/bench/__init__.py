"""``axialdeform bench``: the thesis's evaluation (§3.1), reproduced and compared.

Three ways to draw ``N`` similar shapes, all real, each timed from a fresh
process start.  Every method draws the plain picture the thesis timed, the
``Look(fast=True)`` path of :func:`axialdeform.gl.image.render_image`: no
multisampling (``samples=0`` by default), no shadow map, no ground, no
hidden-line pre-pass:

* ``same`` — the base mesh instanced ``N`` times with position and
  orientation only (``AxialRenderer(..., bend=False)``); reads one mesh file.
* ``loaded`` — ``N`` meshes pre-deformed by the CPU reference
  (:func:`axialdeform.core.deform.deform`), one OBJ file each, read one by one with
  :func:`axialdeform.core.io.mesh.load_mesh`, uploaded (one VBO/IBO/VAO each) and
  drawn with one draw call each.
* ``axial`` — one base mesh + one binary parameter file (``.adp``, float32),
  deformed in the vertex shader, one instanced draw call;
  ``axial-quantized`` the same with the quantized ``.adp`` (32 bytes an
  instance).

Figures per method x count x mode (the records of ``--json``):

``file_bytes``
    bytes read from disk before the first frame (thesis Table 1).
``first_frame_s``
    seconds from just before the child process is started to the child's
    report that its first frame is finished (``ctx.finish()``): interpreter
    start, imports, context, reading, upload and the draw (Fig. 5). Median
    over repeats.
``frame_s``
    median seconds of one later frame (clear + draw + ``ctx.finish()``) after
    warm-up (Fig. 6).  Per count x mode ONE process sets up every method and
    draws them in turn (A B C D A B C D ...), ``frames`` rounds, so that load
    from elsewhere on a shared machine -- which moves separate processes'
    frame times by tens of percent -- hits all methods alike.
``shapes_per_s``
    ``count / frame_s`` (Table 2).

Each first frame is measured in its own child process (``python -c``, entry
point :func:`axialdeform.bench.child.main`), the methods interleaved (A B C D
A B C D ...) so that drift hits all of them alike; the frame times come from
:func:`axialdeform.bench.child.interleaved`.  The ``loaded`` meshes are cached on disk
between runs, keyed by the mesh and the parameters; reading them is always
real.  Use it from Python with :func:`run_bench`.

The package, by job: :mod:`.plan` (what is measured and the cached files),
:mod:`.child` (one measurement process), :mod:`.stats` (records, ratios,
goals), :mod:`.report` (``bench.md`` and plots, also from a saved
``bench-details.json``); this module runs the plan.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, replace
from importlib.metadata import PackageNotFoundError, version
from importlib.util import find_spec
from pathlib import Path

import numpy as np
from PIL import Image

from ..core.deform import deform
from ..core.errors import AxialDeformError
from ..core.io.atomic import atomic_write_text
from ..core.io.mesh import load_mesh
from ..core.variation import random_params
from ..gl.context import create_context
from ..gl.renderer import AxialRenderer
from .plan import (
    BENCH_MODES,
    COUNTS,
    LEAF_SCENE,
    METHODS,
    QUICK_COUNTS,
    SCENE,
    SEPARATE_FRAMES,
    Scene,
    cache_root,
    camera,
    first_frame_plan,
    mesh_file,
    scene_kwargs,
)
from .report import with_goals, write_report
from .stats import (
    GOALS,
    RECORD_KEYS,
    THESIS,
    case_stats,
    leaf_summary,
    pair_rows,
    records_from_stats,
    sort_key,
)

__all__ = ["BENCH_MODES", "COUNTS", "QUICK_COUNTS", "METHODS", "RECORD_KEYS", "THESIS", "GOALS", "run_bench",
           "BenchSettings", "DEFAULT_OUT"]

#: the folder ``axialdeform bench`` writes into when no ``--out`` is given
DEFAULT_OUT = "axialdeform-bench"
#: optional packages that ``import trimesh`` imports itself when they are installed
_TRIMESH_EAGER = ("scipy", "networkx")
_CHILD = "from axialdeform.bench.child import main; main(sys.argv[1])"
_CHILD_FRAMES = "from axialdeform.bench.child import interleaved; interleaved(sys.argv[1])"


def _python_c(code: str, *args: str) -> list[str]:
    """argv of ``python -c code args``, importing exactly what this process
    imports: the child gets this process's ``sys.path`` instead of its own
    (``python -c`` would put the current folder first, and a source checkout
    there -- whose shaders are not packaged -- would shadow the installed
    axialdeform)."""
    prefix = f"import sys; sys.path[:] = {list(sys.path)!r}; "
    return [sys.executable, "-c", prefix + code, *args]


def _run_child(spec: dict, timeout: float) -> dict:
    """Start one child, time it from just before the start to its ``FIRST`` line."""

    with tempfile.TemporaryFile("w+") as err:
        wall0 = time.time()
        t0 = time.perf_counter()
        proc = subprocess.Popen(_python_c(_CHILD, json.dumps(spec)), stdout=subprocess.PIPE,
                                stderr=err, text=True)
        first = None
        result = None
        try:
            for line in proc.stdout:
                if first is None and line.startswith("FIRST"):
                    first = time.perf_counter() - t0
                elif line.startswith("RESULT "):
                    result = json.loads(line[7:])
            proc.wait(timeout=timeout)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        if proc.returncode == -2:  # the child got the same Ctrl-C as this process
            raise KeyboardInterrupt
        if proc.returncode != 0 or first is None or result is None:
            err.seek(0)
            tail = err.read()[-2000:]
            raise AxialDeformError(
                f"bench child {spec['method']} x {spec['count']} ({spec['mode']}) failed with status "
                f"{proc.returncode}: {tail.strip() or 'no message'}"
            )
    stamps = {k: v - wall0 for k, v in result["stamps"].items()}
    return {"first_frame_s": first, "frame_s": statistics.median(result["frames"]), "frames": result["frames"],
            "stamps": stamps, "info": result["info"]}


def _machine() -> dict:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    info = {"cpu": cpu, "cores": os.cpu_count(), "python": platform.python_version(), "platform": platform.platform(),
            "numpy": np.__version__}

    try:
        info["trimesh"] = version("trimesh")
    except PackageNotFoundError:  # pragma: no cover - trimesh is a dependency
        info["trimesh"] = "?"
    # trimesh imports these at its own import when they are installed (not dependencies of axialdeform):
    # they decide what reading the first mesh costs in a fresh process
    info["trimesh_optional_installed"] = [m for m in _TRIMESH_EAGER if find_spec(m) is not None]
    try:
        import moderngl

        from ..gl.context import create_context

        info["moderngl"] = moderngl.__version__
        ctx = create_context()
        info["gl_renderer"] = ctx.info.get("GL_RENDERER", "?")
        info["gl_version"] = ctx.info.get("GL_VERSION", "?")
        ctx.release()
    except Exception as exc:  # reported, not fatal here: the children fail loudly anyway
        info["gl_renderer"] = f"no context ({exc})"
    try:
        mem = Path("/proc/meminfo").read_text().split("\n")[0].split()[1]
        info["memory_gib"] = round(int(mem) / 2**20, 1)
    except (OSError, IndexError, ValueError):
        pass
    return info


def _load_average() -> list[float] | None:
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return None


def _startup_costs(repeats: int) -> dict:
    """Seconds of a bare interpreter start and of ``import axialdeform`` (each in a fresh process)."""
    out = {}
    for name, code in (("python -c pass", "pass"), ("import numpy", "import numpy"),
                       ("import axialdeform", "import axialdeform"),
                       ("import axialdeform.bench.child + moderngl", "import axialdeform.bench.child, moderngl"),
                       ("import trimesh (the mesh loader, with numpy)", "import trimesh")):
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            subprocess.run(_python_c(code), check=True)
            times.append(time.perf_counter() - t)
        out[name] = statistics.median(times)
    return out


def _throughput(mesh, counts, seed: int, repeats: int) -> list[dict]:
    """Vertices deformed per second: CPU reference and GPU capture (with read-back)."""

    rows = []
    ctx = create_context()
    try:
        for n in counts:
            params = random_params(mesh, n, seed, **scene_kwargs(mesh, SCENE))
            verts = n * mesh.vertex_count
            cpu = []
            for _ in range(repeats):
                t = time.perf_counter()
                deform(mesh.axis, mesh.positions, mesh.normals, params)
                cpu.append(time.perf_counter() - t)
            with AxialRenderer(ctx, mesh, params) as r:
                r.capture(0, min(n, 16))  # compiles the capture program
                gpu = []
                for _ in range(repeats):
                    t = time.perf_counter()
                    r.capture()
                    gpu.append(time.perf_counter() - t)
            for engine, times in (("cpu (numpy deform)", cpu), ("gpu (AxialRenderer.capture)", gpu)):
                s = statistics.median(times)
                rows.append({"engine": engine, "count": n, "vertices": verts, "seconds": s, "min_s": min(times),
                             "max_s": max(times), "vertices_per_s": verts / s})
    finally:
        ctx.release()
    return rows


def _run_frames_child(spec: dict, timeout: float) -> dict:
    """The frame-time process of one count x mode (all methods interleaved);
    returns ``{method: [seconds, ...]}`` and each method's info."""
    proc = subprocess.run(_python_c(_CHILD_FRAMES, json.dumps(spec)), capture_output=True, text=True, timeout=timeout)
    result = next((json.loads(line[7:]) for line in proc.stdout.splitlines() if line.startswith("RESULT ")), None)
    if proc.returncode == -2:
        raise KeyboardInterrupt
    if proc.returncode != 0 or result is None:
        raise AxialDeformError(f"bench frame-time child x {spec['methods'][0]['count']} ({spec['mode']}) failed with "
                               f"status {proc.returncode}: {proc.stderr[-2000:].strip() or 'no message'}")
    if result["gl_error"] != "GL_NO_ERROR":
        raise AxialDeformError(f"bench frame-time child x {spec['methods'][0]['count']} ({spec['mode']}): "
                               f"expected GL_NO_ERROR, found {result['gl_error']}")
    return result


def _picture_agreement(frames_dir: Path, count: int, modes) -> list[dict]:
    """Fraction of pixels where the ``loaded`` and ``axial`` pictures differ (by more than 8 of 255)."""

    rows = []
    for mode in modes:
        a, b = frames_dir / f"loaded-{count}-{mode}.png", frames_dir / f"axial-{count}-{mode}.png"
        if a.exists() and b.exists():
            x = np.asarray(Image.open(a), dtype=np.int16)
            y = np.asarray(Image.open(b), dtype=np.int16)
            rows.append({"mode": mode, "count": count,
                         "differing_pixels": float((np.abs(x - y).max(axis=-1) > 8).mean())})
    return rows


def _no_progress(done: int, total: int, label: str) -> None:
    pass


@dataclass(frozen=True)
class BenchSettings:
    """What the benchmark measures (:func:`run_bench`; ``axialdeform bench``'s options).

    Attributes
    ----------
    mesh : str or path
        Base mesh (a file, or ``"stone"`` / ``"leaf"``).
    counts : sequence of int
        Instance counts (default 100, 1 000, 10 000, 100 000).
    modes, methods : sequences of str
        Subsets of :data:`BENCH_MODES` and :data:`METHODS`.
    repeats : int
        First-frame child processes per method x count x mode (fewer where
        one run takes long: 1 at 100 000, 2 for ``loaded`` at 10 000).
    frames, warmup : int
        Rounds timed (median) and rounds drawn before them in the one
        process per count x mode that draws the methods in turn (from 10 000
        on, one warm-up round).
    size : (width, height)
        Pixels of the offscreen target; ``samples`` its MSAA samples (0: none).
    seed : int
        Of the instances' random parameters.
    leaf, throughput : bool
        Also the leaf scene and the throughput run.
    quick : bool
        Small counts (100, 1 000), one repeat, smaller leaf/throughput runs.
    timeout : float
        Seconds one child process may take.
    """

    mesh: object = "stone"
    counts: tuple = COUNTS
    modes: tuple = BENCH_MODES
    methods: tuple = METHODS
    repeats: int = 3
    frames: int = 20
    warmup: int = 3
    size: tuple = (800, 600)
    samples: int = 0
    seed: int = 2003
    leaf: bool = True
    throughput: bool = True
    quick: bool = False
    timeout: float = 3600.0


def run_bench(settings: BenchSettings | None = None, *, out=None, json_path=None, cache=None, progress=None,
              command: str | None = None, **fields) -> list[dict]:
    """Run the benchmark; returns the records (one dict per method x count x mode
    with exactly the keys of :data:`RECORD_KEYS`).

    Parameters
    ----------
    settings : BenchSettings, optional
        What is measured (:class:`BenchSettings`); its fields may also be given as keywords
        (``counts=(100,), quick=True``).
    out : path, optional
        Folder for ``bench.md``, ``bench-details.json`` and the plots.
    json_path : path, optional
        Where to write the records as JSON.
    cache : path, optional
        Folder for the parameter files and pre-deformed OBJ files (default
        ``~/.cache/axialdeform/bench``).
    progress : callable, optional
        ``progress(done, total, label)`` after every step (steps done so
        far, steps in all, what runs next); the command line wraps it in a
        progress bar.

    A ``KeyboardInterrupt`` (Ctrl-C) during the measurements keeps what was
    measured: the finished cases are written (records, ``bench.md`` marked as
    stopped early, ``bench-details.json`` with ``"interrupted": true``), then
    the ``KeyboardInterrupt`` is raised again.
    """
    unknown = sorted(set(fields) - set(BenchSettings.__dataclass_fields__))
    if unknown:
        raise TypeError(f"run_bench() got an unexpected keyword argument {unknown[0]!r}")
    settings = replace(settings or BenchSettings(), **fields)
    mesh, counts, modes, methods = settings.mesh, settings.counts, settings.modes, settings.methods
    repeats, frames, warmup, size, samples = (settings.repeats, settings.frames, settings.warmup, settings.size,
                                              settings.samples)
    seed, leaf, throughput, quick, timeout = (settings.seed, settings.leaf, settings.throughput, settings.quick,
                                              settings.timeout)

    if progress is None or progress is False:
        progress = _no_progress
    elif not callable(progress):
        raise AxialDeformError(f"progress: expected a callable progress(done, total, label) or None, "
                               f"found {type(progress).__name__}")
    if quick:
        counts = QUICK_COUNTS if tuple(counts) == COUNTS else counts
        repeats = 1
        warmup = min(warmup, 1)
        frames = min(frames, 5)
        size = (400, 300)
    for m in methods:
        if m not in METHODS:
            raise AxialDeformError(f"method: expected some of {', '.join(METHODS)}, found {m!r}")
    for m in modes:
        if m not in BENCH_MODES:
            raise AxialDeformError(f"mode: expected some of {', '.join(BENCH_MODES)}, found {m!r}")
    counts = tuple(int(c) for c in counts)
    if not counts or min(counts) < 1 or repeats < 1 or frames < 1 or warmup < 0:
        raise AxialDeformError("bench: expected counts >= 1, repeats >= 1, frames >= 1 and warmup >= 0")
    t_start = time.perf_counter()
    load_before = _load_average()
    cache = cache_root(cache)
    mesh_path = mesh_file(mesh)
    base = load_mesh(mesh)
    machine = _machine()
    leaf_repeats = 1 if quick else repeats
    tp_counts = (1000, 10000) if quick else (10000, 100000)

    scenes = {c: Scene(base, mesh_path, c, seed, SCENE, cache) for c in counts}
    plan = first_frame_plan(counts, modes, methods, repeats)
    # OBJ files still to write (a cached folder is not a step: the estimate follows the real work)
    obj_total = sum(c for c in counts if not scenes[c].folder.is_dir()) if "loaded" in methods else 0
    total = (len(plan) + len(counts) * len(modes) + obj_total + (leaf_repeats if leaf else 0)
             + (1 if throughput else 0) + 1)
    done = 0

    def step(n: int, label: str) -> None:
        nonlocal done
        done += n
        progress(done, total, label)

    frames_dir = Path(out) / "frames" if out is not None else None
    image_count = 1000 if 1000 in counts else counts[0]
    runs: dict[tuple, list] = {}
    interleaved: dict[tuple, dict] = {}
    leaf_result = tp = None
    startup = {}
    interrupted = False
    try:
        if "loaded" in methods:
            for c in counts:
                if scenes[c].folder.is_dir():
                    continue
                step(0, f"OBJ files x {c}")
                before = done
                scenes[c].ensure_objs(progress=lambda n, c=c: step(n, f"OBJ files x {c}"))
                step(before + c - done, f"OBJ files x {c}")
        cameras = {c: camera(base, scenes[c].params, size) for c in counts}
        if frames_dir is not None:
            frames_dir.mkdir(parents=True, exist_ok=True)
        for c, mode, rep, m in plan:
            step(0, f"{m} x {c} {mode} #{rep + 1}")
            sc = scenes[c]
            spec = {"method": m, "count": c, "mode": mode, "size": list(size), "samples": samples,
                    "view": cameras[c][0], "proj": cameras[c][1], "warmup": 0, "frames": SEPARATE_FRAMES,
                    "seed": seed, "scene": SCENE, "mesh": str(mesh_path),
                    "params": str(sc.params_file(m)), "folder": str(sc.folder)}
            if frames_dir is not None and rep == 0 and c == image_count:
                spec["image"] = str(frames_dir / f"{m}-{c}-{mode}.png")
            result = _run_child(spec, timeout)  # (an interrupted child leaves no empty case behind)
            runs.setdefault((m, c, mode), []).append(result)
            step(1, f"{m} x {c} {mode} #{rep + 1}")
        # frame times: one process per count x mode, the methods drawn in turn
        for c in counts:
            sc = scenes[c]
            for mode in modes:
                step(0, f"frame times x {c} {mode} ({', '.join(methods)} in turn)")
                subs = [{"method": m, "count": c, "seed": seed, "scene": SCENE, "mesh": str(mesh_path),
                         "params": str(sc.params_file(m)), "folder": str(sc.folder)} for m in methods]
                spec = {"mode": mode, "size": list(size), "samples": samples, "view": cameras[c][0],
                        "proj": cameras[c][1], "warmup": min(warmup, 1) if c >= 10000 else warmup, "frames": frames,
                        "methods": subs}
                interleaved[(c, mode)] = _run_frames_child(spec, timeout)["frames"]
                step(1, f"frame times x {c} {mode}")
        if leaf:
            leaf_mesh = load_mesh("leaf")
            leaf_path = mesh_file("leaf")
            ls = Scene(leaf_mesh, leaf_path, LEAF_SCENE["count"], seed,
                       {"bend": LEAF_SCENE["bend"], "placement": LEAF_SCENE["placement"]}, cache)
            view, proj = camera(leaf_mesh, ls.params, size)
            leaf_runs = []
            for rep in range(leaf_repeats):
                step(0, f"leaf scene #{rep + 1}")
                spec = {"method": "axial", "count": ls.count, "mode": "solid", "size": list(size), "samples": samples,
                        "view": view, "proj": proj, "warmup": 0, "frames": SEPARATE_FRAMES, "seed": seed,
                        "scene": ls.scene, "mesh": str(leaf_path), "params": str(ls.adp), "folder": ""}
                if frames_dir is not None and rep == 0:
                    spec["image"] = str(frames_dir / f"leaf-{ls.count}-solid.png")
                leaf_runs.append(_run_child(spec, timeout))
                step(1, f"leaf scene #{rep + 1}")
            leaf_result = leaf_summary(ls.count, ls.file_bytes("axial"), leaf_runs)
        if throughput:
            step(0, "deformation throughput")
            tp = _throughput(base, tp_counts, seed, 1 if quick else 3)
            step(1, "deformation throughput")
        step(0, "process start-up costs")
        startup = _startup_costs(1 if quick else 3)
        step(1, "done")
    except KeyboardInterrupt:
        interrupted = True
        if not runs:
            raise

    stats = [case_stats(m, c, mode, rs, interleaved.get((c, mode), {}).get(m), scenes[c].file_bytes(m))
             for (m, c, mode), rs in runs.items()]
    culling = {r["info"].get("cull_back_faces") for rs in runs.values() for r in rs}
    if len(culling) > 1:  # a fair comparison draws every method the same way
        raise AxialDeformError(f"bench: the methods drew with different face culling ({sorted(map(str, culling))}); "
                               "expected one setting for all (is every loaded file as closed as the base mesh?)")
    stats.sort(key=sort_key)
    records = records_from_stats(stats)
    paired = pair_rows(interleaved)
    details = {
        "command": command or "axialdeform.bench.run_bench(...)",
        "finished_utc": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
        "interrupted": interrupted,
        "machine": machine,
        "load_average_before": load_before,
        "load_average_after": _load_average(),
        "wall_s": time.perf_counter() - t_start,
        "settings": {"mesh": str(mesh), "mesh_file": str(mesh_path), "mesh_bytes": mesh_path.stat().st_size,
                     "vertices": base.vertex_count, "triangles": len(base.faces), "edges": len(base.edges),
                     "counts": list(counts), "modes": list(modes), "methods": list(methods), "repeats": repeats,
                     "frames": frames, "warmup": warmup, "size": list(size), "samples": samples, "seed": seed,
                     "scene": SCENE, "quick": quick, "cache": str(cache), "cull_back_faces": bool(base.is_volume)},
        "stats": stats,
        "leaf": leaf_result,
        "throughput": tp,
        "paired": paired,
        "pictures": [] if out is None else _picture_agreement(Path(out) / "frames", image_count, modes),
        "startup_s": startup,
        "thesis": THESIS,
    }

    details = with_goals(details)
    if json_path is not None:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(json_path, json.dumps(records, indent=1) + "\n")
    if out is not None:
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_text(out / "bench-details.json", json.dumps(details, indent=1, default=str) + "\n")
        write_report(details, out)
    if interrupted:
        raise KeyboardInterrupt
    return records

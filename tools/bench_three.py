#!/usr/bin/env python3
"""Measure axialdeform-three against the instancing three.js users pick today, in Chromium.

The same stones (``random_params`` on a grid: positions, turns, bends) at each count, the same
camera walking through the field, three ways (tools/bench_three.html, three r187 from js/node_modules):

* ``plain``: ``THREE.InstancedMesh`` under ``WebGLRenderer``, every instance drawn, unbent;
* ``addon``: ``@three.ez/instanced-mesh``'s ``InstancedMesh2`` with its BVH frustum culling
  (``WebGLRenderer``: the add-on has no WebGPU path), unbent;
* ``axial``: ``axialdeform-three/webgpu``'s ``AxialInstancedMesh`` under ``WebGPURenderer``
  (WebGPU backend) with GPU culling (``setGPUCulling``), every instance bent; ``axial-unbent``: the same with
  every offset zero, so its positionNode leaves the bend out (``core/variant.js``); ``axial-whole``: the bent
  one built with the turn although no instance twists (what the variant saves);
* ``axial-webgl-cull``: ``axialdeform-three``'s ``AxialInstancedMesh`` under ``WebGLRenderer`` with
  per-instance culling (``setInstanceCulling``), every instance bent -- the add-on's backend;
  ``axial-webgl-unbent``: the same with every offset zero, so its shader variant leaves the bend out
  (``core/variant.js``): the bend's own vertex work, the same culling;
* ``batched``, ``batched-webgpu``: three's own per-instance culling, a ``THREE.BatchedMesh`` of the one stone
  (``perObjectFrustumCulled``: its CPU tests every instance's sphere a frame), under ``WebGLRenderer`` or
  ``WebGPURenderer`` (the add-on's counterpart on WebGPU), unbent.

Per mode and count, each run in a page of its own, the modes alternating over ``--repeats`` runs:
the first frame (from making the mesh to the GPU done), the median CPU ms of the ``render`` call,
the median frame ms (until the GPU is done), the JS heap and how many instances were drawn; the
table gives the median over the runs.  Headless Chromium draws with SwiftShader (the CPU) unless
a GPU is there: frame times then measure the CPU rasterizer, the CPU ms the library.

    python3 tools/bench_three.py                       # 100 000, 500 000, 1 000 000
    python3 tools/bench_three.py --counts 100000 --frames 5 -o /tmp/b --overwrite
"""

from __future__ import annotations

import argparse
import base64
import json
import shutil
import sys
import tempfile
import threading
from pathlib import Path

import axialdeform as ad
from axialdeform.web import make_server

ROOT = Path(__file__).resolve().parents[1]
JS = ROOT / "js"
ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox", "--enable-unsafe-webgpu",
        "--use-webgpu-adapter=swiftshader", "--enable-features=Vulkan", "--use-vulkan=swiftshader",
        "--enable-precise-memory-info"]
MODES = ("plain", "addon", "axial", "one", "axial-webgl", "plain-webgpu", "axial-nocull", "axial-webgl-cull", "axial-webgl-unbent",
         "batched", "batched-webgpu", "axial-unbent", "axial-whole")


def site(folder: Path, counts, spacing: float) -> None:
    modules = folder / "node_modules"
    (modules / "@three.ez").mkdir(parents=True)
    links = {"three": JS / "node_modules" / "three-r187", "bvh.js": JS / "node_modules" / "bvh.js",
             "@three.ez/instanced-mesh": JS / "node_modules" / "@three.ez" / "instanced-mesh", "axialdeform-three": JS}
    for name, target in links.items():
        if not target.exists():
            sys.exit(f"bench_three: {target} is missing: run `npm ci --prefix js` first")
        (modules / name).symlink_to(target)
    shutil.copy(ROOT / "tools" / "bench_three.html", folder / "bench.html")
    shutil.copy(ROOT / "axialdeform" / "meshes" / "stone.obj", folder / "stone.obj")
    (folder / "favicon.ico").write_bytes(b"")
    stone = ad.load_mesh("stone")
    for n in counts:
        params = ad.random_params(stone, n, seed=1, variation=ad.Variation(bend=0.15), spacing=spacing)
        ad.write_params(folder / f"stones-{n}.adp", params, stone)


def median_run(runs: list[dict]) -> dict:
    """One row of several runs of a mode: the median of each measure (the first error, if any)."""
    bad = [r for r in runs if "error" in r]
    if bad:
        return bad[0]
    out = dict(runs[0], repeats=len(runs))
    for key in ("firstFrame", "cpuMs", "frameMs", "heapMB", "drawn"):
        values = sorted(r[key] for r in runs if r.get(key) is not None)
        out[key] = values[len(values) // 2] if values else None
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--counts", default="100000,500000,1000000", help="instance counts, comma-separated")
    p.add_argument("--modes", default="plain,addon,axial,one", help="some of " + ", ".join(MODES) + " (comma-separated)")
    p.add_argument("--frames", type=int, default=8, help="frames of the walk a run (medians over them)")
    p.add_argument("--still", action="store_true", help="the camera at rest at the walk's start (default: it walks)")
    p.add_argument("--spacing", type=float, default=1.5, help="grid spacing of the stones (model units)")
    p.add_argument("--repeats", type=int, default=3, help="runs of every mode, alternated (medians over them)")
    p.add_argument("-o", "--out", default="axialdeform-bench-three", help="folder for results.json and pictures")
    p.add_argument("--overwrite", action="store_true", help="replace the results of an earlier run there")
    a = p.parse_args(argv)
    counts = [int(c) for c in a.counts.split(",")]
    modes = [m for m in a.modes.split(",") if m]
    if any(m not in MODES for m in modes):
        p.error(f"--modes: expected some of {', '.join(MODES)}, found {a.modes}")
    out = Path(a.out)
    if (out / "results.json").exists() and not a.overwrite:
        p.error(f"{out / 'results.json'}: exists; refusing to replace it (--overwrite replaces it)")
    out.mkdir(parents=True, exist_ok=True)
    chromium = shutil.which("chromium")
    if not chromium:
        p.error("Debian's chromium is required (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    results = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "site"
        folder.mkdir()
        site(folder, counts, a.spacing)
        server, _ = make_server(folder, 0, follow=(ROOT / "js",))
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = f"http://127.0.0.1:{server.server_address[1]}/bench.html"
        try:
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path=chromium, args=ARGS)
                for n in counts:
                    runs = {mode: [] for mode in modes}
                    for _ in range(a.repeats):  # the modes alternate, so a slow spell of the machine hits all
                        for mode in modes:
                            page = browser.new_page(viewport={"width": 640, "height": 360})
                            page.goto(f"{url}?mode={mode}&frames={a.frames}&adp=stones-{n}.adp{'&still=1' if a.still else ''}")
                            page.wait_for_function("window.result !== undefined", timeout=3_600_000)
                            r = page.evaluate("window.result")
                            page.close()
                            png = r.pop("png", None)
                            if png:
                                (out / f"{mode}-{n}.png").write_bytes(base64.b64decode(png.split(",", 1)[1]))
                            runs[mode].append(r)
                            print(json.dumps(r), flush=True)
                    for mode in modes:
                        results.append(median_run(runs[mode]))
                browser.close()
        finally:
            server.shutdown()
            server.server_close()
    (out / "results.json").write_text(json.dumps(results, indent=1))
    print("\n| instances | mode | drawn | first frame ms | CPU ms a frame | frame ms | JS heap MB |")
    print("|---:|---|---:|---:|---:|---:|---:|")
    for r in results:
        if "error" in r:
            print(f"| {r.get('n', '?')} | {r['mode']} | error: {r['error'].splitlines()[0]} | | | | |")
            continue
        print(f"| {r['n']:,} | {r['mode']} | {r['drawn']:,} | {r['firstFrame']:.0f} | {r['cpuMs']:.2f} | "
              f"{r['frameMs']:.0f} | {r['heapMB']:.0f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Bytes a browser downloads for a scene of N stones as an axialdeform page
(page + mesh + parameters; three.js separately) against the same N stones
baked into one GLB, and the time to the first frame in headless Chromium
(Debian's chromium, SwiftShader WebGL 2 -- a software rasterizer, so the
time is an upper bound for a machine with a GPU).

    .venv/bin/python tools/web_sizes.py [-n 10000] [--size 800x600] [--runs 3] [--screenshot docs/gallery/web.png]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import threading
import time
from pathlib import Path

import axialdeform as ad
from axialdeform.core.io.gltf import encode_baked
from axialdeform.gl.image import parse_size
from axialdeform.web import build_scene, make_server, scene_bytes, single_file_html, write_page


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-n", "--count", type=int, default=10_000)
    ap.add_argument("--size", default="800x600")
    ap.add_argument("--runs", type=int, default=3, help="page loads to time (median)")
    ap.add_argument("--screenshot", help="save the page's canvas as this PNG (scaled to half size)")
    args = ap.parse_args()
    size = parse_size(args.size)
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, args.count, seed=2003, bend=0.12, placement="disc")
    scene = build_scene(mesh, params, size=size)
    work = Path(tempfile.mkdtemp(prefix="axd-web-"))
    try:
        write_page(work / "site", scene)
        b = scene_bytes(work / "site")
        single = len(single_file_html(scene).encode("utf-8"))
        scene32 = build_scene(mesh, params, size=size, quantize=False)
        baked = len(encode_baked(mesh, params))
        page_total = b["page"] + b["mesh"] + b["params"]
        print(f"{args.count} stones, {mesh.vertex_count} vertices each")
        print(f"  page (index.html + app.js + scene.json): {b['page']:>12,} bytes")
        print(f"  mesh.glb:                                {b['mesh']:>12,} bytes")
        print(f"  params.adp (quantized, 32 B/instance):   {b['params']:>12,} bytes")
        print(f"  = page + mesh + params:                  {page_total:>12,} bytes")
        print(f"  (params.adp as float32, 64 B/instance:   {len(scene32.adp):>12,} bytes)")
        print(f"  three.js (vendored, cacheable):          {b['three']:>12,} bytes")
        print(f"  single self-contained .html:             {single:>12,} bytes")
        print(f"  baked: {args.count} meshes in one GLB:       {baked:>12,} bytes "
              f"({baked / page_total:.0f}x page + mesh + params)")

        from playwright.sync_api import sync_playwright

        server, _ = make_server(work, 0)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = f"http://127.0.0.1:{server.server_address[1]}/site/index.html"
        times, inner = [], []
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=shutil.which("chromium"),
                                         args=["--use-angle=swiftshade", "--enable-unsafe-swiftshader", "--no-sandbox"])
            for run in range(args.runs):
                page = browser.new_page(viewport={"width": size[0], "height": size[1] + 40})
                t0 = time.perf_counter()
                page.goto(url, wait_until="commit")
                page.wait_for_function("window.axialdeform && window.axialdeform.ready !== undefined", timeout=300_000, polling=20)
                times.append(time.perf_counter() - t0)
                state = page.evaluate("window.axialdeform")
                assert state.get("ready"), state
                inner.append(state["firstFrameMs"] / 1000)
                if args.screenshot and run == 0:
                    from io import BytesIO

                    from PIL import Image

                    img = Image.open(BytesIO(page.screenshot(clip={"x": 0, "y": 0, "width": size[0], "height": size[1] + 28}))).convert("RGB")
                    img = img.resize((img.width // 2, img.height // 2), Image.LANCZOS)
                    Path(args.screenshot).parent.mkdir(parents=True, exist_ok=True)
                    img.save(args.screenshot, optimize=True)
                page.close()
            browser.close()
        server.shutdown()
        print(f"  time to first frame, headless Chromium (SwiftShader), {size[0]}x{size[1]}, median of {args.runs}: "
              f"{statistics.median(times):.2f} s from navigation "
              f"(the page's own count from navigation start: {statistics.median(inner):.2f} s)")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()

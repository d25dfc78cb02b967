"""Time to make a generated layer's tiles in the browser: the npm module's generated AxialInstancedMesh under
WebGLRenderer (examples/web/generated.html: glsl/generate.glsl by WebGL 2 transform feedback, the count
kept one pixel read back) and under WebGPURenderer (examples/web/generated-webgpu.html: the port to node
functions by one compute pass, the count read back asynchronously), the same recipe in both.

    .venv/bin/python tools/bench_generate_web.py [--rate 4] [--tile 16] [--reach 100] [--repeats 5]

Each repeat moves the point one tile along x (a new tile set: every slot made again) and times
``update(renderer, point)`` until the count kept is known (WebGL 2: at once; WebGPU: ``await counted``);
medians, after one set made to compile the programs.  Headless Chromium (Debian's) with SwiftShader:
WebGL 2 through ANGLE, WebGPU on its Vulkan -- software rasterizers, so the times are a CPU's.  three
r187 (js/node_modules/three-r187).
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import sys
import tempfile
import threading
from pathlib import Path
from urllib.parse import quote

from playwright.sync_api import sync_playwright

from axialdeform.web import make_server

ROOT = Path(__file__).resolve().parents[1]
ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox", "--enable-unsafe-webgpu",
        "--use-webgpu-adapter=swiftshader", "--enable-features=Vulkan", "--use-vulkan=swiftshader"]

TIMED = """async ([repeats, tile]) => {
    const { THREE, renderer, stones } = window.app;
    renderer.setAnimationLoop(null);
    const webgpu = Boolean(renderer.isWebGPURenderer), out = [];
    for (let k = 0; k <= repeats; k++) {
        const t0 = performance.now();
        stones.update(renderer, new THREE.Vector3((k + 1) * tile, 0, 0));
        const kept = webgpu ? await stones.counted : stones.kept;
        if (k > 0) out.push(performance.now() - t0);  // the first: the programs compiled
        if (!(kept > 0)) throw new Error('nothing kept');
    }
    return { ms: out, slots: stones.count, kept: webgpu ? await stones.counted : stones.kept,
             backend: webgpu ? (renderer.backend.isWebGPUBackend ? 'WebGPU' : 'WebGPU fallback') : 'WebGL 2' };
}"""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rate", type=float, default=4.0, help="instances per square unit (default 4)")
    p.add_argument("--tile", type=float, default=16.0, help="the tile's side (default 16)")
    p.add_argument("--reach", type=float, default=100.0, help="tiles within this distance are made (default 100)")
    p.add_argument("--repeats", type=int, default=5, help="tile sets timed (default 5)")
    a = p.parse_args(argv)
    recipe = {"rate": a.rate, "tile": a.tile, "min_distance": 0.1, "seed": 1, "bend": 0.12, "scale": [0.5, 1.0],
              "reach": a.reach}
    with tempfile.TemporaryDirectory() as tmp:
        site = Path(tmp)
        (site / "node_modules").mkdir()
        (site / "node_modules" / "three").symlink_to(ROOT / "js" / "node_modules" / "three-r187")
        (site / "node_modules" / "axialdeform-three").symlink_to(ROOT / "js")
        for f in ("generated.html", "generated-webgpu.html"):
            shutil.copy(ROOT / "examples" / "web" / f, site / f)
        shutil.copy(ROOT / "axialdeform" / "meshes" / "stone.obj", site / "stone.obj")
        server, _ = make_server(site, port=0, follow=(ROOT / "js",))
        url = f"http://127.0.0.1:{server.server_address[1]}/"
        threading.Thread(target=server.serve_forever, daemon=True).start()
        try:
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS)
                for page_name in ("generated.html", "generated-webgpu.html"):
                    page = browser.new_page(viewport={"width": 640, "height": 480})
                    page.goto(url + page_name + "?recipe=" + quote(json.dumps(recipe)))
                    page.wait_for_function("window.app !== undefined && window.app.frames >= 1", timeout=600_000)
                    errors = []
                    page.on("console", lambda m, errors=errors: errors.append(m.text) if m.type == "error" else None)
                    try:
                        r = page.evaluate(TIMED, [a.repeats, a.tile])
                    except Exception as exc:  # noqa: BLE001 -- said, with what the page logged
                        print(f"{page_name}: {str(exc).splitlines()[0]}; the page logged: {errors[:3]}")
                        continue
                    finally:
                        page.close()
                    print(f"{r['backend']:>8}: {r['slots']:,} slots ({r['kept']:,} kept) a tile set: "
                          f"median {statistics.median(r['ms']):.0f} ms (of {len(r['ms'])}: "
                          f"{', '.join(f'{x:.0f}' for x in r['ms'])})")
                browser.close()
        finally:
            server.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())

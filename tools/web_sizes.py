"""Bytes a browser downloads for a scene of N stones as an axialdeform page
(page + mesh + parameters; three.js separately) against the same N stones
baked into one GLB, and the time to the first frame in headless Chromium
(Debian's chromium, SwiftShader WebGL 2 -- a software rasterizer, so the
time is an upper bound for a machine with a GPU).

    .venv/bin/python tools/web_sizes.py [-n 10000] [--size 800x600] [--runs 3] [--screenshot docs/gallery/web.png]

With ``--peer`` it compares, instead, the npm module against the meshopt peer:
the same N stones drawn by a plain three.js app through ``AxialInstancedMesh``
(base mesh GLB + quantized .adp) and baked, then compressed by gltfpack
(``-cc``, meshopt; npm's gltfpack, installed by ``npm ci --prefix js``) and
drawn by plain three.js with ``MeshoptDecoder``: bytes, first frame (from
navigation to a finished frame: a 1-pixel ``readPixels``) and later frames
(each finished the same way), over loopback and over a link throttled with
CDP network emulation, pages loaded in turn, medians.

    .venv/bin/python tools/web_sizes.py --peer [-n 10000] [--runs 3] [--mbit 10]
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
from axialdeform.web import PageOptions, build_scene, make_server, scene_bytes, single_file_html, write_page

ROOT = Path(__file__).resolve().parents[1]
JS = ROOT / "js"

# One page for both: three.js, a camera, the same lights and material; `load` fills the scene.
PEER_PAGE = """<!doctype html><html><head><meta charset="utf-8"><link rel="icon" href="data:,">
<script type="importmap">{"imports": {"three": "./three/build/three.module.min.js",
  "three/addons/": "./three/examples/jsm/", "axialdeform-three": "./axialdeform-three/index.js"}}</script>
<style>body{margin:0}canvas{display:block}</style></head><body><script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
%(imports)s
const cam = %(camera)s;
const renderer = new THREE.WebGLRenderer({ antialias: true });
renderer.setSize(%(w)d, %(h)d);
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xeef0f5);
scene.add(new THREE.HemisphereLight(0xffffff, 0x50483c, 1.5));
const sun = new THREE.DirectionalLight(0xffffff, 2.5);
sun.position.set(4, 10, 2);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(cam.fovy, %(w)d / %(h)d, cam.near, cam.far);
camera.position.fromArray(cam.eye);
camera.up.fromArray(cam.up);
camera.lookAt(new THREE.Vector3().fromArray(cam.target));
const gl = renderer.getContext(), px = new Uint8Array(4);
const finished = () => gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
%(load)s
renderer.render(scene, camera);
finished();
const firstFrameMs = performance.now();
%(after)s
const bakeMs = performance.now() - firstFrameMs;
const frames = [];
for (let i = 0; i < %(frames)d; i++) {
  const t = performance.now();
  camera.position.applyAxisAngle(new THREE.Vector3(0, 1, 0), 0.01);
  camera.lookAt(new THREE.Vector3().fromArray(cam.target));
  renderer.render(scene, camera);
  finished();
  frames.push(performance.now() - t);
}
frames.sort((a, b) => a - b);
window.result = { firstFrameMs, bakeMs, frameMs: frames[frames.length >> 1],
  heap: performance.memory ? performance.memory.usedJSHeapSize : null };
</script></body></html>
"""

MODULE_LOAD = """const [gltf, bytes] = await Promise.all([new GLTFLoader().loadAsync('mesh.glb'),
  fetch('params.adp').then((r) => r.arrayBuffer())]);
const base = gltf.scene.getObjectByProperty('isMesh', true).geometry;
const stones = new AxialInstancedMesh(base, new THREE.MeshStandardMaterial({ color: 0x8a8580 }), parseADP(bytes, 'params.adp'));
scene.add(stones);"""
# after the first frame (drawn bent): bend once on the GPU (transform feedback), plain geometry from then on
BAKE = "stones.bake(renderer); renderer.render(scene, camera); finished();"
PEER_LOAD = """const loader = new GLTFLoader().setMeshoptDecoder(MeshoptDecoder);
const gltf = await loader.loadAsync('stones.glb');
gltf.scene.traverse((o) => { if (o.isMesh) o.material = new THREE.MeshStandardMaterial({ color: 0x8a8580 }); });
scene.add(gltf.scene);"""


def open_page(browser, viewport, mbit=None):
    """A new page with the cache off and, with ``mbit``, the network throttled by CDP emulation to that
    many Mbit/s each way with 20 ms of latency (what a first visit over such a link downloads)."""
    page = browser.new_page(viewport={"width": viewport[0], "height": viewport[1]})
    cdp = page.context.new_cdp_session(page)
    cdp.send("Network.enable")
    cdp.send("Network.setCacheDisabled", {"cacheDisabled": True})
    if mbit:
        rate = mbit * 1e6 / 8
        cdp.send("Network.emulateNetworkConditions", {"offline": False, "latency": 20,
                                                       "downloadThroughput": rate, "uploadThroughput": rate})
    return page


def peer(args, size) -> None:
    """The npm module against gltfpack's meshopt-compressed baked GLB (see the module docs)."""
    import gzip
    import json
    import subprocess

    from axialdeform.core.io.gltf import encode_base_mesh
    from axialdeform.core.io.params import encode_binary

    three = JS / "node_modules" / "three"
    gltfpack = JS / "node_modules" / "gltfpack" / "cli.js"
    if not (three.is_dir() and gltfpack.is_file()):
        raise SystemExit("web_sizes.py --peer: run `npm ci --prefix js` first (three and gltfpack)")
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, args.count, seed=2003, variation=ad.Variation(bend=0.12), placement="disc")
    cam = build_scene(mesh, params, page=PageOptions(size=size)).config["camera"]
    work = Path(tempfile.mkdtemp(prefix="axd-peer-"))
    try:
        # the module bending every frame, the module baking once after its first frame, the peer
        sites = {"module": work / "module", "baked": work / "baked", "peer": work / "peer"}
        for name, site in sites.items():
            site.mkdir()
            (site / "three").symlink_to(three)
            imports = ("import { parseADP, AxialInstancedMesh } from 'axialdeform-three';" if name != "peer" else
                       "import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';")
            load = PEER_LOAD if name == "peer" else MODULE_LOAD
            page = PEER_PAGE % {"imports": imports, "camera": json.dumps(cam), "w": size[0], "h": size[1],
                                "load": load, "frames": args.frames, "after": BAKE if name == "baked" else ""}
            (site / "index.html").write_text(page)
        for name in ("module", "baked"):
            (sites[name] / "axialdeform-three").symlink_to(JS / "src")
            (sites[name] / "mesh.glb").write_bytes(encode_base_mesh(mesh))
            (sites[name] / "params.adp").write_bytes(encode_binary(params, axis=mesh, mesh_fingerprint=mesh.fingerprint,
                                                                  quantize=True))
        write_page(work / "page", build_scene(mesh, params, page=PageOptions(size=size)))  # `axialdeform web`'s page, for its first frame
        baked = work / "baked.glb"
        baked.write_bytes(encode_baked(mesh, params))
        subprocess.run(["node", str(gltfpack), "-i", str(baked), "-o", str(sites["peer"] / "stones.glb"), "-cc"],
                       check=True, capture_output=True)
        module_js = sum(f.stat().st_size for f in (JS / "src").rglob("*.js") if f.parent.name != "webgpu" and f.name != "webgpu.js")
        data = {"module": [sites["module"] / "mesh.glb", sites["module"] / "params.adp"],
                "peer": [sites["peer"] / "stones.glb"]}
        print(f"{args.count} stones, {mesh.vertex_count} vertices each; {size[0]}x{size[1]}")
        for name, files in data.items():
            raw = sum(f.stat().st_size for f in files)
            gz = sum(len(gzip.compress(f.read_bytes(), 9)) for f in files)
            print(f"  {name:6} data: {raw:>12,} bytes ({gz:>10,} gzip -9) in {', '.join(f.name for f in files)}")
        print(f"  module code (axialdeform-three/*.js): {module_js:,} bytes; three.js the same for both")
        peer_raw = (sites["peer"] / "stones.glb").stat().st_size
        mod_raw = sum(f.stat().st_size for f in data["module"]) + module_js
        print(f"  module data + code / peer data: 1/{peer_raw / mod_raw:.1f}")

        from playwright.sync_api import sync_playwright

        server, _ = make_server(work, 0, follow=(ROOT / "js",))
        threading.Thread(target=server.serve_forever, daemon=True).start()
        base_url = f"http://127.0.0.1:{server.server_address[1]}/"
        links = {"loopback": None, f"{args.mbit:g} Mbit/s": args.mbit}
        results = {(link, name): [] for link in links for name in [*sites, "page"]}
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=shutil.which("chromium"), args=[
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox", "--enable-precise-memory-info"])
            for run in range(args.runs):
                for link, mbit in links.items():
                    for name in ([*sites, "page"] if run % 2 == 0 else ["page", *list(sites)[::-1]]):  # alternate
                        page = open_page(browser, size, mbit)
                        page.goto(base_url + name + "/index.html", wait_until="commit")
                        if name == "page":  # its own count: navigation to a finished first frame (readPixels)
                            page.wait_for_function("window.axialdeform !== undefined", timeout=600_000, polling=50)
                            state = page.evaluate("window.axialdeform")
                            assert state.get("ready"), state
                            results[(link, name)].append({"firstFrameMs": state["firstFrameMs"]})
                        else:
                            page.wait_for_function("window.result !== undefined", timeout=600_000, polling=50)
                            results[(link, name)].append(page.evaluate("window.result"))
                        page.close()
            browser.close()
        server.shutdown()
        med = statistics.median
        print(f"  medians of {args.runs} loads each, in turn; headless Chromium, SwiftShader WebGL 2:")
        for link in links:
            p = results[(link, "peer")]
            fp, tp, hp = (med(r[k] or 0 for r in p) for k in ("firstFrameMs", "frameMs", "heap"))
            print(f"  {link:>12}: peer (meshopt GLB): first frame {fp / 1000:.2f} s, later frames {tp:.0f} ms, "
                  f"JS heap {hp / 1e6:.1f} MB")
            for name in ("module", "baked"):
                m = results[(link, name)]
                fm, tm, hm = (med(r[k] or 0 for r in m) for k in ("firstFrameMs", "frameMs", "heap"))
                what = "bent every frame" if name == "module" else "baked after it "
                bake = f", the bake + its frame {med(r['bakeMs'] for r in m):.0f} ms" if name == "baked" else ""
                print(f"  {'':>12}  module, {what}: first frame {fm / 1000:.2f} s ({fm / fp:.2f}x), "
                      f"later frames {tm:.0f} ms ({tm / tp:.2f}x), JS heap {hm / 1e6:.1f} MB{bake}")
            fg = med(r["firstFrameMs"] for r in results[(link, "page")])
            print(f"  {'':>12}  the page `axialdeform web` writes (AxialInstancedMesh, the page's own shaders): "
                  f"first frame {fg / 1000:.2f} s ({fg / fp:.2f}x)")
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-n", "--count", type=int, default=10_000)
    ap.add_argument("--size", default="800x600")
    ap.add_argument("--runs", type=int, default=3, help="page loads to time (median)")
    ap.add_argument("--screenshot", help="save the page's canvas as this PNG (scaled to half size)")
    ap.add_argument("--peer", action="store_true", help="the npm module against gltfpack's meshopt GLB (see above)")
    ap.add_argument("--mbit", type=float, default=10.0, help="--peer: the throttled link's rate (default 10)")
    ap.add_argument("--frames", type=int, default=9, help="--peer: later frames to time (median)")
    args = ap.parse_args()
    size = parse_size(args.size)
    if args.peer:
        peer(args, size)
        return
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, args.count, seed=2003, variation=ad.Variation(bend=0.12), placement="disc")
    scene = build_scene(mesh, params, page=PageOptions(size=size))
    work = Path(tempfile.mkdtemp(prefix="axd-web-"))
    try:
        write_page(work / "site", scene)
        b = scene_bytes(work / "site")
        single = len(single_file_html(scene).encode("utf-8"))
        scene32 = build_scene(mesh, params, page=PageOptions(size=size, quantize=False))
        baked = len(encode_baked(mesh, params))
        page_total = b["page"] + b["mesh"] + b["params"]
        print(f"{args.count} stones, {mesh.vertex_count} vertices each")
        print(f"  page (index.html, app.js, scene.json, module): {b['page']:>6,} bytes")
        print(f"  mesh.glb:                                {b['mesh']:>12,} bytes")
        print(f"  params.adp (quantized, 32 B/instance):   {b['params']:>12,} bytes")
        print(f"  = page + mesh + params:                  {page_total:>12,} bytes")
        print(f"  (params.adp as float32, 64 B/instance:   {len(scene32.adp):>12,} bytes)")
        print(f"  three.js (vendored, cacheable):          {b['three']:>12,} bytes")
        print(f"  single self-contained .html:             {single:>12,} bytes")
        print(f"  baked: {args.count} meshes in one GLB:       {baked:>12,} bytes "
              f"({baked / page_total:.0f}x page + mesh + params)")

        from playwright.sync_api import sync_playwright

        server, _ = make_server(work, 0, follow=(ROOT / "js",))
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = f"http://127.0.0.1:{server.server_address[1]}/site/index.html"
        times, inner = [], []
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=shutil.which("chromium"),
                                         args=["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"])
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

                    clip = {"x": 0, "y": 0, "width": size[0], "height": size[1] + 28}
                    img = Image.open(BytesIO(page.screenshot(clip=clip))).convert("RGB")
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

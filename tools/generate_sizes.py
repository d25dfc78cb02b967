"""Bytes a first visit downloads, and the time to its first frame, for a field of N stones made from
one recipe, three ways: today's page (``axialdeform web`` of the instances as a list: one ``.adp``),
the same stones baked into one GLB compressed by gltfpack (``-cc``, meshopt: the peer; bytes only),
and the generated page (``axialdeform web`` of the recipe: no per-instance file; the page makes the
tiles within reach of the camera on the GPU).  Both pages hold the same instances at their start.

    .venv/bin/python tools/generate_sizes.py [--counts 10000,100000,1000000] [--runs 3] [--mbit 10]
                                             [--peer-max 150000] [--bytes-only]

Headless Chromium (Debian's), SwiftShader WebGL 2 -- a software rasterizer: frame times are a CPU's.
First frame: from the start of the navigation to the first frame finished (the page's own count,
``firstFrameMs``: a 1-pixel readPixels), over loopback and over a link throttled by CDP network
emulation (``--mbit``, 20 ms latency); pages loaded in turn, medians of ``--runs``.  gzip -9 stands
for a server's compression.  The peer's GLB is baked in memory (N x the stone's vertices): above
``--peer-max`` stones it is not made.
"""

from __future__ import annotations

import argparse
import gzip
import json
import math
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import axialdeform as ad
from axialdeform.core.generate import Generate, generate_tiles, tile_size, tiles_around
from axialdeform.core.io.gltf import encode_baked
from axialdeform.web import make_server

sys.path.insert(0, str(Path(__file__).resolve().parent))
from web_sizes import open_page  # noqa: E402  (tools/: the same throttled page as the other size tool)

ROOT = Path(__file__).resolve().parents[1]
JS = ROOT / "js"
RATE, TILE = 0.25, 16.0  # 64 stones a tile
RECIPE = dict(rate=RATE, tile=TILE, min_distance=1.0, seed=1, bend=0.12, scale=[0.5, 1.0])

SCENE = """background = [0.80, 0.87, 0.95]
[camera]
elevation = 30
[[layer]]
name = "stones"
mesh = "stone"
color = [0.58, 0.55, 0.5]
"""


def _three(name: str) -> bool:  # the same for every page
    return name.startswith("three/")


def _data(name: str) -> bool:  # the landscape's own: meshes, per-instance files, the config (shaders, recipe)
    return name.endswith((".glb", ".adp", ".f32", "scene.json"))


PARTS = {"three": _three, "code": lambda name: not _three(name) and not _data(name), "data": _data}


def _files(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def _bytes(files: dict, pick) -> tuple[int, int]:
    chosen = [b for n, b in files.items() if pick(n)]
    return sum(map(len, chosen)), sum(len(gzip.compress(b, 9)) for b in chosen)


def _web(scene: Path, out: Path, size: str) -> None:
    subprocess.run([sys.executable, "-m", "axialdeform", "web", str(scene), "-o", str(out), "--size", size],
                   check=True, capture_output=True)


def build(work: Path, n: int, size: str, peer_max: int) -> dict:
    """The three forms of about ``n`` stones in ``work``: {"count", "gen", "adp", "peer" (bytes or None)}."""
    reach = math.sqrt(n / (RATE * math.pi))  # the disc within reach holds about n stones
    e = round(reach, 3)
    gen = work / "gen.toml"
    gen.write_text(SCENE + "[layer.generate]\n" + "".join(f"{k} = {json.dumps(v)}\n" for k, v in RECIPE.items())
                   + f"extent = [{-e}, {-e}, {e}, {e}]\nreach = {reach!r}\n")
    _web(gen, work / "gen", size)
    config = json.loads((work / "gen" / "scene.json").read_text())
    tx, _, tz = config["camera"]["target"]
    recipe = Generate(**RECIPE)
    mesh = ad.load_mesh("stone")
    params = generate_tiles(recipe, mesh, tiles_around(recipe, tx, tz, reach))  # what the generated page holds
    assert len(params) == config["instances"] == config["layers"][0]["instances"]
    ad.write_params(work / "stones.adp", params, mesh)
    (work / "adp.toml").write_text(SCENE + 'params = "stones.adp"\n')
    _web(work / "adp.toml", work / "adp", size)
    peer = None
    if len(params) <= peer_max:
        (work / "baked.glb").write_bytes(encode_baked(mesh, params))
        subprocess.run(["node", str(JS / "node_modules" / "gltfpack" / "cli.js"), "-i", str(work / "baked.glb"),
                        "-o", str(work / "peer.glb"), "-cc"], check=True, capture_output=True)
        peer = (work / "peer.glb").read_bytes()
        (work / "baked.glb").unlink()
    return {"count": len(params), "tiles": len(params) // tile_size(recipe)[0] ** 2, "peer": peer}


def first_frames(work: Path, names, runs: int, mbit: float, size) -> dict:
    from playwright.sync_api import sync_playwright

    server, _ = make_server(work, 0)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    url = f"http://127.0.0.1:{server.server_address[1]}/"
    links = {"loopback": None, f"{mbit:g} Mbit/s": mbit}
    out = {(link, name): [] for link in links for name in names}
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=shutil.which("chromium"), args=[
            "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"])
        for run in range(runs):
            for link, rate in links.items():
                for name in (names if run % 2 == 0 else names[::-1]):  # alternated
                    page = open_page(browser, (size[0], size[1] + 40), rate)
                    page.goto(url + name + "/index.html", wait_until="commit")
                    page.wait_for_function("window.axialdeform !== undefined", timeout=900_000, polling=50)
                    state = page.evaluate("window.axialdeform")
                    assert state.get("ready"), state
                    r = {"first": state["firstFrameMs"], "instances": state["instances"]}
                    if name == "gen":
                        r["timing"] = page.evaluate("window.axialdeformView.generated({records: false})[0].timing")
                    # later frames: the interval between animation frames, medians of 3
                    r["frame"] = page.evaluate("""async () => { const t = [];
                        let last = await new Promise((ok) => requestAnimationFrame(ok));
                        for (let i = 0; i < 3; i++) { const now = await new Promise((ok) => requestAnimationFrame(ok));
                          t.push(now - last); last = now; }
                        return t.sort((a, b) => a - b)[1]; }""")
                    out[(link, name)].append(r)
                    page.close()
        browser.close()
    server.shutdown()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--counts", default="10000,100000,1000000")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--mbit", type=float, default=10.0)
    ap.add_argument("--size", default="800x600")
    ap.add_argument("--peer-max", type=int, default=150_000)
    ap.add_argument("--bytes-only", action="store_true", help="the bytes alone: no browser, no first frames")
    args = ap.parse_args()
    size = tuple(int(x) for x in args.size.split("x"))
    med = statistics.median
    rows = []
    for n in (int(x) for x in args.counts.split(",")):
        work = Path(tempfile.mkdtemp(prefix="axd-gensizes-"))
        try:
            built = build(work, n, args.size, args.peer_max)
            gen, adp = _files(work / "gen"), _files(work / "adp")
            sizes = {"gen": {k: _bytes(gen, f) for k, f in PARTS.items()},
                     "adp": {k: _bytes(adp, f) for k, f in PARTS.items()}}
            peer = built["peer"]
            times = {} if args.bytes_only else first_frames(work, ["adp", "gen"], args.runs, args.mbit, size)
            rows.append((built, sizes, peer, times))
            print(f"\n{built['count']:,} stones ({built['tiles']} tiles of {TILE:g} x {TILE:g}; stone: "
                  f"{ad.load_mesh('stone').vertex_count} vertices):")
            for name, label in (("adp", "today's page (.adp)"), ("gen", "generated page")):
                s = sizes[name]
                total = sum(v[0] for v in s.values()), sum(v[1] for v in s.values())
                print(f"  {label:22} data {s['data'][0]:>12,} B ({s['data'][1]:>11,} gzip)   whole visit "
                      f"{total[0]:>12,} B ({total[1]:>11,} gzip; three.js {s['three'][1]:,}, code {s['code'][1]:,})")
            if peer is not None:
                pg = len(gzip.compress(peer, 9))
                print(f"  {'meshopt peer (-cc)':22} data {len(peer):>12,} B ({pg:>11,} gzip)")
                g = sizes["gen"]
                gen_total = sum(v[0] for v in g.values()), sum(v[1] for v in g.values())
                print(f"  generated page, whole visit / peer data: 1/{len(peer) / gen_total[0]:.0f} "
                      f"(gzip: 1/{pg / gen_total[1]:.0f}); data / peer data: 1/{len(peer) / g['data'][0]:.0f}")
            else:
                print(f"  meshopt peer: not made (a baked GLB of {built['count']:,} stones; --peer-max {args.peer_max:,})")
            for (link, name), rs in times.items():
                extra = ""
                if name == "gen":
                    gm = med(r["timing"]["generateMs"] for r in rs)
                    extra = f"; tiles: the GPU passes and the count's pixel {gm:.0f} ms"
                print(f"  {link:>12} {name}: first frame {med(r['first'] for r in rs) / 1000:.2f} s, later frames "
                      f"{med(r['frame'] for r in rs):.0f} ms ({rs[0]['instances']:,} held){extra}")
        finally:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()

"""A scene file as a web page against ``axialdeform render`` of it: the bytes
of the one-file page, its time to the first frame in headless Chromium
(Debian's chromium, SwiftShader WebGL 2), and how far its picture is from
render's at the same size and wind time (silhouette IoU over the background,
mean absolute difference per channel of 255).

    .venv/bin/python tools/web_scene.py [SCENE.toml] [--size 800x600] [--time 0] [--screenshot docs/gallery/web-landscape.png]

The page fills an 800x600 window (no --size at export); with --screenshot the
window (status line included) is saved at half size.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
from io import BytesIO
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", nargs="?", default=str(ROOT / "examples" / "landscape" / "landscape.toml"))
    ap.add_argument("--size", default="800x600", help="window and render size (default: %(default)s)")
    ap.add_argument("--time", type=float, default=0.0, help="the wind's time, seconds (default: %(default)s)")
    ap.add_argument("--screenshot", help="save the page's window as this PNG (half size)")
    args = ap.parse_args()

    from PIL import Image
    from playwright.sync_api import sync_playwright

    from axialdeform.core.options import RenderOptions
    from axialdeform.core.scene import load_scene
    from axialdeform.gl.image import parse_size, render_image
    from axialdeform.web import PageOptions, build_scene_file, write_page

    w, h = parse_size(args.size)
    scene = load_scene(args.scene)
    web = build_scene_file(scene, page=PageOptions(size=(w, h), fixed_size=False))
    work = Path(tempfile.mkdtemp(prefix="axd-web-scene-"))
    try:
        page_path = write_page(work / "scene.html", web)
        render = render_image(scene, size=(w, h), options=RenderOptions(time=args.time if scene.wind is not None else 0.0))
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=shutil.which("chromium"),
                                         args=["--use-angle=swiftshade", "--enable-unsafe-swiftshader", "--no-sandbox"])
            page = browser.new_page(viewport={"width": w, "height": h})
            errors = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.goto(page_path.as_uri() + f"?t={args.time}")
            page.wait_for_function("window.axialdeform && window.axialdeform.ready !== undefined", timeout=300_000)
            state = page.evaluate("window.axialdeform")
            assert state.get("ready"), state
            shown = page.screenshot()  # with the status line, for --screenshot
            page.evaluate("document.querySelector('.axd-status').style.visibility = 'hidden'")
            page.wait_for_timeout(500)
            png = page.screenshot()  # the picture alone, to compare
            browser.close()
        shot = np.asarray(Image.open(BytesIO(png)).convert("RGB"))
        bg = np.asarray(scene.background) * 255.0
        ms = np.abs(shot.astype(np.float64) - bg).max(axis=2) > 12
        mr = np.abs(render.astype(np.float64) - bg).max(axis=2) > 12
        iou = (ms & mr).sum() / max((ms | mr).sum(), 1)
        layers = [layer for layer in web.config["layers"] if not layer["terrain"]]
        print(f"{args.scene}: {len(layers)} layers{' and a terrain' if len(layers) < len(web.config['layers']) else ''}, "
              f"{web.count:,} instances")
        print(f"  one-file page:        {page_path.stat().st_size:>12,} bytes")
        print(f"  first frame:          {state['firstFrameMs'] / 1000:.2f} s after navigation (the page's own count)")
        diff = np.abs(shot - render.astype(np.float64)).mean()
        print(f"  vs render at t={args.time:g}:   IoU {iou:.4f}, mean |difference| {diff:.2f} of 255"
              " (the status line hidden)")
        print(f"  console errors:       {len(errors)}")
        if args.screenshot:
            img = Image.open(BytesIO(shown)).convert("RGB").resize((w // 2, h // 2), Image.LANCZOS)
            img.save(args.screenshot, optimize=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()

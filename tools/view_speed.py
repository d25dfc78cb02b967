"""Frame time of the viewer (headless, 960x720, 4x MSAA) with 1 000 000 stones,
framed and zoomed in, with and without LOD (culling on).  Prints one line per case.

    .venv/bin/python tools/view_speed.py
"""

import time

import axialdeform as ad
from axialdeform.viewer import Viewer

stone = ad.load_mesh("stone")
params = ad.random_params(stone, 1_000_000, seed=0)
for lod in (True, False):
    v = Viewer.create(stone, params, headless=True, size=(960, 720), options=ad.RenderOptions(lod=lod))
    try:
        for name, zoom in (("framed", 1.0), ("zoomed in x0.02", 0.02)):
            v.reset_camera()
            v.orbit.zoom(zoom)
            v.step(1)
            t = time.perf_counter()
            v.step(2)
            v.ctx.finish()
            dt = (time.perf_counter() - t) / 2
            stats = v.renderer.stats
            print(f"lod={lod} {name}: {dt:.2f} s/frame, drawn {stats['visible']}, levels {stats['levels']}", flush=True)
    finally:
        v.release()
        v.wnd.destroy()

"""The deformation inside a moderngl-window app: a meadow of leaf blades
standing up and swaying in a gust of wind -- each blade's control axis is
bent a little more each frame, all blades in one ``update_params``.

    python examples/04_moderngl_window_app.py --window       # a window (needs a display)
    python examples/04_moderngl_window_app.py                # headless: writes 04_moderngl_window_app.png
    python examples/04_moderngl_window_app.py --quick        # fewer blades, a small picture

Headless runs moderngl-window's own headless window (an EGL context).
"""

import argparse
import logging
from pathlib import Path

import moderngl_window as mglw
import numpy as np

import axialdeform as ad

T = np.linspace(0.0, 1.0, 5)        # control points P1..P5 along the blade
SWAY = T ** 2 - np.mean(T ** 2)     # zero-mean: the tip moves most


class Meadow(mglw.WindowConfig):
    gl_version = (3, 3)
    title = "axialdeform meadow"
    window_size = (800, 600)
    aspect_ratio = None
    samples = 4
    clear_color = None
    log_level = logging.WARNING
    count = 3000                    # set from the command line before the app is made

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.mesh = ad.load_mesh("leaf")
        n = self.count
        rng = np.random.default_rng(5)
        self.params = ad.random_params(self.mesh, n, seed=5, bend=0.05, placement="disc", spacing=0.6,
                                       tilt=(-0.15, 0.15))
        self.rest = self.params[:, 0:10].copy()
        self.xz = self.params[:, [10, 12]].astype(np.float64)
        self.stiffness = rng.uniform(0.6, 1.4, n)
        self.renderer = ad.AxialRenderer(self.ctx, self.mesh, self.params)
        self.renderer.color = (0.16, 0.36, 0.07)
        self.ground = ad.GroundPlane(self.ctx, color=(0.30, 0.26, 0.16)).fit(self.mesh, self.params, sink=0.0)
        self.ground.center[1] = 0.0
        radius = float(np.abs(self.xz).max())
        self.camera = ad.Camera(eye=(1.3 * radius, 0.9 * radius, 1.6 * radius), target=(0.0, 0.0, 0.0),
                                fovy=40.0, near=0.05 * radius, far=8.0 * radius)

    def on_render(self, time, frame_time):
        # wind: a wave travelling along x; each blade bends across x (the u offset)
        gust = 0.35 * np.sin(1.5 * time - 0.35 * self.xz[:, 0]) + 0.15 * np.sin(3.1 * time + self.xz[:, 1])
        bend = (gust / self.stiffness)[:, None] * SWAY[None, :]
        self.params[:, 0:10] = self.rest
        self.params[:, 0:10:2] += bend.astype(np.float32)
        self.renderer.update_params(self.params)              # in place, every frame

        background = (0.78, 0.86, 0.95)
        self.ctx.clear(*background, 1.0, depth=1.0)
        view, proj = self.camera.view(), self.camera.projection(self.wnd.aspect_ratio)
        self.ground.render(view, proj, background=background)
        self.renderer.render(view, proj, "solid")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default=".", help="folder for the PNG (default: current folder)")
    ap.add_argument("-n", "--count", type=int, default=3000)
    ap.add_argument("--frames", type=int, default=20, help="frames to draw headless before the picture")
    ap.add_argument("--window", action="store_true", help="open a window instead (needs a display)")
    ap.add_argument("--quick", action="store_true", help="400 blades, a small picture (tests)")
    args = ap.parse_args()
    Meadow.count = 400 if args.quick else args.count
    size = "320x240" if args.quick else "800x600"
    frames = 6 if args.quick else args.frames

    if args.window:
        mglw.run_window_config(Meadow, args=["--size", size])
        return
    app = mglw.create_window_config_instance(Meadow, args=["--window", "headless", "--backend", "egl", "--size", size])
    for i in range(frames):                               # the same loop mglw runs, at 24 frames a second
        app.wnd.use()
        app.wnd.render(i / 24, 1 / 24)
        app.wnd.swap_buffers()
    assert app.renderer.instances.reallocations == 0
    # the headless window's framebuffer is multisampled: read_pixels resolves it, then reads
    image = ad.read_pixels(app.ctx, app.wnd.fbo, resolve=True)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    ad.save_png(out / "04_moderngl_window_app.png", image)
    print(f"wrote {out / '04_moderngl_window_app.png'} ({Meadow.count} blades, {frames} frames)")
    app.wnd.destroy()


if __name__ == "__main__":
    main()

"""The deformation inside a moderngl-window app: a meadow of leaf blades
standing up and swaying in gusts of wind.  The wind runs on the GPU
(``ad.Wind``, docs/wind.md): it moves each blade's control points in the
vertex shader from a few uniforms, so no instance data is uploaded after the
first frame.  Blades differ in size, twist and taper (extended instances).

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

WIND = ad.Wind(direction=(1.0, 0.0, 0.3), strength=0.22, gustiness=0.7, frequency=0.35, wavelength=6.0)


#: how the frames look: a sky-blue background, the default light
LOOK = ad.Look(background=(0.78, 0.86, 0.95))

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
        self.mesh = ad.load_mesh("leafcard")  # textured card, alpha cut-out (tools/make_leaf_card.py)
        n = self.count
        # 19 numbers a blade: the 16, then size 0.7..1.3, a twist up to 0.6 rad, a taper up to 0.5
        blades = ad.Variation(bend=0.05, tilt=(-0.15, 0.15), scale=(0.7, 1.3), twist=0.6, taper=0.5)
        self.params = ad.random_params(self.mesh, n, seed=5, variation=blades, placement="disc", spacing=0.6)
        self.xz = self.params[:, [10, 12]].astype(np.float64)
        self.renderer = ad.AxialRenderer(self.ctx, self.mesh, self.params, options=ad.RenderOptions(wind=WIND))
        self.shadow = ad.gl.ShadowMap(self.ctx, 2048)
        self.ground = ad.gl.GroundPlane(self.ctx, color=(0.30, 0.26, 0.16)).fit(self.mesh, self.params, sink=0.0)
        self.ground.center[1] = 0.0
        radius = float(np.abs(self.xz).max())
        self.camera = ad.Camera(eye=(1.3 * radius, 0.9 * radius, 1.6 * radius), target=(0.0, 0.0, 0.0),
                                fovy=40.0, near=0.05 * radius, far=8.0 * radius)

    def on_render(self, time, frame_time):
        look = LOOK
        self.shadow.fit(self.mesh, self.params, look.light_dir, extra=[[*self.ground.center, 0.6 * self.ground.radius]])
        self.renderer.time = time                             # the shadows bend in this frame's wind
        self.renderer.render_shadow(self.shadow)              # blades shadow the ground and each other
        self.ctx.clear(*look.background, 1.0, depth=1.0)
        view, proj = self.camera.view(), self.camera.projection(self.wnd.aspect_ratio)
        self.ground.render(view, proj, look=look, shadow=self.shadow)
        self.renderer.render(view, proj, "solid", look=look, shadow=self.shadow,
                             time=time)  # the wind: uniforms only, no upload


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
    image = ad.gl.read_pixels(app.ctx, app.wnd.fbo, resolve=True)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    ad.save_png(out / "04_moderngl_window_app.png", image)
    print(f"wrote {out / '04_moderngl_window_app.png'} ({Meadow.count} blades, {frames} frames)")
    app.wnd.destroy()


if __name__ == "__main__":
    main()

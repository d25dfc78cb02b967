"""1000 leaves falling and fluttering: every frame, each leaf's position,
orientation AND bend change, written into the same instance buffer in place
(``update_params``: no reallocation).

Writes ``02_falling_leaves.gif`` (animated, offscreen) and
``02_falling_leaves.png`` (its first frame) into --output.

    python examples/02_falling_leaves.py                # 1000 leaves, 36 frames
    python examples/02_falling_leaves.py --window       # live, in the viewer
    python examples/02_falling_leaves.py --quick        # 150 leaves, 6 small frames
"""

import argparse
from pathlib import Path

import numpy as np
from PIL import Image

import axialdeform as ad
from axialdeform.core.io.atomic import atomic_path
from axialdeform.gl.image import parse_size

# where each control point sits along the leaf (t of P1..P5) and a zero-mean
# curl profile over them: the tip and stem bend one way, the middle the other
T = np.linspace(0.0, 1.0, 5)
CURL = (T - 0.5) ** 2 - np.mean((T - 0.5) ** 2)


class FallingLeaves:
    """Per-leaf motion constants, drawn once; ``at(t)`` gives every leaf's
    16 numbers at time ``t`` (seconds) with array operations only.

    count : number of leaves; seed : random seed; size : side of the
    square area they fall over and height they fall from, world units.
    """

    def __init__(self, count, seed=1, size=16.0):
        rng = np.random.default_rng(seed)
        n = self.count = count
        self.size = size
        self.start = rng.uniform([-size / 2, 0.0, -size / 2], [size / 2, size, size / 2], (n, 3))
        self.speed = rng.uniform(0.6, 1.2, n)             # fall, world units / s
        self.sway = rng.uniform(0.3, 0.9, (n, 1))         # side-to-side drift amplitude
        self.freq = rng.uniform(0.8, 1.6, n)              # sway frequency, rad / s
        self.flutter = rng.uniform(3.0, 6.0, n)           # flutter frequency, rad / s
        self.phase = rng.uniform(0.0, 2 * np.pi, (n, 3))
        self.spin = rng.uniform(-1.0, 1.0, n)             # yaw rate, rad / s
        self.yaw = rng.uniform(0.0, 2 * np.pi, n)
        self.curl = rng.uniform(0.3, 0.9, n)              # rest curl, fraction of L
        self.floor = 0.0

    def at(self, t):
        """(count, 16) float32 parameters at time ``t`` seconds."""
        n = self.count
        f = self.freq * t + self.phase[:, 0]
        flutter = self.flutter * t + self.phase[:, 1]
        params = ad.Instances.zeros(n)  # (n, 16) float32 with named views: offsets, position, rotation
        # offsets: u (across the leaf) sways as a travelling wave, v (out of
        # the leaf's plane) curls and uncurls with the flutter
        u = 0.05 * np.sin(flutter[:, None] - 2.0 * T[None, :])
        u -= u.mean(axis=1, keepdims=True)
        v = (self.curl + 0.6 * np.sin(flutter))[:, None] * CURL[None, :]
        params.offsets = np.stack([u, v], axis=2)  # (n, 5, 2): (u, v) of each control point
        # position: fall (wrapping to the top), drift in x and z
        y = self.floor + np.mod(self.start[:, 1] - self.speed * t, self.size)
        x = self.start[:, 0] + self.sway[:, 0] * np.sin(f)
        z = self.start[:, 2] + self.sway[:, 0] * np.cos(0.7 * f + self.phase[:, 2])
        params.position = np.stack([x, y, z], axis=1)
        # orientation: lying roughly flat (rx ~ 90 deg), rocking with the sway
        params.rotation = np.stack([np.pi / 2 + 0.5 * np.sin(f + 0.5), self.yaw + self.spin * t,
                                    0.45 * np.cos(f) + 0.15 * np.sin(flutter)], axis=1)
        return params

    def colours(self, seed=1):
        """(count, 3) linear RGB: autumn greens, yellows, oranges and reds."""
        rng = np.random.default_rng(seed + 1)
        palette = np.array([[0.30, 0.50, 0.10], [0.75, 0.55, 0.05], [0.80, 0.30, 0.04], [0.55, 0.10, 0.04]])
        pick = rng.choice(len(palette), size=self.count, p=[0.25, 0.3, 0.3, 0.15])
        return palette[pick] * rng.uniform(0.75, 1.1, (self.count, 1))


def save_gif(path, frames, fps):
    """Frames ``(h, w, 3) uint8`` -> an endless animated GIF, written atomically."""
    images = [Image.fromarray(f).quantize(colors=64, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
              for f in frames]
    with atomic_path(path, suffix=".gif") as tmp:
        images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                       duration=int(1000 / fps), loop=0, optimize=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default=".", help="folder for the GIF and PNG (default: current folder)")
    ap.add_argument("-n", "--count", type=int, default=1000)
    ap.add_argument("--frames", type=int, default=36)
    ap.add_argument("--fps", type=float, default=12.0)
    ap.add_argument("--size", default="480x360")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--quick", action="store_true", help="150 leaves, 6 small frames (tests)")
    ap.add_argument("--window", action="store_true", help="watch it live in the viewer")
    args = ap.parse_args()
    count, frames, size = (150, 6, (200, 150)) if args.quick else (args.count, args.frames, parse_size(args.size))

    mesh = ad.load_mesh("leafcard")  # a textured card with an alpha cut-out (tools/make_leaf_card.py)
    leaves = FallingLeaves(count, args.seed, size=16.0 * (count / 1000) ** (1 / 3))
    if args.window:
        from axialdeform.viewer import Viewer, ViewerSettings

        Viewer.open(mesh, leaves.at(0.0), settings=ViewerSettings(animate=leaves.at, tint=leaves.colours(args.seed), seed=args.seed))
        return

    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    side = leaves.size
    cam = ad.Camera(eye=(1.25 * side, 0.95 * side, 1.25 * side), target=(0.0, 0.38 * side, 0.0), fovy=40.0,
                    near=0.1 * side, far=5.0 * side)
    view, proj = cam.view(), cam.projection(size[0] / size[1])
    look = ad.Look(background=(0.82, 0.87, 0.93))
    ctx = ad.create_context()
    images = []
    with ad.AxialRenderer(ctx, mesh, leaves.at(0.0)) as r, ad.gl.GroundPlane(ctx, color=(0.30, 0.27, 0.20)) as ground, \
            ad.Offscreen(ctx, size) as target, ad.gl.ShadowMap(ctx, 1024) as shadow:
        # the tint multiplies the leaf texture: autumn colours over its veins
        r.set_tint(leaves.colours(args.seed) / np.array([0.30, 0.50, 0.10]).mean() * 0.6)
        ground.center, ground.radius = np.zeros(3), 1.2 * side
        for i in range(frames):
            params = leaves.at(i / args.fps)
            r.update_params(params)   # same count: written in place
            shadow.fit(mesh, params, look.light_dir, extra=[[*ground.center, ground.radius]])
            r.render_shadow(shadow)   # the leaves' shadows: one more instanced draw
            target.use(look.background)
            ground.render(view, proj, look=look, shadow=shadow)
            r.render(view, proj, "solid", look=look, shadow=shadow)
            images.append(target.read())
        assert r.instances.reallocations == 0, "the instance buffer was reallocated"
    ctx.release()
    save_gif(out / "02_falling_leaves.gif", images, args.fps)
    ad.save_png(out / "02_falling_leaves.png", images[0])
    print(f"wrote {out / '02_falling_leaves.gif'} ({count} leaves, {frames} frames, 0 reallocations)")


if __name__ == "__main__":
    main()

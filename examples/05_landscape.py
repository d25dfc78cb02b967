"""A small landscape from one terrain, one stone, one grass blade, one leaf and
one trunk-like shape, all from a scene file (examples/landscape/landscape.toml):
stones scattered on the river banks, grass where a density map says, trunks
on the slopes, leaves falling.  The grass sways in the GPU wind (uniforms
only); the leaves fall on the CPU (``update_params`` into the same buffer).

Writes ``05_landscape.png`` (the first frame) and ``05_landscape.gif``
(the animation) into --output.

    python examples/05_landscape.py            # full counts, 800x600, 24 frames
    python examples/05_landscape.py --quick    # 40 % of the instances, 320x240, 5 frames

The same scene from the command line:

    axialdeform render examples/landscape/landscape.toml -o landscape.png
"""

import argparse
from pathlib import Path

import numpy as np
from PIL import Image

import axialdeform as ad
from axialdeform.gl.scene import SceneRenderer, scene_camera

SCENE = Path(__file__).resolve().parent / "landscape" / "landscape.toml"


class Falling:
    """Leaves that fall from their start height to the ground under them,
    drifting and spinning: ``at(t)`` -> the leaves layer's parameters."""

    def __init__(self, layer, up: int, seed: int = 3):
        rng = np.random.default_rng(seed)
        n = len(layer.params)
        self.start = layer.params.astype(np.float64)
        self.ground = ad.Instances.of(self.start).position[:, up] - layer.lift  # where the scatter put them
        self.speed = rng.uniform(0.8, 1.5, n)
        self.spin = rng.uniform(-1.5, 1.5, (n, 3))
        self.phase = rng.uniform(0, 2 * np.pi, n)
        self.up = up

    def at(self, t: float) -> np.ndarray:
        p = ad.Instances.of(self.start).copy()  # named views of the record: position, rotation, ...
        fallen = np.minimum(self.speed * t, p.position[:, self.up] - self.ground)
        p.position[:, self.up] -= fallen
        landed = (p.position[:, self.up]) <= self.ground + 1e-6
        drift = 0.4 * np.sin(1.3 * t + self.phase) * ~landed
        p.position[:, 0] += drift
        p.rotation += self.spin * np.where(landed, fallen / self.speed, t)[:, None]
        return p.astype(np.float32)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer instances, small frames (the test suite's mode)")
    ap.add_argument("-o", "--output", default=".", help="folder to write into")
    args = ap.parse_args()
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    size, frames = ((320, 240), 5) if args.quick else ((800, 600), 24)

    scene = ad.Scene.load(SCENE, scale_counts=0.4 if args.quick else 1.0)   # layers, terrain, wind, look
    leaves = next(layer for layer in scene.layers if layer.name == "leaves")
    falling = Falling(leaves, "xyz".index(scene.up))
    ctx = ad.create_context()
    pictures = []
    try:
        cam = scene_camera(scene, size[0] / size[1])
        view, proj = cam.view(), cam.projection(size[0] / size[1])
        with SceneRenderer(ctx, scene) as sr, ad.Offscreen(ctx, size, samples=4) as target:
            leaf_renderer = sr.layer("leaves")
            for k in range(frames):
                t = k * 0.25
                leaf_renderer.update_params(falling.at(t))  # the CPU path: same buffer, in place
                target.use(scene.background)
                sr.render(view, proj, "solid", time=t)  # the grass's wind: uniforms only
                pictures.append(target.read())
        assert ctx.error == "GL_NO_ERROR", ctx.error
    finally:
        ctx.release()
    ad.save_png(out / "05_landscape.png", pictures[0])
    Image.fromarray(pictures[0]).save(out / "05_landscape.gif", save_all=True,
                                      append_images=[Image.fromarray(p) for p in pictures[1:]], duration=80, loop=0)
    counts = ", ".join(f"{len(layer.params)} {layer.name}" for layer in scene.layers)
    print(f"wrote {out / '05_landscape.png'} and {out / '05_landscape.gif'} ({counts}; {frames} frames, "
          f"{size[0]}x{size[1]})")


if __name__ == "__main__":
    main()

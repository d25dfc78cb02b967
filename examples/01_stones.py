"""A river bank of 5000 stones, each bent by its own control axis.

Writes two pictures into --output (default: the current folder):

* ``01_stones.png`` -- solid | wireframe of the SAME 16 numbers per stone,
  side by side (the thesis' Figs. 7 and 8: same parameters, same shape);
* ``01_stones_bank.png`` -- the same stones on a ground plane, each with its
  own colour (the record's tint field: 22 numbers a stone).

    python examples/01_stones.py                  # 5000 stones, offscreen
    python examples/01_stones.py --window         # the same scene in the viewer
    python examples/01_stones.py --quick          # 600 stones, small pictures
"""

import argparse
from pathlib import Path

import numpy as np

import axialdeform as ad
from axialdeform.gl.image import parse_size


def river_bank(mesh, count, seed):
    """(count, 16) parameters: stones on a flat bank by the water.

    Bend and orientation come from ``random_params``; the positions are
    replaced by a jittered strip, 2 stones along the river for 1 up the bank.
    """
    params = ad.random_params(mesh, count, seed=seed, variation=ad.Variation(bend=0.14, tilt=(-0.2, 0.2)))
    rng = np.random.default_rng(seed)
    spacing = 0.8 * mesh.axis.length                 # world units between neighbours
    cols = int(np.ceil(np.sqrt(2 * count)))
    k = np.arange(count)
    x = (k % cols - (cols - 1) / 2) * spacing + rng.uniform(-0.3, 0.3, count) * spacing
    z = (k // cols) * spacing + rng.uniform(-0.3, 0.3, count) * spacing
    y = rng.uniform(0.0, 0.12, count)                  # resting on the ground, some sunk deeper
    params.position = np.stack([x, y, -z], axis=1)  # px py pz: a named view of the record
    return params


def stone_colours(count, seed):
    """(count, 3) linear RGB: greys, browns and a few ochre stones."""
    rng = np.random.default_rng(seed + 1)
    palette = np.array([[0.42, 0.41, 0.40], [0.36, 0.31, 0.26], [0.50, 0.46, 0.40], [0.55, 0.40, 0.22]])
    pick = rng.choice(len(palette), size=count, p=[0.4, 0.3, 0.22, 0.08])
    return palette[pick] * rng.uniform(0.8, 1.15, (count, 1))


def camera(params):
    """Standing at the water's edge, looking up the bank."""
    xyz = params.position
    depth = -xyz[:, 2].min()
    eye = (0.0, 0.3 * depth + 3.0, 0.1 * depth + 2.0)
    target = (0.0, 0.0, -0.45 * depth)
    return ad.Camera(eye, target, fovy=45.0, near=0.5, far=4.0 * depth + 50.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default=".", help="folder for the pictures (default: current folder)")
    ap.add_argument("-n", "--count", type=int, default=5000)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--size", default="640x480", help="size of each panel")
    ap.add_argument("--quick", action="store_true", help="600 stones, small pictures (tests)")
    ap.add_argument("--window", action="store_true", help="open the scene in the interactive viewer")
    args = ap.parse_args()
    count, size = (600, (320, 240)) if args.quick else (args.count, parse_size(args.size))

    mesh = ad.load_mesh("stone")
    params = river_bank(mesh, count, args.seed)
    if args.window:
        from axialdeform.viewer import Viewer, ViewerSettings

        Viewer.open(mesh, params, settings=ViewerSettings(seed=args.seed))
        return
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    cam = camera(params)

    # 1. solid | wireframe, the same parameters and camera
    # (the ground, shadows, multisampling and hidden-line wireframe are on by default)
    image = ad.render_image(mesh, params, size, ("solid", "wireframe"), camera=cam)
    ad.save_png(out / "01_stones.png", image)

    # 2. the bank: ground plane + one colour per stone, in your own offscreen target;
    # the colours are the record's tint field (22 numbers a stone: a file keeps them)
    params = ad.core.tint_params(params, stone_colours(count, args.seed))
    ctx = ad.create_context()
    look = ad.Look(background=(0.80, 0.86, 0.92))   # light, ambient, background: one value object
    with ad.AxialRenderer(ctx, mesh, params) as stones, ad.gl.GroundPlane(ctx, color=(0.42, 0.37, 0.30)) as ground, \
            ad.Offscreen(ctx, size) as target, ad.gl.ShadowMap(ctx) as shadow:
        ground.fit(mesh, params, margin=3.0)
        shadow.fit(mesh, params, look.light_dir)          # the key light's shadow map around the stones
        stones.render_shadow(shadow)             # one more instanced draw
        view, proj = cam.view(), cam.projection(size[0] / size[1])
        target.use(look.background)
        ground.render(view, proj, look=look, shadow=shadow)
        stones.render(view, proj, "solid", look=look, shadow=shadow)
        ad.save_png(out / "01_stones_bank.png", target.read())
    ctx.release()
    print(f"wrote {out / '01_stones.png'} and {out / '01_stones_bank.png'} ({count} stones)")


if __name__ == "__main__":
    main()

"""A walk through a generated landscape that does not end: river-bank stones, grass blades and trees
of ten axes made from three recipes (examples/generated/walk.toml, ``[layer.generate]``, docs/generate.md) -- no list of
instances anywhere.  The viewer makes the tiles within reach of the camera as it walks and lets the
far ones go, so what it holds stays the same size however far it goes.

Writes ``07_generated_walk.png`` (at the start) and ``07_generated_walk_far.png`` (after a walk of
several hundred units) into --output, and prints how many instances the viewer held at each.

    python examples/07_generated_walk.py            # 800x600, 60 frames of the walk
    python examples/07_generated_walk.py --quick    # 320x240, 20 frames (longer strides)

The same from the command line:

    axialdeform view examples/generated/walk.toml --walk 5,3      # a window; --headless --frames N too
    axialdeform render examples/generated/walk.toml -o walk.png   # the recipe's extent, materialized
"""

import argparse
from pathlib import Path

import numpy as np

import axialdeform as ad
from axialdeform.viewer import Viewer, ViewerSettings

SCENE = Path(__file__).resolve().parent / "generated" / "walk.toml"


def held(viewer) -> int:
    """Instances the viewer holds now: its own layer and the scene's others."""
    return viewer.renderer.count + sum(renderer.count for _, renderer, _ in viewer.layers)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a small picture, fewer frames (the test suite's mode)")
    ap.add_argument("-o", "--output", default=".", help="folder to write into")
    args = ap.parse_args()
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    size, frames = ((320, 240), 20) if args.quick else ((800, 600), 60)
    stride = 600.0 / frames  # the walk: 600 units along x, 360 along z, whatever the frame count
    viewer = Viewer.create(ad.Scene.load(SCENE), headless=True, size=size, settings=ViewerSettings(walk=(stride, 0.6 * stride)))
    try:
        viewer.step(1)
        viewer.save_screenshot(out / "07_generated_walk.png")
        start, near = held(viewer), viewer.orbit.target.copy()
        viewer.step(frames)
        viewer.save_screenshot(out / "07_generated_walk_far.png")
        far, there = held(viewer), viewer.orbit.target.copy()
    finally:
        viewer.release()
        viewer.wnd.destroy()
    print(f"wrote {out / '07_generated_walk.png'} and {out / '07_generated_walk_far.png'}: "
          f"{start} instances held at ({near[0]:.0f}, {near[2]:.0f}), {far} at ({there[0]:.0f}, {there[2]:.0f}), "
          f"{np.hypot(*(there - near)[[0, 2]]):.0f} units away")


if __name__ == "__main__":
    main()

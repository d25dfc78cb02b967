"""A forest of 2 000 distinct trees from ONE tree mesh and a few dozen numbers
per tree (examples/forest/forest.toml): the bundled low-poly tree with ten
axes in a hierarchy (trunk -> branches -> twigs, examples/forest/tree-axes.toml),
scattered on the landscape example's terrain.  Each tree leans its trunk and
droops its branches and twigs by its own numbers; the wind sways every axis
(the tips of the branches most), all in one instanced draw.

Writes ``06_forest.png`` (the whole forest), ``06_forest_close.png`` (a
walk among the trees) and ``06_forest.gif`` (the wind) into --output.

    python examples/06_forest.py            # 2 000 trees, 800x600, 12 frames
    python examples/06_forest.py --quick    # 15 % of the trees, 320x240, 4 frames

The same forest from the command line, as a page and as an instanced glTF:

    axialdeform render examples/forest/forest.toml -o forest.png
    axialdeform web examples/forest/forest.toml -o forest.html
    axialdeform export examples/forest/forest.toml --instanced -o forest.glb
"""

import argparse
from pathlib import Path

from PIL import Image

import axialdeform as ad
from axialdeform.gl.scene import SceneRenderer, scene_camera

SCENE = Path(__file__).resolve().parent / "forest" / "forest.toml"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer trees, small frames (the test suite's mode)")
    ap.add_argument("-o", "--output", default=".", help="folder to write into")
    args = ap.parse_args()
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    size, frames = ((320, 240), 4) if args.quick else ((800, 600), 12)
    aspect = size[0] / size[1]

    scene = ad.Scene.load(SCENE, scale_counts=0.15 if args.quick else 1.0)
    trees = scene.layers[0]
    k = trees.mesh.axis_count  # 10 axes: 10 k + 6 = 106 numbers a tree
    close = ad.Camera(eye=(-6.0, 7.5, 14.0), target=(0.0, 4.0, 2.0), fovy=40.0, near=0.1, far=80.0)
    ctx = ad.create_context()
    try:
        with SceneRenderer(ctx, scene) as sr, ad.Offscreen(ctx, size, samples=4) as target:
            pictures = []
            for cam in (scene_camera(scene, aspect), close):
                target.use(scene.background)
                sr.render(cam.view(), cam.projection(aspect), "solid", time=0.0)
                pictures.append(target.read())
            gif = []
            for f in range(frames):  # the wind: uniforms only, every axis of every tree
                target.use(scene.background)
                sr.render(close.view(), close.projection(aspect), "solid", time=0.3 * f)
                gif.append(target.read())
        assert ctx.error == "GL_NO_ERROR", ctx.error
    finally:
        ctx.release()
    ad.save_png(out / "06_forest.png", pictures[0])
    ad.save_png(out / "06_forest_close.png", pictures[1])
    Image.fromarray(gif[0]).save(out / "06_forest.gif", save_all=True,
                                 append_images=[Image.fromarray(p) for p in gif[1:]], duration=100, loop=0)
    per_tree = 4 * trees.params.shape[1]
    baked = 24 * trees.mesh.vertex_count  # positions + normals of one baked tree, float32
    print(f"wrote {out / '06_forest.png'}, {out / '06_forest_close.png'} and {out / '06_forest.gif'} "
          f"({len(trees.params)} trees of {k} axes: {per_tree} bytes a tree against {baked} baked; "
          f"{frames} frames, {size[0]}x{size[1]})")


if __name__ == "__main__":
    main()

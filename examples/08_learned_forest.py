"""Scenery by example: a forest learned from a survey of where trees stand, then planted on ANOTHER
terrain (docs/learn.md).

The survey here is made up for the example (trees in clumps, thicker on steep ground, on rolling hills of
their own); ``axialdeform learn`` reads real ones the same way (a CSV of x, z, size, kind).  What is learned:
how the trees' density depends on the ground (slope, altitude, aspect), that they stand in clumps and how
large, and their sizes.  Then the same kind of forest grows on the landscape example's terrain, which the
survey never saw: thick on its slopes, thin on its flats, in clumps.

Writes ``08_learned_forest.png`` (the forest on the landscape) and ``08_survey.csv`` (the survey) into --output.

    python examples/08_learned_forest.py            # 800x600
    python examples/08_learned_forest.py --quick    # 320x240 (the test suite's mode)

The same from the command line:

    axialdeform learn 08_survey.csv --terrain hills.toml --apply-to examples/landscape/landscape.toml -o forest.toml
"""

import argparse
from pathlib import Path

import numpy as np
from PIL import Image

import axialdeform as ad
from axialdeform.core.io.example import read_terrain, write_learned

LANDSCAPE = Path(__file__).resolve().parent / "landscape" / "landscape.toml"


def survey(folder: Path) -> tuple[Path, Path]:
    """A made-up survey: 120 x 90 units of rolling hills (a 16-bit height map and its scene file), and trees in
    clumps of radius 2, more of them where the ground is steep."""
    x, z = np.meshgrid(np.linspace(0, 1, 121), np.linspace(0, 1, 91))
    hills = 0.5 + 0.3 * np.sin(7 * x + 1) * np.cos(5 * z) + 0.1 * x
    Image.fromarray(np.round(hills * 65535).astype(np.uint16)).save(folder / "08_hills.png")
    scene = folder / "08_hills.toml"
    scene.write_text('[terrain]\nheightmap = "08_hills.png"\nheight_scale = 30.0\nextent = [120.0, 90.0]\n')
    rng = np.random.default_rng(8)
    parents = rng.uniform([-64, -49], [64, 49], (rng.poisson(0.15 * 128 * 98), 2))
    slope = read_terrain(scene)[2].at(parents, ["slope"])[:, 0]  # degrees
    parents = parents[rng.uniform(size=len(parents)) < np.clip(slope / 25.0, 0.05, 1.0)]  # thicker where steep
    trees = np.repeat(parents, rng.poisson(6, len(parents)), axis=0)
    a, r = rng.uniform(0, 2 * np.pi, len(trees)), 2.0 * np.sqrt(rng.uniform(size=len(trees)))
    trees = trees + np.stack([r * np.cos(a), r * np.sin(a)], 1)
    trees = trees[(np.abs(trees[:, 0]) < 60) & (np.abs(trees[:, 1]) < 45)]
    size = rng.lognormal(0.0, 0.2, len(trees))
    csv = folder / "08_survey.csv"
    np.savetxt(csv, np.column_stack([trees, size]), delimiter=",", header="x,z,size", comments="", fmt="%.3f")
    return csv, scene


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small frames (the test suite's mode)")
    ap.add_argument("-o", "--output", default=".", help="folder to write into")
    args = ap.parse_args()
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    csv, hills = survey(out)
    learned = ad.learn_layer(csv, hills, window=(-60, -45, 60, 45), features=("slope", "altitude", "eastness", "northness"))
    for lay in learned:
        print(f"learned from {lay.count} trees: {lay.spacing.pattern}, terms {' '.join(lay.intensity.labels) or 'none'}")
    scene_file = out / "08_learned_forest.toml"
    write_learned(scene_file, learned, LANDSCAPE, mesh="tree", size=0.35)
    scene = ad.Scene.load(scene_file)
    size = (320, 240) if args.quick else (800, 600)
    camera = ad.Camera(eye=(-22.0, 17.0, 27.0), target=(1.0, 0.0, 0.0), fovy=40.0, near=0.5, far=150.0)
    image = ad.render_image(scene, size=size, camera=camera)
    ad.save_png(out / "08_learned_forest.png", image)
    print(f"wrote {out / '08_learned_forest.png'} ({len(scene.layers[0].params)} trees on the landscape) and {csv}")


if __name__ == "__main__":
    main()

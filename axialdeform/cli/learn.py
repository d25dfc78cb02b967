"""``axialdeform learn``: a generated layer learned from an example of placed objects (docs/learn.md)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..core.ground_features import FEATURES
from ..core.io.example import layer_mesh, learn_layer, learned_paths, read_example, read_terrain, write_learned
from ..core.io.mesh import load_mesh
from ..core.io.safeio import check_output_path
from ..core.io.scene import parse_scene
from ..core.learn import ERRORS
from ._common import add_overwrite


def _window(text: str) -> tuple:
    try:
        w = tuple(float(v) for v in text.split(","))
    except ValueError:
        w = ()
    if len(w) != 4 or not all(math.isfinite(v) for v in w) or not (w[2] > w[0] and w[3] > w[1]):
        raise argparse.ArgumentTypeError(f"expected x0,z0,x1,z1 with x1 > x0 and z1 > z0, found {text!r}")
    return w


def add_parser(sub) -> None:
    p = sub.add_parser("learn", help="learn a generated layer from an example of placed objects", description=(
        "Learn where objects stand (their intensity as a function of the ground's altitude, slope, curvature, "
        "aspect and distance to water; their spacing; their sizes) from EXAMPLE, and write a scene file whose "
        "generated layers (one a kind) grow the same kind of scenery on the terrain -- or, with --apply-to, on "
        "another terrain. EXAMPLE: a CSV table (header x,z[,size][,kind]), a parameter file, a glTF scene of "
        "placed objects, or a scene file's layer (--layer)."))
    p.add_argument("example", help="the example: .csv, .adp/.txt, .glb/.gltf or a scene .toml (with --layer)")
    p.add_argument("--terrain", help="a scene file whose height-map terrain the example stands on (default: none, "
                                     "flat ground without features)")
    p.add_argument("-o", "--output", required=True, help="the scene file to write (required, no default); the "
                                                         "density maps are written beside it")
    p.add_argument("--apply-to", help="a scene file with another height-map terrain to fill with the learned "
                                      "scenery (default: the example's own terrain)")
    p.add_argument("--mesh", help="the mesh of each learned layer: a bundled name or a file (default: with --layer, "
                                  "that layer's own objects: its mesh, axis frame, axes, parts, colour and wind, standing on "
                                  "its anchor with its lift; else tree)")
    p.add_argument("--window", type=_window, help="the ground the example covers, x0,z0,x1,z1 (default: the "
                                                  "objects' bounding box grown by half a mean spacing)")
    p.add_argument("--layer", help="the layer of a scene-file example (required there; default: none)")
    p.add_argument("--mask", help="a grey image of the water over the example's terrain, white = water (default: "
                                  "none, no 'water' feature)")
    p.add_argument("--apply-mask", help="the water of --apply-to's terrain (default: none)")
    p.add_argument("--features", type=lambda t: tuple(f.strip() for f in t.split(",") if f.strip()),
                   help=f"the ground's features the intensity may depend on, comma-separated (default: all of "
                        f"{', '.join(FEATURES[:-1])}, and water with --mask)")
    p.add_argument("--size", type=float, help="the scale of an object of the example's median size (default: the "
                                              "records' own median scale where the example is made of them, else 1)")
    p.add_argument("--seed", type=int, default=0, help="the seed of the simulations and the layers (default: %(default)s)")
    p.add_argument("--errors", choices=ERRORS, default="clumps",
                   help="which errors decide the ground's terms of an example in clumps: the clumps' own variation "
                        "(what transfers to another terrain), or poisson: Poisson's errors and Akaike's criterion, every "
                        "dependence the example shows, its own ground reproduced more closely (default: %(default)s)")
    p.add_argument("--fit", action="store_true",
                   help="EXAMPLE is a .glb of one node an object, each its own bent copy of --mesh (the baked export, an "
                        "editor's bent duplicates): fit each one's record to it, and learn its bend, scale, twist and "
                        "taper too (default: the objects' places, sizes and turns only)")
    add_overwrite(p)
    p.set_defaults(handler=run)


def run(args) -> None:
    """``axialdeform learn EXAMPLE --terrain SCENE.toml -o OUT.toml``."""
    example = args.example
    if args.fit:  # each object fitted to the mesh; the default window cut to the terrain, as learn_layer does
        bounds = read_terrain(args.terrain, args.mask)[2].bounds if args.terrain else None
        example = read_example(args.example, args.window, layer=args.layer, fit=load_mesh(args.mesh or "tree", textures=False),
                               bounds=bounds)
    learned = learn_layer(example, args.terrain, window=args.window, layer=args.layer, mask=args.mask,
                          features=args.features, seed=args.seed, errors=args.errors)
    target, mask = (args.apply_to, args.apply_mask) if args.apply_to else (args.terrain, args.mask)
    inputs = [args.example, args.terrain, args.apply_to, args.mask, args.apply_mask]
    for scene in (args.terrain, args.apply_to):  # and the height maps they name (parsed, not read)
        terrain = parse_scene(scene).terrain if scene else None
        if terrain is not None:
            inputs.append(terrain.file)
    for path in learned_paths(args.output, learned):
        check_output_path(path, [p for p in inputs if p], "learned scene", overwrite=args.overwrite)
    mesh = args.mesh or (layer_mesh(args.example, args.layer) if args.layer else "tree")  # more of the layer's own objects
    written = write_learned(args.output, learned, target, mesh=mesh, mask=mask, seed=args.seed,
                            size=args.size)
    for lay in learned:
        print(f"{lay.kind or 'layer'}: {lay.describe()}")
    print(f"wrote {Path(written[-1])} and {len(written) - 1} density map(s)")

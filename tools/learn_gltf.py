#!/usr/bin/env python3
"""Learn a layer from a glTF scene of placed objects on its own ground, and compare what it grows with the scene.

The example is what an editor or an app exports: a glTF of placed objects (``EXT_mesh_gpu_instancing``, one node
an object, or ``AXIALDEFORM_bend``), read by the library's own reader (``read_example``), and the ground they stand
on as a glTF mesh.  The ground is sampled into a height map (linear over its triangulated vertices, on a square
grid over its box) and written as a scene file's terrain, the example is moved into that terrain's frame (the
terrain centred on the origin), and the layer is learned and compared as ``tools/learn_survey.py`` compares a
surveyed plot (``compare``: the total, each quartile of each ground feature, the L-function against the
envelope of the generated patterns, Diggle's global test, the sizes' KS), on the whole scene and on a random half
learned and the other half compared.  A ground compressed with ``KHR_draco_mesh_compression`` needs ``DracoPy``
(``pip install DracoPy``: not a dependency of the library).

    python3 tools/learn_gltf.py TREES.glb --ground GROUND.glb [--grid 256] [--sims 39]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator

sys.path.insert(0, str(Path(__file__).resolve().parent))
from learn_survey import calibrate, compare, halves, held_out, print_table  # noqa: E402

from axialdeform.core.io.example import read_example  # noqa: E402
from axialdeform.core.io.glb import read_accessor  # noqa: E402


def ground_points(path: Path) -> np.ndarray:
    """(k, 3) float64: every vertex of the glTF ``path``'s meshes in the scene's frame (the ground).  trimesh
    places them; a mesh compressed with ``KHR_draco_mesh_compression`` (which trimesh does not read) is decoded
    by DracoPy and placed by its node's translation and scale (a rotated or nested one is refused)."""
    import pygltflib

    gltf = pygltflib.GLTF2().load(str(path))
    if "KHR_draco_mesh_compression" not in (gltf.extensionsUsed or []):
        import trimesh

        return np.asarray(trimesh.load(str(path), force="mesh").vertices, np.float64)
    try:
        import DracoPy
    except ImportError:
        sys.exit(f"learn_gltf: {path}: its meshes are Draco-compressed; pip install DracoPy to read them")
    blob, out = gltf.binary_blob(), []
    children = {c for n in gltf.nodes for c in (n.children or [])}
    for k, node in enumerate(gltf.nodes):
        if node.mesh is None:
            continue
        if k in children or node.rotation not in (None, [0, 0, 0, 1]) or node.matrix is not None:
            sys.exit(f"learn_gltf: {path}: node {node.name!r} is rotated or nested; expected a Draco ground placed by "
                     "translation and scale")
        for prim in gltf.meshes[node.mesh].primitives:
            draco = (prim.extensions or {}).get("KHR_draco_mesh_compression")
            if draco:
                view = gltf.bufferViews[draco["bufferView"]]
                start = view.byteOffset or 0
                p = np.asarray(DracoPy.decode(blob[start:start + view.byteLength]).points, np.float64)
            else:
                p = read_accessor(gltf, blob, prim.attributes.POSITION, "POSITION", str(path)).astype(np.float64)
            out.append(p * np.asarray(node.scale or [1, 1, 1]) + np.asarray(node.translation or [0, 0, 0]))
    if not out:
        sys.exit(f"learn_gltf: {path}: no mesh to stand on")
    return np.concatenate(out)


def terrain(points: np.ndarray, folder: Path, grid: int) -> tuple[Path, np.ndarray]:
    """A scene file whose height-map terrain samples ``points`` on a ``grid`` x ``grid`` square grid over their box
    (the first row at the low z), centred on the origin, and the shift (x, z) that moves the points' frame into it."""
    lo, hi = points[:, [0, 2]].min(0), points[:, [0, 2]].max(0)
    x, z = np.linspace(lo[0], hi[0], grid), np.linspace(lo[1], hi[1], grid)
    gx, gz = np.meshgrid(x, z)
    h = LinearNDInterpolator(points[:, [0, 2]], points[:, 1])(gx, gz)
    holes = np.isnan(h)
    h[holes] = NearestNDInterpolator(points[:, [0, 2]], points[:, 1])(gx[holes], gz[holes])
    bottom, top = float(h.min()), float(h.max())
    Image.fromarray(np.round((h - bottom) / (top - bottom) * 65535).astype(np.uint16)).save(folder / "ground.png")
    (folder / "ground.toml").write_text(f'[terrain]\nheightmap = "ground.png"\nheight_scale = {top - bottom}\n'
                                        f"extent = [{hi[0] - lo[0]}, {hi[1] - lo[1]}]\n")
    return folder / "ground.toml", -(lo + hi) / 2


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("example", help="a glTF scene of placed objects (.glb/.gltf)")
    p.add_argument("--ground", required=True, help="a glTF of the ground they stand on (required, no default)")
    p.add_argument("--grid", type=int, default=256, help="height-map pixels a side (default: %(default)s)")
    p.add_argument("--sims", type=int, default=39, help="generated patterns a comparison (default: %(default)s)")
    p.add_argument("--out", help="a folder for the files (default: a temporary folder)")
    p.add_argument("--errors", choices=("clumps", "poisson"), default="clumps", help="learn's --errors (default: %(default)s)")
    p.add_argument("--calibrate", type=int, default=0, metavar="N",
                   help="also grow N examples from what was learned and compare them the same way: what a true model "
                        "scores (default: %(default)s, none)")
    p.add_argument("--halves", type=int, default=0, metavar="N",
                   help="also hold out N random halves (seeds 1..N), each learned and the other compared, both ways "
                        "(default: %(default)s, none)")
    args = p.parse_args(argv)
    folder = Path(args.out or tempfile.mkdtemp())
    folder.mkdir(parents=True, exist_ok=True)
    points = ground_points(Path(args.ground))
    scene, shift = terrain(points, folder, args.grid)
    ex = read_example(args.example)
    half_w, half_d = (points[:, [0, 2]].max(0) - points[:, [0, 2]].min(0)) / 2
    w = ex.window  # the objects' box grown by half a spacing, within the ground
    window = (max(w[0] + shift[0], -half_w), max(w[1] + shift[1], -half_d), min(w[2] + shift[0], half_w), min(w[3] + shift[1], half_d))
    ex = dataclasses.replace(ex, xz=ex.xz + shift, window=window)
    name = Path(args.example).name
    rows = [compare(name, ex, scene, folder, args.sims, errors=args.errors)]
    half = halves(len(ex.xz))
    rows.append(compare(f"{name}: a random half learned, the other compared", ex.subset(half), scene, folder, args.sims,
                        ex.subset(~half), args.errors))
    print_table(rows)
    if args.calibrate:
        print()
        print_table(calibrate(name, ex, scene, folder, args.sims, args.calibrate, args.errors, (rows[0], rows[1])))
    if args.halves:
        print()
        print_table([held_out(name, ex, scene, folder, args.sims, args.halves, args.errors)])
    return 0


if __name__ == "__main__":
    sys.exit(main())

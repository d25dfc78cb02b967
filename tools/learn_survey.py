"""Learn scenery from public surveyed forest plots and compare what the learned layer grows with the survey
(docs/learn.md, "Measured").

The plots are spatstat.data's (GPL >= 2; the surveys' own sources are cited in docs/learn.md): ``bei`` (3 604
trees of Beilschmiedia pendula on 1000 x 500 m of Barro Colorado Island, with the plot's elevation on a 5 m
grid) and ``longleaf`` (584 longleaf pines on 200 x 200 m in Georgia, with trunk diameters).  They come from
Debian's package ``r-cran-spatstat.data`` (``apt-get download r-cran-spatstat.data``; nothing is installed)
and are read with ``rdata`` from the package index (``pip install rdata``); neither is a dependency of
axialdeform.

    python3 tools/learn_survey.py --deb r-cran-spatstat.data_*.deb [--out DIR] [--sims 39] [--errors poisson]
                                  [--calibrate N] [--halves N]

For each plot: learn on the whole plot, generate the learned layer over the same ground (``--sims`` seeds,
numpy), and compare: the total count, the count per quartile of each ground feature (and whether the example's
count lies within the generated patterns' range), the example's L-function against the envelope of the
generated patterns for r in [0.5, 5] mean spacings, the sizes' KS distance; then
two hold-outs: learn on the west half and compare on the east half, and learn on a random half of the trees and
compare on the other half (with the learned half's own counts against the other's: what a model that reproduced
the learned half exactly would score on the quartiles).  ``--calibrate N``: the same comparisons of N patterns of
which the learned layer is the true model; ``--halves N``: N random halves, each learned and the other compared.
"""

from __future__ import annotations

import argparse
import bz2
import gzip
import lzma
import math
import subprocess
import sys
import tempfile
import warnings
import zlib
from pathlib import Path

import numpy as np
from PIL import Image
from scipy.stats import ks_2samp

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import axialdeform as ad  # noqa: E402
from axialdeform.core.io.example import read_example, read_terrain, write_learned  # noqa: E402
from axialdeform.core.learn import ERRORS, Example, expected_count, l_function, largest_deviations, learn_layers, own_rate  # noqa: E402
from axialdeform.core.record import POSITION, SCALE  # noqa: E402


def _plots(deb: Path, folder: Path) -> dict:
    import rdata

    subprocess.run(["dpkg-deb", "-x", str(deb), str(folder / "deb")], check=True)
    base = next((folder / "deb").rglob("spatstat.data/data/Rdata.rdx")).with_suffix("")
    index = rdata.conversion.convert(rdata.parser.parse_data(gzip.decompress(base.with_suffix(".rdx").read_bytes())))
    blob = base.with_suffix(".rdb").read_bytes()

    def obj(name):
        off, n = (int(v) for v in index["variables"][name])
        raw = blob[off:off + n]
        kind = {b"Z": zlib.decompress, b"X": lzma.decompress, b"2": bz2.decompress}.get(raw[4:5])
        body = kind(raw[5:]) if kind else zlib.decompress(raw[4:])  # R's lazy-load: a length, [a type], the data
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return rdata.conversion.convert(rdata.parser.parse_data(body))

    return {"bei": obj("bei"), "elev": obj("bei.extra")["elev"], "longleaf": obj("longleaf")}


def _survey(path: Path, x, z, size=None) -> Path:
    cols = "x,z" + (",size" if size is not None else "")
    rows = [cols] + [f"{a:.3f},{b:.3f}" + (f",{s:.3f}" if size is not None else "") for a, b, s in
                     zip(x, z, size if size is not None else [None] * len(x))]
    path.write_text("\n".join(rows) + "\n")
    return path


def _terrain(folder: Path, elev: dict) -> Path:
    v = np.asarray(elev["v"], np.float64)  # rows: y (north), cols: x
    lo, hi = v.min(), v.max()
    Image.fromarray(np.round((v - lo) / (hi - lo) * 65535).astype(np.uint16)).save(folder / "bei_elev.png")
    w = float(elev["xcol"][-1] - elev["xcol"][0])
    d = float(elev["yrow"][-1] - elev["yrow"][0])
    (folder / "bei.toml").write_text(f'[terrain]\nheightmap = "bei_elev.png"\nheight_scale = {hi - lo}\n'
                                     f'extent = [{w}, {d}]\n')
    return folder / "bei.toml"


def _generated(out: Path, learned, terrain, seed: int, size: float) -> tuple[np.ndarray, np.ndarray | None]:
    write_learned(out, learned, terrain, mesh="stone", seed=seed, size=size)
    params = ad.Scene.load(out).layers[0].params
    return params[:, POSITION][:, [0, 2]].astype(np.float64), (params[:, SCALE] if params.shape[1] > SCALE else None)


def compare(name: str, ex: Example, terrain, folder: Path, sims: int, test: Example | None = None,
            errors: str = "clumps") -> dict:
    """Learn on ``ex`` (``errors``: learn_layers'), generate ``sims`` times over its terrain, compare with ``test``
    (default ``ex``)."""
    test = test or ex
    ground = read_terrain(terrain)[2] if terrain else None
    learned = learn_layers(ex, ground, errors=errors)
    lay = learned[0]
    w = test.window
    inside = lambda p: p[(p[:, 0] >= w[0]) & (p[:, 0] <= w[2]) & (p[:, 1] >= w[1]) & (p[:, 1] <= w[3])]  # noqa: E731
    made, scales = [], None
    for s in range(sims):
        xz, sc = _generated(folder / f"{name}-{s}.toml", learned, terrain, s, 1.0)
        made.append(inside(xz))
        scales = sc if scales is None else scales
    counts = np.array([len(m) for m in made])
    row = {"plot": name, "objects": len(test.xz), "generated (median)": float(np.median(counts)),
           "total ratio": float(np.median(counts) / len(test.xz)), "terms": " ".join(lay.intensity.labels) or "none",
           "pattern": lay.spacing.pattern}
    worst, where, inside, quartiles, floor = 0.0, "", 0, 0, 0.0
    held = test is not ex and tuple(test.window) == tuple(ex.window)  # a random half: the same ground
    if ground is not None:
        for f in ground.names:
            edges = np.quantile(ground.at(_grid(w), [f])[:, 0], [0, 0.25, 0.5, 0.75, 1])
            a = np.histogram(ground.at(test.xz, [f])[:, 0], edges)[0]
            if held:  # the learned half's own counts (to the compared half's total): what reproducing it exactly gives
                own = np.histogram(ground.at(ex.xz, [f])[:, 0], edges)[0] * len(test.xz) / len(ex.xz)
                floor = max(floor, float(np.max(np.abs(own / np.maximum(a, 1) - 1))))
            grown = np.array([np.histogram(ground.at(m, [f])[:, 0], edges)[0] for m in made])
            b = np.median(grown, axis=0)
            inside += int(np.sum((a >= grown.min(0)) & (a <= grown.max(0))))  # within the generated patterns' range
            quartiles += 4
            off = np.abs(b / np.maximum(a, 1) - 1)
            if off.max() > worst:
                k = int(np.argmax(off))
                worst, where = float(off.max()), f"{f} Q{k + 1}: {b[k]:g} grown, {a[k]} there"
        row["worst quartile"] = f"{worst:.3f} ({where})"
        row["_worst"] = worst  # the figures themselves, for calibrate (not printed: print_table skips "_" keys)
        row["quartiles inside the generated range"] = f"{inside}/{quartiles}"
        if held:
            row["worst quartile of the learned half itself"] = floor
    spacing = math.sqrt((w[2] - w[0]) * (w[3] - w[1]) / len(test.xz))
    r = np.linspace(0.5, 5.0, 19) * spacing
    r = r[r <= min(w[2] - w[0], w[3] - w[1]) / 4]
    total = expected_count(lay.intensity, ground, w)
    rate = lambda p: own_rate(lay.intensity, ground, p, total)  # noqa: E731  each pattern's own level (Linhom refits)
    obs = l_function(test.xz, w, r, rate(test.xz))
    env = np.array([l_function(m, w, r, rate(m)) for m in made])
    row["_inside"] = (int(np.sum((obs >= env.min(0)) & (obs <= env.max(0)))), len(r))
    row["L inside envelope"] = "{}/{}".format(*row["_inside"])
    out = [f"{x / spacing:.2f}{'+' if o > hi else '-'}" for x, o, lo, hi in zip(r, obs, env.min(0), env.max(0)) if not lo <= o <= hi]
    row["L outside (r / spacing: + above, - below)"] = " ".join(out) or "none"
    # Diggle's global test (the largest deviation from the mean over r, as learn's own test): the survey's rank
    # among the generated patterns; and how the pointwise envelope treats the model's own patterns: each
    # generated one against the envelope of the others, how many fall outside at one distance or more
    dev = largest_deviations(np.vstack([env, obs]))
    row["L global test p"] = float((1 + np.sum(dev[:-1] >= dev[-1])) / (len(env) + 1))
    own = [np.any((env[j] < np.delete(env, j, 0).min(0)) | (env[j] > np.delete(env, j, 0).max(0))) for j in range(len(env))]
    row["generated outside the others' envelope"] = f"{int(np.sum(own))}/{len(env)}"
    if test.size is not None and scales is not None:
        row["size KS"] = float(ks_2samp(test.size / np.median(ex.size), scales).statistic)
    return row


def calibrate(name: str, ex: Example, terrain, folder: Path, sims: int, patterns: int, errors: str = "clumps",
              observed: tuple | None = None) -> list:
    """What the comparisons give when the learned layer is TRUE: learn on ``ex``, grow ``patterns`` examples from
    what was learned (seeds 1000, 1001, ..), and compare each as ``ex`` is compared -- learned whole, and a random
    half learned and the other half compared.  Two rows: each figure's median and range over the patterns, and
    how many of them pass each line of the goal (total within 10 %, every quartile within 15 %, the L-function
    inside the envelope at every distance, Diggle's global test not rejected at 5 %).  ``observed``: the
    example's own rows (:func:`compare`'s, whole and half), each placed among the patterns' (:func:`summary`)."""
    ground = read_terrain(terrain)[2] if terrain else None
    learned = learn_layers(ex, ground, errors=errors)
    w = ex.window
    rows = {"whole": [], "half": []}
    for k in range(patterns):
        xz, _ = _generated(folder / f"{name}-truth-{k}.toml", learned, terrain, 1000 + k, 1.0)
        grown = Example(xz[(xz[:, 0] >= w[0]) & (xz[:, 0] <= w[2]) & (xz[:, 1] >= w[1]) & (xz[:, 1] <= w[3])], w, source=name)
        rows["whole"].append(compare(f"{name}-truth-{k}", grown, terrain, folder, sims, errors=errors))
        half = halves(len(grown.xz))
        rows["half"].append(compare(f"{name}-truth-{k}-half", grown.subset(half), terrain, folder, sims, grown.subset(~half), errors))
    return [summary(f"{name}: {patterns} patterns grown from what was learned, {what}"
                    + (" (the other half compared)" if what == "half" else ""), got, mine)
            for (what, got), mine in zip(rows.items(), observed or (None, None))]


def held_out(name: str, ex: Example, terrain, folder: Path, sims: int, seeds: int, errors: str = "clumps") -> dict:
    """The random hold-out ``seeds`` times (:func:`halves` of seeds 1, 2, ..), each half learned and the other
    compared, both ways: ``2 seeds`` comparisons summarized as :func:`summary` (how many meet each line)."""
    got = []
    for seed in range(1, seeds + 1):
        half = halves(len(ex.xz), seed)
        for a, b in ((half, ~half), (~half, half)):
            got.append(compare(f"{name}-halves-{seed}", ex.subset(a), terrain, folder, sims, ex.subset(b), errors))
    return summary(f"{name}: {seeds} random halves, each learned and the other compared, both ways ({2 * seeds})", got)


def summary(label: str, got: list, observed: dict | None = None) -> dict:
    """Comparisons ``got`` (:func:`compare`'s rows) in one row: each figure's median and range, and how many
    meet each line of the goal (total within 10 %, every quartile within 15 %, the L-function inside the
    envelope at every distance, Diggle's global test not rejected at 5 %).  ``observed`` (a row of the example
    itself): for each figure, how many of ``got`` are as far off as the example or farther (the total from 1,
    the worst quartile, the distances outside the envelope, Diggle's p): the example's place among patterns of
    which the learned layer is the true model (0: farther off than every one of them)."""
    total = np.array([r["total ratio"] for r in got])
    worst = np.array([r.get("_worst", 0.0) for r in got])
    inside = np.array([r["_inside"][0] for r in got])
    of = got[0]["_inside"][1]
    p = np.array([r["L global test p"] for r in got])
    row = {"plot": label, "total ratio": f"{np.median(total):.3f} ({total.min():.3f}-{total.max():.3f}); "
                                         f"within 10 %: {int(np.sum(np.abs(total - 1) <= 0.1))}"}
    if "worst quartile" in got[0]:
        row["worst quartile"] = (f"{np.median(worst):.3f} ({worst.min():.3f}-{worst.max():.3f}); "
                                 f"within 15 %: {int(np.sum(worst <= 0.15))}")
    if "worst quartile of the learned half itself" in got[0]:
        own = np.array([r["worst quartile of the learned half itself"] for r in got])
        row["worst quartile of the learned half itself"] = (f"{np.median(own):.3f} ({own.min():.3f}-{own.max():.3f}); "
                                                            f"within 15 %: {int(np.sum(own <= 0.15))}")
    row["L inside envelope"] = f"{np.median(inside):g} of {of} ({inside.min()}-{inside.max()}); all: {int(np.sum(inside == of))}"
    row["L global test p"] = f"{np.median(p):.3f}; not rejected: {int(np.sum(p > 0.05))}"
    if observed is not None:
        place = [("total", np.abs(total - 1) >= abs(observed["total ratio"] - 1)),
                 ("L", inside <= observed["_inside"][0]), ("Diggle", p <= observed["L global test p"])]
        if "_worst" in observed:
            place.insert(1, ("quartiles", worst >= observed["_worst"]))
        row["the example's figures: as far off or farther"] = ", ".join(f"{k} {int(np.sum(v))}/{len(got)}" for k, v in place)
    return row


def halves(n: int, seed: int = 1) -> np.ndarray:
    """A random half of ``n`` objects, (n,) bool: exactly ``n // 2`` of them, so the two halves differ by the
    objects they hold, not by how many (a coin a tree would make one half up to a few per cent larger)."""
    keep = np.zeros(n, bool)
    keep[np.random.default_rng(seed).permutation(n)[:n // 2]] = True
    return keep


def _grid(w, n=200):
    gx, gz = np.meshgrid(np.linspace(w[0], w[2], n), np.linspace(w[1], w[3], n))
    return np.stack([gx.ravel(), gz.ravel()], 1)


def _picture(path: Path, ex: Example, terrain: Path, folder: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ground = read_terrain(terrain)[2]
    learned = learn_layers(ex, ground)
    made, _ = _generated(folder / "picture.toml", learned, terrain, 0, 1.0)
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.6), constrained_layout=True)
    for ax, pts, title in ((axes[0], ex.xz, f"bei: the survey ({len(ex.xz)} trees)"),
                           (axes[1], made, f"learned and generated ({len(made)})")):
        ax.imshow(ground.grids["altitude"], origin="lower", extent=ground.bounds[0::2] + ground.bounds[1::2], cmap="terrain")
        ax.scatter(pts[:, 0], pts[:, 1], s=1.5, c="k")
        ax.set_title(title)
        ax.set_aspect("equal")
    fig.savefig(path, dpi=90)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--deb", required=True, help="Debian's r-cran-spatstat.data .deb (required, no default)")
    p.add_argument("--out", help="a folder for the plots' files (default: a temporary folder)")
    p.add_argument("--picture", help="a PNG of the bei survey beside one generated pattern (default: none)")
    p.add_argument("--sims", type=int, default=39, help="generated patterns a comparison (default: %(default)s)")
    p.add_argument("--errors", choices=ERRORS, default="clumps", help="learn's --errors (default: %(default)s)")
    p.add_argument("--calibrate", type=int, default=0, metavar="N",
                   help="also grow N examples from what was learned on each plot and compare them the same way: what "
                        "a true model scores (default: %(default)s, none)")
    p.add_argument("--halves", type=int, default=0, metavar="N",
                   help="also hold out N random halves (seeds 1..N), each learned and the other compared, both ways "
                        "(default: %(default)s, none)")
    args = p.parse_args(argv)
    folder = Path(args.out or tempfile.mkdtemp())
    folder.mkdir(parents=True, exist_ok=True)
    data = _plots(Path(args.deb), folder)
    bei_scene = _terrain(folder, data["elev"])
    b = data["bei"]
    bei = _survey(folder / "bei.csv", np.asarray(b["x"]) - 500.0, np.asarray(b["y"]) - 250.0)
    ll = data["longleaf"]
    longleaf = _survey(folder / "longleaf.csv", ll["x"], ll["y"], ll["marks"])
    rows = []
    e_bei = read_example(bei, (-500, -250, 500, 250))
    e_ll = read_example(longleaf, (0, 0, 200, 200))
    rows.append(compare("bei", e_bei, bei_scene, folder, args.sims, errors=args.errors))
    rows.append(compare("longleaf", e_ll, None, folder, args.sims, errors=args.errors))
    west = e_bei.subset(e_bei.xz[:, 0] < 0)
    west = Example(west.xz, (-500, -250, 0, 250), source="bei west")
    east = e_bei.subset(e_bei.xz[:, 0] >= 0)
    east = Example(east.xz, (0, -250, 500, 250), source="bei east")
    rows.append(compare("bei: west learned, east compared", west, bei_scene, folder, args.sims, east, args.errors))
    # the other hold-out: a random half of the trees learned, the other half compared (each half the same
    # ground, half the trees: the learned layer grows half as many)
    for name, ex, scene in (("bei", e_bei, bei_scene), ("longleaf", e_ll, None)):
        half = halves(len(ex.xz))
        rows.append(compare(f"{name}: a random half learned, the other compared", ex.subset(half), scene, folder,
                            args.sims, ex.subset(~half), args.errors))
    if args.picture:
        _picture(Path(args.picture), e_bei, bei_scene, folder)
    print_table(rows)
    if args.calibrate:
        print()
        print_table(calibrate("bei", e_bei, bei_scene, folder, args.sims, args.calibrate, args.errors, (rows[0], rows[3]))
                    + calibrate("longleaf", e_ll, None, folder, args.sims, args.calibrate, args.errors, (rows[1], rows[4])))
    if args.halves:
        print()
        print_table([held_out("bei", e_bei, bei_scene, folder, args.sims, args.halves, args.errors),
                     held_out("longleaf", e_ll, None, folder, args.sims, args.halves, args.errors)])
    return 0


def print_table(rows: list) -> None:
    """The comparisons as a Markdown table (a column for every key of any row)."""
    keys = list(dict.fromkeys(k for r in rows for k in r if not k.startswith("_")))
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(f"{r[k]:.3g}" if isinstance(r.get(k), float) else str(r.get(k, "")) for k in keys) + " |")


if __name__ == "__main__":
    sys.exit(main())

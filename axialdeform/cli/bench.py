"""``axialdeform bench``: the thesis's evaluation (:mod:`axialdeform.bench`)."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

from tqdm import tqdm

from ..core.errors import AxialDeformError
from ..core.io.mesh import load_mesh
from ..core.io.safeio import check_new_outputs, check_output_path
from ._common import add_max_triangles, add_overwrite, check_triangles, drawn_triangles


def add_parser(sub) -> None:
    from ..bench import BENCH_MODES, DEFAULT_OUT, METHODS

    b = sub.add_parser("bench", help="reproduce the thesis's evaluation (Tables 1, 2, Figs. 5, 6, 9)", description=(
        "Time the three methods of the thesis (same / loaded / axial, and axial-quantized) at 100, 1 000, 10 000 "
        "and 100 000 instances, solid and wireframe, each in fresh processes; write a Markdown report with the "
        "thesis's numbers beside ours, plots, and the measurements as JSON. The full run takes about 16 minutes "
        "on a 2-core machine with a software rasterizer; --quick takes under a minute. Ctrl-C keeps what was "
        "measured so far."))
    b.add_argument("--mesh", default="stone", help="base mesh file, or 'stone' / 'leaf' / 'leafcard' / 'tree' (default: %(default)s)")
    b.add_argument("--counts", default=None, help="comma-separated instance counts (default: 100,1000,10000,100000)")
    b.add_argument("--modes", default=",".join(BENCH_MODES), help="comma-separated subset of solid,wireframe (default: %(default)s)")
    b.add_argument("--methods", default=",".join(METHODS), help="comma-separated subset of the methods (default: %(default)s)")
    b.add_argument("--repeats", type=int, default=3, help="first-frame processes per case (default: %(default)s)")
    b.add_argument("--frames", type=int, default=20, help="timed rounds of later frames (default: %(default)s)")
    b.add_argument("--warmup", type=int, default=3, help="rounds drawn before the timed ones (default: %(default)s)")
    b.add_argument("--size", default="800x600", help="offscreen target WIDTHxHEIGHT (default: %(default)s)")
    b.add_argument("--samples", type=int, default=0, help="MSAA samples of the target (default: %(default)s)")
    b.add_argument("--seed", type=int, default=2003, help="random seed of the scenes (default: %(default)s)")
    b.add_argument("--out", default=None, help=f"folder for bench.md, bench-details.json and the plots "
                                                f"(default: ./{DEFAULT_OUT}/; with --report-from: the JSON's folder)")
    b.add_argument("--json", dest="json_path", default=None, help="also write the records as JSON here (default: none)")
    b.add_argument("--cache", default=None, help="folder for parameter and OBJ files (default: ~/.cache/axialdeform/bench)")
    b.add_argument("--quick", action="store_true",
                   help="100 and 1 000 instances, one repeat, 5 frames, 400x300: under a minute (default: the full run)")
    b.add_argument("--no-leaf", action="store_true", help="leave out the 1 000-leaf scene (default: include it)")
    b.add_argument("--no-throughput", action="store_true", help="leave out the deformation throughput (default: include it)")
    b.add_argument("--no-progress", action="store_true", help="no progress bar (default: a bar on stderr)")
    add_max_triangles(b)
    b.add_argument("--report-from", metavar="DETAILS_JSON", default=None,
                   help="measure nothing: render bench.md and the plots again from a saved bench-details.json, "
                        "into --out if given, else beside the JSON (default: measure)")
    add_overwrite(b, " (bench.md, bench-details.json, the plots and --json)")
    b.set_defaults(handler=run)


def _csv(text: str, name: str) -> tuple[str, ...]:
    items = tuple(x.strip() for x in text.split(",") if x.strip())
    if not items:
        raise AxialDeformError(f"{name}: expected a comma-separated list, found {text!r}")
    return items


#: what a run writes into --out: the one rule for existing outputs holds for each of them
REPORT_FILES = ("bench.md", "bench-details.json", "fig5-first-frame.png", "fig6-frame-time.png")


def _refuse_existing(args, out: Path, names=REPORT_FILES) -> None:
    """An earlier run's report in ``out`` is replaced only with --overwrite (and never its own details)."""
    check_new_outputs([out / name for name in names], "a report's files", args.overwrite)


def _report_from(args) -> None:
    from ..bench.report import load_details, write_report

    details = load_details(args.report_from)
    out = Path(args.report_from).parent if args.out is None else Path(args.out)
    _refuse_existing(args, out, [n for n in REPORT_FILES if n != "bench-details.json"])
    path = write_report(details, out)
    print(f"wrote {path} (from the measurements in {args.report_from})")


def _check_triangles(args, counts) -> None:
    """The largest count of the bench's mesh in each mode within ``--max-triangles``, before anything runs."""
    from ..bench import COUNTS, QUICK_COUNTS

    if args.quick and tuple(counts) == COUNTS:
        counts = QUICK_COUNTS
    if not counts:
        return
    triangles = drawn_triangles(load_mesh(args.mesh))
    for mode in _csv(args.modes, "--modes"):
        check_triangles([(f"{args.mesh} x --counts {max(counts)}", max(counts), triangles)], mode, args.max_triangles)


def run(args) -> None:
    """Handler of ``axialdeform bench``."""
    from ..bench import COUNTS, DEFAULT_OUT, run_bench
    from ..gl.image import parse_size

    if args.report_from:
        return _report_from(args)
    counts = COUNTS
    if args.counts:
        try:
            counts = tuple(int(x) for x in _csv(args.counts, "--counts"))
        except ValueError:
            raise AxialDeformError(f"--counts: expected comma-separated integers, found {args.counts!r}") from None
    _check_triangles(args, counts)
    command = shlex.join(["axialdeform", *sys.argv[1:]]) if sys.argv and "bench" in sys.argv[1:] else None
    out = Path(DEFAULT_OUT if args.out is None else args.out)
    _refuse_existing(args, out)
    if args.json_path:
        check_output_path(args.json_path, (), "measurements JSON", overwrite=args.overwrite)
    how_long = "under a minute" if args.quick else "about 16 minutes on a 2-core machine; --quick for under a minute"
    print(f"axialdeform bench: writing the report into {out.resolve()}/ ({how_long}; Ctrl-C keeps what was measured)",
          file=sys.stderr, flush=True)
    bar = None
    if not args.no_progress:

        bar = tqdm(total=1, desc="bench", unit="step", file=sys.stderr)

    def progress(done: int, total: int, label: str) -> None:
        bar.total = total
        bar.n = done
        bar.set_postfix_str(label, refresh=False)
        bar.refresh()

    try:
        records = run_bench(
            mesh=args.mesh, counts=counts, modes=_csv(args.modes, "--modes"), methods=_csv(args.methods, "--methods"),
            repeats=args.repeats, frames=args.frames, warmup=args.warmup, size=parse_size(args.size),
            samples=args.samples, seed=args.seed, out=out, json_path=args.json_path, cache=args.cache,
            leaf=not args.no_leaf, throughput=not args.no_throughput, quick=args.quick,
            progress=None if bar is None else progress, command=command,
        )
    except KeyboardInterrupt:
        if bar is not None:
            bar.close()
        if (out / "bench.md").exists() and (out / "bench-details.json").exists():
            print(f"axialdeform bench: stopped; kept what was measured in {out / 'bench.md'} and "
                  f"{out / 'bench-details.json'}", file=sys.stderr)
        raise
    if bar is not None:
        bar.close()
    for r in records:
        print(f"{r['method']:>16} {r['count']:>7} {r['mode']:<9} {r['file_bytes'] / 1024:>12,.1f} KB "
              f"first {r['first_frame_s']:8.3f} s  frame {r['frame_s'] * 1000:9.2f} ms  {r['shapes_per_s']:>12,.0f} shapes/s")
    print(f"wrote {out / 'bench.md'} and {out / 'bench-details.json'}")
    if args.json_path:
        print(f"wrote {args.json_path}")

"""The field scene: frame time with culling off / on / on + LOD
and each picture's difference to the full render, alternated in one process.

    .venv/bin/python tools/field_bench.py                 # 1 000 000 stones, 800x600
    .venv/bin/python tools/field_bench.py -n 100000 --frames 5 --json field.json

Prints a Markdown table and whether each goal of the issue was met (the
goals are reported, never asserted).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from axialdeform.bench.field import format_field, run_field  # noqa: E402
from axialdeform.gl.image import parse_size  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-n", "--count", type=int, default=1_000_000)
    p.add_argument("--size", default="800x600")
    p.add_argument("--frames", type=int, default=3, help="alternated timed frames per method (default: %(default)s)")
    p.add_argument("--samples", type=int, default=0)
    p.add_argument("--lod-error", type=float, default=1.0, metavar="PX")
    p.add_argument("--mesh", default="stone")
    p.add_argument("--views", default="across,out", help="walker views, comma-separated (default: %(default)s)")
    p.add_argument("--no-all-visible", action="store_true", help="skip the all-in-view scene (the slowest part)")
    p.add_argument("--all-visible-frames", type=int, default=None, metavar="N",
                   help="timed frames of the all-in-view scene (default: --frames)")
    p.add_argument("--json", default=None, help="write the figures here as JSON")
    args = p.parse_args(argv)
    res = run_field(args.count, parse_size(args.size), args.frames, lod_error=args.lod_error, samples=args.samples,
                    mesh=args.mesh, views=tuple(args.views.split(",")), all_visible=not args.no_all_visible,
                    all_visible_frames=args.all_visible_frames, progress=lambda text: print(f"  {text}", file=sys.stderr, flush=True))
    print(format_field(res))
    if args.json:
        from axialdeform.core.io.atomic import atomic_path

        with atomic_path(args.json, suffix=".json") as tmp:
            Path(tmp).write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

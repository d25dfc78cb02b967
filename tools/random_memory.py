"""Memory of ``axialdeform random``: bytes per instance of one piece, and the
peak of the whole command against the count.

    python3 tools/random_memory.py [--piece 131072] [--counts 300000 1200000 4800000]

1. tracemalloc peak of making ONE piece of ``--piece`` instances and
   encoding it, per instance, for 16 and 19 numbers and each output form
   (text, float32 .adp, quantized .adp): what ``RANDOM_BYTES_EACH`` in
   ``axialdeform/cli/random.py`` must cover (the largest is the 19-number
   text form).
2. The peak resident memory (``ru_maxrss`` of the child, ``os.wait4``) of
   ``axialdeform random stone -n N`` for each ``--counts`` N, .adp and
   quantized .adp with 19 numbers: flat in N when the command streams.

One JSON line per measurement.  Feeds docs/reliability.md.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path


def piece_bytes(piece: int, width: int, suffix: str, quantize: bool, folder: Path) -> float:
    import axialdeform as ad
    from axialdeform.core.io.params import write_param_chunks
    from axialdeform.core.variation import iter_random_params

    mesh = ad.load_mesh("stone")
    extra = {"scale": (0.5, 2.0), "twist": 1.0, "taper": 0.3} if width == 19 else {}
    out = folder / f"p{suffix}"
    tracemalloc.start()
    write_param_chunks(out, lambda: iter_random_params(mesh, piece, 1, chunk=piece, **extra), piece, width, mesh,
                       quantize=quantize)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak / piece


def command_peak(count: int, args: list[str], folder: Path) -> tuple[float, float]:
    """(peak MB, seconds) of ``axialdeform random stone -n count`` in a child process."""
    cmd = [sys.executable, "-m", "axialdeform", "random", "stone", "-n", str(count), *args]
    t = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, cwd=folder)
    _, status, usage = os.wait4(proc.pid, 0)
    if status:
        raise SystemExit(f"{' '.join(cmd)}: exit status {status}")
    return usage.ru_maxrss / 1024, time.perf_counter() - t


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--piece", type=int, default=131072, help="instances in one piece (default: %(default)s)")
    ap.add_argument("--counts", type=int, nargs="*", default=[300_000, 1_200_000, 4_800_000])
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for width in (16, 19):
            for suffix, quantize in ((".txt", False), (".adp", False), (".adp", True)):
                each = piece_bytes(args.piece, width, suffix, quantize, folder)
                print(json.dumps({"piece": args.piece, "width": width, "form": "quantized" if quantize else suffix,
                                  "bytes_per_instance": round(each, 1)}), flush=True)
        ext = ["--scale", "0.5:2", "--twist", "1", "--taper", "0.3"]
        for n in args.counts:
            for form, extra in ((".adp", []), ("quantized", ["--quantize"])):
                peak, secs = command_peak(n, ["-o", "p.adp", *ext, *extra], folder)
                print(json.dumps({"command": f"random stone -n {n} (19 numbers, {form})", "peak_rss_mb": round(peak),
                                  "seconds": round(secs, 1)}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The peak resident memory of one CLI run, measured in a child process of its own."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


# a small Python process runs the CLI and reports its child's peak: the CLI is then
# forked from that small process, not from pytest (a vfork child's peak RSS counts
# its parent's pages until exec, so measured straight from pytest it would include
# everything this test process holds)
_MEASURE = ("import os, subprocess, sys\n"
            "p = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL)\n"
            "_, status, usage = os.wait4(p.pid, 0)\n"
            "print(usage.ru_maxrss)\n"
            "sys.exit(os.waitstatus_to_exitcode(status))\n")


def peak_rss_mb(args) -> float:
    """Peak resident memory (MB) of the CLI in a child process (that process
    alone: ``os.wait4`` in a small parent of its own, see ``_MEASURE``).
    glibc's mmap threshold is fixed at 1 MB, so freed pieces go back to the
    system at once and the peak is what is in use, not heap fragmentation."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MALLOC_MMAP_THRESHOLD_": str(1 << 20)}
    done = subprocess.run([sys.executable, "-c", _MEASURE, sys.executable, "-m", "axialdeform", *map(str, args)],
                          capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    return int(done.stdout.split()[-1]) / 1024

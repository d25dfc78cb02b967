"""Frame times of several renderers drawn in turn (A B A B ...), so that load
from elsewhere on the machine hits all alike: the timing loop the speed tools
share (``cull_speed.py``, ``texture_speed.py``)."""

from __future__ import annotations

import time


def alternate(ctx, target, renderers: dict, view, proj, rounds: int, warmup: int = 2, mode: str = "solid"):
    """``{name: [seconds, ...]}`` of ``rounds`` frames of each renderer (after
    ``warmup`` untimed rounds), each ``clear + render + ctx.finish()`` into
    ``target``; and ``{name: picture}`` of each one's last frame."""
    times = {name: [] for name in renderers}
    pictures = {}
    for k in range(rounds + warmup):
        for name, r in renderers.items():
            t = time.perf_counter()
            target.use()
            r.render(view, proj, mode)
            ctx.finish()
            if k >= warmup:
                times[name].append(time.perf_counter() - t)
            pictures[name] = target.read() if k == rounds + warmup - 1 else None
    return times, pictures

"""What the GPU wind costs: the same blades drawn still, swaying in ``ad.Wind``
(control points moved in the vertex shader from uniforms) and swaying the old
way (new offsets computed on the CPU and uploaded with ``update_params`` every
frame), frames alternating in one process so load from elsewhere hits all alike.

    python3 tools/wind_speed.py [--count 100000] [--size 800x600] [--rounds 15] [--plain]

Prints the median frame time of each, the median of the per-round ratios
wind / still with its quartiles (the goal: at most 1.10), and the bytes
written to GL buffers per frame (counted by wrapping ``moderngl.Buffer.write``
and ``orphan``).  It is a measurement, not a test: nothing is asserted about time.
"""

from __future__ import annotations

import argparse
import statistics
import time

import moderngl
import numpy as np

import axialdeform as ad
from axialdeform.core.camera import frame_instances
from axialdeform.core.wind import apply_wind
from axialdeform.gl.image import parse_size


class _Counter:
    """Counts bytes written to any moderngl buffer while installed."""

    def __init__(self):
        self.bytes = 0
        self._write, self._orphan = moderngl.Buffer.write, moderngl.Buffer.orphan

    def __enter__(self):
        counter = self

        def write(buf, data, *args, **kwargs):
            counter.bytes += memoryview(data).nbytes
            return counter._write(buf, data, *args, **kwargs)

        def orphan(buf, size=-1, *args, **kwargs):
            counter.bytes += buf.size if size < 0 else size
            return counter._orphan(buf, size, *args, **kwargs)

        moderngl.Buffer.write, moderngl.Buffer.orphan = write, orphan
        return self

    def __exit__(self, *exc):
        moderngl.Buffer.write, moderngl.Buffer.orphan = self._write, self._orphan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=100_000)
    ap.add_argument("--size", default="800x600")
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--plain", action="store_true", help="16-number blades (default: 19, extended)")
    ap.add_argument("--no-cpu", action="store_true", help="skip the CPU-upload comparison")
    args = ap.parse_args()
    size = parse_size(args.size)
    ctx = ad.create_context()
    mesh = ad.load_mesh("leaf")
    extra = {} if args.plain else dict(scale=(0.7, 1.3), twist=0.6, taper=0.5)
    params = ad.random_params(mesh, args.count, seed=5, variation=ad.Variation(bend=0.05, tilt=(-0.15, 0.15)), placement="disc",
                              spacing=0.6, **extra)
    wind = ad.Wind(direction=(1.0, 0.0, 0.3), strength=0.22, gustiness=0.7, frequency=0.35, wavelength=6.0)
    cam = frame_instances(mesh, params, size[0] / size[1], elevation=25.0)
    view, proj = cam.view(), cam.projection(size[0] / size[1])
    kinds = ["still", "wind"] + ([] if args.no_cpu else ["cpu upload"])
    times = {k: [] for k in kinds}
    written = {k: [] for k in kinds}
    with ad.Offscreen(ctx, size, samples=0) as target, ad.AxialRenderer(ctx, mesh, params) as r:
        for k in range(args.rounds + 2):  # two warm-up rounds
            now = 0.1 * k
            for kind in kinds:
                with _Counter() as count:
                    t = time.perf_counter()
                    target.use()
                    if kind == "still":
                        r.wind = None
                        r.render(view, proj, "solid")
                    elif kind == "wind":
                        r.wind = wind
                        r.render(view, proj, "solid", time=now)
                    else:  # the CPU path: the same wind computed in numpy, uploaded every frame
                        r.update_params(apply_wind(wind, mesh.axis, params, now))
                        r.wind = None
                        r.render(view, proj, "solid")
                    ctx.finish()
                    dt = time.perf_counter() - t
                if k >= 2:
                    times[kind].append(dt)
                    written[kind].append(count.bytes)
            if not args.no_cpu:
                r.update_params(params)  # back to rest for the next round's still frame (not timed)
    ratios = np.array(times["wind"]) / np.array(times["still"])
    print(f"{args.count} leaf blades ({params.shape[1]} numbers each), {size[0]}x{size[1]}, {args.rounds} rounds, "
          f"{ctx.info['GL_RENDERER']}")
    for kind in kinds:
        print(f"{kind:>10}: median {statistics.median(times[kind]) * 1e3:8.1f} ms a frame, "
              f"{max(written[kind]):>10,} bytes written to buffers a frame (max over frames)")
    print(f"wind / still: median of per-round ratios {np.median(ratios):.3f} "
          f"[quartiles {np.quantile(ratios, 0.25):.3f} .. {np.quantile(ratios, 0.75):.3f}]")
    if not args.no_cpu:
        cpu = np.array(times["cpu upload"]) / np.array(times["still"])
        print(f"cpu upload / still: median {np.median(cpu):.3f}")
    ctx.release()


if __name__ == "__main__":
    main()

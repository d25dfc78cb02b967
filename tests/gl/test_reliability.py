"""Long runs and big counts: nothing is lost, nothing leaks, a
million instances are ONE draw call.

* a writer killed with SIGKILL mid-write leaves the previous file intact and
  at most its own ``.part`` file (swept by the next writer);
* 1000 renderers created, drawn and released, and 10 000 parameter updates,
  leave no live GL object behind and the process memory bounded;
* 1 000 000 instances render in one instanced draw call on llvmpipe, at 64
  bytes an instance (float32) or 32 (``quantized=True``), and the quantized
  GPU path matches the CPU deformation of the dequantized numbers.

Figures for docs/reliability.md come from ``tools/scale.py`` and
``tools/fuzz_params.py``; nothing here asserts a time.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import moderngl
import numpy as np
import pyrr
import pytest

import axialdeform as ad
from axialdeform.core.deform import deform
from axialdeform.core.io.atomic import sweep_stale_parts
from axialdeform.core.quantize import dequantize_params, quantize_params

from conftest import make_mesh

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TETRA_V = np.array([(0, 0, 0), (1, 0, 0), (0.3, 0.8, 0), (0.3, 0.3, 0.7)], dtype=np.float64) * (2, 1, 1)
TETRA_F = np.array([(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)])


def rss_bytes() -> int:
    """Resident set size of this process (Linux ``/proc/self/statm``)."""
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


class CountingContext:
    """Forwards to a moderngl context and remembers every GL object created
    through it, so a test can count the ones still alive (not released)."""

    CREATORS = {"buffer", "program", "vertex_array", "simple_vertex_array", "renderbuffer", "depth_renderbuffer",
                "framebuffer", "texture", "depth_texture", "query", "sampler"}

    def __init__(self, ctx):
        object.__setattr__(self, "_ctx", ctx)
        object.__setattr__(self, "created", [])

    def __getattr__(self, name):
        attr = getattr(self._ctx, name)
        if name not in self.CREATORS:
            return attr

        def create(*args, **kwargs):
            obj = attr(*args, **kwargs)
            self.created.append(obj)
            return obj

        return create

    def __setattr__(self, name, value):
        setattr(self._ctx, name, value)

    def live(self) -> int:
        alive = [o for o in self.created if not isinstance(o.mglo, moderngl.InvalidObject)]
        self.created[:] = alive  # forget released ones: the list stays small
        return len(alive)


# ------------------------------------------------------------------ nothing lost

WRITER = r"""
import sys, numpy as np
from axialdeform.core.io.params import write_params
path, n = sys.argv[1], int(sys.argv[2])
base = np.arange(n * 16, dtype=np.float32).reshape(n, 16) % 1000
k = int(sys.argv[3])
while True:
    write_params(path, base + k)          # atomic: temp file, fsync, rename
    print(k, flush=True)
    k += 1
"""


@pytest.mark.slow
def test_killed_writer_leaves_previous_file_intact(tmp_path):
    """SIGKILL a process that rewrites a 6.4 MB parameter file in a loop, at
    random moments, 8 times: the file always reads back as one complete
    earlier write (same values), and killed writers' .part files do not pile up."""
    n = 100_000
    path = tmp_path / "big.adp"
    base = np.arange(n * 16, dtype=np.float32).reshape(n, 16) % 1000
    rng = np.random.default_rng(5)
    k = 0
    completed_total = 0
    for _ in range(8):
        proc = subprocess.Popen([sys.executable, "-c", WRITER, str(path), str(n), str(k)], stdout=subprocess.PIPE,
                                text=True, cwd=ROOT)
        try:
            first = proc.stdout.readline()  # one complete write, so a file exists
            assert first.strip() == str(k), f"writer failed to start: {first!r}"
            time.sleep(float(rng.uniform(0.0, 0.4)))  # then kill it at a random moment
        finally:
            proc.send_signal(signal.SIGKILL)
            proc.wait(timeout=30)
        done = [int(x) for x in [first, *proc.stdout.read().split()] if str(x).strip()]
        proc.stdout.close()
        completed_total += len(done)
        values = ad.read_params(path)  # intact: the checksum and the count verify it
        written = int(values[0, 0] - base[0, 0])
        assert written >= done[-1], "the file is older than the last completed write"
        assert written <= done[-1] + 1, "the file is newer than any write started"
        assert np.array_equal(values, base + written)
        parts = sorted(p.name for p in tmp_path.iterdir() if p.name.endswith(".part"))
        # at most the one of the writer just killed: the next writer sweeps it
        assert len(parts) <= 1, parts
        assert all(p.startswith(".big.adp.axtmp") for p in parts), parts
        k = written + 1
    assert completed_total >= 8
    sweep_stale_parts(tmp_path)
    assert [p.name for p in tmp_path.iterdir()] == ["big.adp"]


def test_failed_write_keeps_old_file(tmp_path):
    from axialdeform.core.io.atomic import atomic_path

    path = ad.write_params(tmp_path / "p.txt", np.ones((2, 16)))
    with pytest.raises(RuntimeError):
        with atomic_path(path) as tmp:
            tmp.write_text("half")
            raise RuntimeError("disk full")
    assert np.array_equal(ad.read_params(path), np.ones((2, 16), np.float32))
    assert [p.name for p in tmp_path.iterdir()] == ["p.txt"]


# ------------------------------------------------------------------- no leaks


@pytest.mark.slow
def test_1000_renderers_leave_nothing_behind(ctx):
    """Create, draw (8x8 offscreen) and release 1000 renderers: no live GL
    object remains, and the process memory grows by less than 48 MB."""
    counting = CountingContext(ctx)
    mesh = make_mesh(TETRA_V, TETRA_F, "tetra")
    params = ad.random_params(mesh, 16, seed=3)
    view = pyrr.matrix44.create_look_at((4, 3, 5), (0, 0, 0), (0, 1, 0))
    proj = pyrr.matrix44.create_perspective_projection(45, 1, 0.1, 100)

    def cycle(i):
        with ad.Offscreen(counting, (8, 8), samples=0) as target:
            r = ad.AxialRenderer(counting, mesh, params, options=ad.RenderOptions(quantized=bool(i % 2)))
            target.use()
            r.render(view, proj, ("solid", "flat", "wireframe")[i % 3])
            if i % 50 == 0:
                r.capture(0, 2)
            r.release()

    for i in range(50):  # warm-up: shader caches, allocator pools
        cycle(i)
    # moderngl 5 cannot delete a query: the culling pass keeps ONE per context (gl/cull.py shared_query)
    shared = [o for o in counting.created if isinstance(o, moderngl.Query)]
    assert len(shared) <= 1  # none if an earlier test in the session made it
    for query in shared:
        counting.created.remove(query)
    assert counting.live() == 0
    before = rss_bytes()
    for i in range(1000):
        cycle(i)
        if i % 100 == 0:
            assert counting.live() == 0
    grown = rss_bytes() - before
    print(f"\n1000 renderers: live GL objects {counting.live()}, RSS growth {grown / 2**20:.2f} MB")
    assert counting.live() == 0, "GL objects left alive"
    assert grown < 48 * 2**20, f"RSS grew by {grown / 2**20:.1f} MB over 1000 renderers"


def test_10000_parameter_updates_do_not_grow(ctx, stone):
    counting = CountingContext(ctx)
    rng = np.random.default_rng(9)
    params = ad.random_params(stone, 1000, seed=1)
    with ad.AxialRenderer(counting, stone, params, capacity=1000) as r:
        objects = counting.live()
        before = rss_bytes()
        for i in range(10_000):
            if i % 10 == 0:
                params = params + np.float32(0.001)
                r.set_params(params)  # all 1000
            else:
                start = int(rng.integers(0, 990))
                block = params[start : start + 10] * np.float32(1.0001)
                r.update_params(block, start)
                params[start : start + 10] = block
        grown = rss_bytes() - before
        print(f"\n10000 updates: live GL objects {counting.live() - objects} more, RSS growth {grown / 2**20:.2f} MB")
        assert r.instances.reallocations == 0
        assert counting.live() == objects
        assert np.array_equal(r.instances.read(), params)
    assert counting.live() == 0
    assert grown < 16 * 2**20, f"RSS grew by {grown / 2**20:.1f} MB over 10 000 updates"


# ---------------------------------------------------------------------- scale


def million_params(n: int = 1_000_000, seed: int = 1) -> np.ndarray:
    """n instances on a cubic grid (3 units apart), random bends and angles: (n, 16) float32."""
    side = int(round(n ** (1 / 3)))
    assert side**3 == n
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3) * 3.0
    p = np.zeros((n, 16), np.float32)
    p[:, :10] = rng.normal(scale=0.15, size=(n, 10))
    p[:, 10:13] = grid
    p[:, 13:16] = rng.uniform(0, 2 * np.pi, (n, 3))
    return p


class DrawCounter:
    """Wraps a vertex array and counts its render() calls."""

    def __init__(self, vao):
        self.vao, self.calls = vao, 0

    def render(self, *args, **kwargs):
        self.calls += 1
        return self.vao.render(*args, **kwargs)

    def __getattr__(self, name):
        return getattr(self.vao, name)


@pytest.mark.slow
@pytest.mark.parametrize("quantized", [False, True])
def test_million_instances_one_draw_call(ctx, quantized):
    n = 1_000_000
    mesh = make_mesh(TETRA_V, TETRA_F, "tetra")
    params = million_params(n)
    background = np.array([0.93, 0.94, 0.96])
    view = pyrr.matrix44.create_look_at((570.0, 450, 670), (150.0, 150, 150), (0, 1, 0))
    proj = pyrr.matrix44.create_perspective_projection(45, 1, 1, 3000)
    # culling=False: the plain path draws every instance in ONE call (tests/gl/test_cull.py covers the culled draw)
    with ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(quantized=quantized, culling=False)) as r, \
            ad.Offscreen(ctx, (96, 96), samples=0) as target:
        assert r.count == n
        assert r.instances.buffer.size == n * (32 if quantized else 64)
        r._vao_triangles = counter = DrawCounter(r._vao_triangles)
        target.use(tuple(background))
        r.render(view, proj)
        image = target.read()
        assert counter.calls == 1, "one instanced draw call for all instances"
    drawn = np.any(np.abs(image.astype(int) - np.round(background * 255)) > 2, axis=-1).mean()
    assert 0.2 < drawn < 0.9, f"{drawn:.0%} of the pixels drawn"


def test_quantized_gpu_capture_matches_cpu_of_dequantized(ctx, stone, leaf):
    for mesh in (stone, leaf):
        params = ad.random_params(mesh, 300, seed=11)
        lo, step, q = quantize_params(params)
        expected = dequantize_params(lo, step, q)
        cpu_pos, cpu_nrm = deform(mesh.axis, mesh.positions, mesh.normals, expected)
        with ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(quantized=True)) as r:
            assert np.array_equal(r.instances.read(), expected)
            pos, nrm = r.capture()
            L = mesh.axis.length
            assert np.abs(pos - cpu_pos).max() <= 1e-5 * L
            assert np.abs(nrm - cpu_nrm).max() <= 1e-4
            # a new set re-quantizes; the uniforms of every program follow
            params2 = ad.random_params(mesh, 50, seed=12)
            r.set_params(params2)
            expected2 = dequantize_params(*quantize_params(params2))
            pos2, _ = r.capture(10, 20)
            cpu2, _ = deform(mesh.axis, mesh.positions, mesh.normals, expected2[10:30])
            assert np.abs(pos2 - cpu2).max() <= 1e-5 * L
            # an update inside the quantized range is stored; outside it is refused with advice
            r.update_params(expected2[3:5], 3)
            assert np.array_equal(r.instances.read(), expected2)
            bad = expected2[3:4].copy()
            bad[0, 10] += 1e6
            with pytest.raises(ad.core.ParamError, match=r"outside the quantized range .*call set_params\(\)"):
                r.update_params(bad, 3)

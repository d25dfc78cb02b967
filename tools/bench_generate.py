#!/usr/bin/env python3
"""Time to generate a layer: glsl/generate.glsl's slots by a compute shader (glsl/generate.comp, GL >= 4.3;
all the tiles in one dispatch) and by transform feedback (glsl/generate.vert; a pass a tile), into one GPU
buffer; the slots compacted into a renderer's own buffers (``GeneratedTiles.make``: what ``view`` does
when the tiles change) and the numpy reference, against one frame's draw of the same instances.

    python3 tools/bench_generate.py                    # 1 000 000 stones (tiles of 16 x 16 units, rate 4)
    python3 tools/bench_generate.py --count 100000 --repeats 5
    python3 tools/bench_generate.py --walk             # a tile set of examples/generated/walk.toml made
                                                       # anew: numpy + upload against the GPU (view's way)

Medians over --repeats, the methods alternated; the draw is AxialRenderer.render of the stones (one
instanced draw, no culling) into a 640 x 480 target, finished (ctx.finish).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import moderngl
import numpy as np

import axialdeform as ad
from axialdeform.core.camera import frame_instances
from axialdeform.core.generate import GENERATED_FLOATS, Generate, generate_tiles, tile_size
from axialdeform.gl.generate import TileGenerator
from axialdeform.gl.generated import GeneratedTiles
from axialdeform.gl.renderer import AxialRenderer


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--count", type=int, default=1_000_000, help="instances (rounded up to whole tiles)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--walk", action="store_true", help="time a tile set of the walk example's layers made anew")
    a = p.parse_args(argv)
    if a.walk:
        return walk(a.repeats)
    recipe = Generate(rate=4.0, tile=16.0, min_distance=0.2, seed=1, bend=0.15, scale=(0.5, 1.0))
    m, _ = tile_size(recipe)
    side = math.ceil(math.sqrt(a.count / (m * m)))
    tiles = np.array([(x, z) for x in range(side) for z in range(side)])
    n = len(tiles) * m * m
    stone = ad.load_mesh("stone")
    ctx = moderngl.create_standalone_context(backend="egl")
    ways = {"compute": TileGenerator(ctx, recipe, stone, compute=True),
            "transform feedback": TileGenerator(ctx, recipe, stone, compute=False)}
    out = ctx.buffer(reserve=n * GENERATED_FLOATS * 4)
    params = generate_tiles(recipe, stone, tiles)
    renderer = AxialRenderer(ctx, stone, params, options=ad.RenderOptions(culling=False, lod=False))
    held = AxialRenderer(ctx, stone, params[:0], options=ad.RenderOptions(culling=False, lod=False, extended=True))
    into = GeneratedTiles(held, recipe, stone)
    target = ctx.simple_framebuffer((640, 480))
    cam = frame_instances(stone, params, 640 / 480)
    view, proj = cam.view(), cam.projection(640 / 480)

    def slots(gen):
        def run():
            t = time.perf_counter()
            gen.run_tiles(tiles, out)
            ctx.finish()
            return time.perf_counter() - t
        return run

    def compact():
        t = time.perf_counter()
        into.make(tiles)  # ends reading the count back: the passes are finished
        return time.perf_counter() - t

    def cpu():
        t = time.perf_counter()
        generate_tiles(recipe, stone, tiles)
        return time.perf_counter() - t

    def draw():
        t = time.perf_counter()
        target.use()
        ctx.clear(0.9, 0.9, 0.9, 1.0, depth=1.0)
        renderer.render(view, proj, look=ad.Look(fast=True))
        ctx.finish()
        return time.perf_counter() - t

    runs = {"generate (GPU, compute)": [], "generate (GPU, transform feedback)": [],
            "generate into a renderer (GPU, + compaction)": [], "generate (numpy)": [], "draw one frame": []}
    for _ in range(a.repeats):
        for name, f in zip(runs, (slots(ways["compute"]), slots(ways["transform feedback"]), compact, cpu, draw)):
            runs[name].append(f())
    print(f"{n:,} instances ({len(tiles)} tiles of {m * m}); {ctx.info['GL_RENDERER']}; medians of {a.repeats}:")
    for name, ts in runs.items():
        print(f"  {name}: {1000 * statistics.median(ts):.1f} ms")
    g, d = statistics.median(runs["generate (GPU, compute)"]), statistics.median(runs["draw one frame"])
    f = statistics.median(runs["generate (GPU, transform feedback)"])
    c = statistics.median(runs["generate into a renderer (GPU, + compaction)"])
    print(f"  GPU generation / one frame's draw: {g / d:.3f} (compute), {f / d:.3f} (transform feedback); "
          f"into a renderer: {c / d:.3f}")
    if held.count != len(params):
        raise SystemExit(f"the renderer holds {held.count:,}, numpy made {len(params):,}")
    return 0


def walk(repeats: int) -> int:
    """What ``view --walk`` pays when its tiles change: every generated layer of examples/generated/walk.toml
    (stones, grass, trees of ten axes) made for the tiles around a point, by numpy and uploaded into its
    renderer (how ``view`` made them before), or made on the GPU into the renderer (``GeneratedTiles``)."""
    from pathlib import Path

    from axialdeform.core.generate import tiles_around

    scene = ad.Scene.load(Path(__file__).resolve().parents[1] / "examples" / "generated" / "walk.toml")
    ctx = moderngl.create_standalone_context(backend="egl")
    layers = []
    for layer in scene.layers:
        g = layer.generate
        tiles = tiles_around(g.generate, 300.0, 180.0, g.reach)
        width = np.asarray(layer.params).shape[1]
        cpu_r, gpu_r = (AxialRenderer(ctx, layer.mesh, np.zeros((0, width), np.float32)) for _ in range(2))
        layers.append((layer, tiles, cpu_r, gpu_r, GeneratedTiles(gpu_r, g.generate, layer.mesh, g.maps)))

    def cpu():
        t = time.perf_counter()
        for layer, tiles, r, _, _ in layers:
            r.set_params(generate_tiles(layer.generate.generate, layer.mesh, tiles, layer.generate.maps))
        ctx.finish()
        return time.perf_counter() - t

    def gpu():
        t = time.perf_counter()
        for _, tiles, _, _, gen in layers:
            gen.make(tiles)  # ends reading the count back
        ctx.finish()
        return time.perf_counter() - t

    runs = {"numpy + upload": [], "GPU into the renderer": []}
    for _ in range(repeats):
        for name, f in zip(runs, (cpu, gpu)):
            runs[name].append(f())
    held = [(layer.name, r.count) for layer, _, _, r, _ in layers]
    if any(r.count != g.count for _, _, r, g, _ in layers):
        raise SystemExit("the two ways hold different counts")
    print(f"a tile set of {', '.join(f'{n} {c:,}' for n, c in held)}; {ctx.info['GL_RENDERER']}; medians of {repeats}:")
    for name, ts in runs.items():
        print(f"  {name}: {1000 * statistics.median(ts):.1f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

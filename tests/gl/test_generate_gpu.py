"""Generated layers on the GPU (glsl/generate.glsl by transform feedback) equal the numpy reference."""

from __future__ import annotations

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.generate import Generate, generate_tile, generate_tiles
from axialdeform.gl.generate import TileGenerator, generate_tile_gpu

RECIPES = [Generate(rate=4.0, tile=8.0, min_distance=0.3, seed=7, bend=0.1),
           Generate(rate=2.5, tile=10.0, min_distance=0.1, seed=4_000_000_000, bend=0.2, scale=(0.7, 1.3),
                    twist=0.5, taper=0.3)]


@pytest.mark.parametrize("recipe", RECIPES, ids=["16 numbers", "19 numbers"])
def test_the_gpu_makes_the_numpy_records(ctx, recipe):
    stone = ad.load_mesh("stone")
    for tile in [(0, 0), (-3, 5), (1000, -7), (-40000, 123456)]:
        cpu, _ = generate_tile(recipe, stone, *tile)
        gpu = generate_tile_gpu(ctx, recipe, stone, *tile)
        assert gpu.shape == cpu.shape
        rel = np.abs(gpu - cpu) / np.maximum(1.0, np.abs(cpu))
        assert rel.max() <= 1e-6, (tile, rel.max())
    # the hash is exact: the positions' jitter (u0, u1) is the same number on both sides
    assert np.array_equal(gpu[:, [10, 12]], cpu[:, [10, 12]])


def test_one_program_makes_any_tile_into_a_gpu_buffer(ctx):
    stone = ad.load_mesh("stone")
    gen = TileGenerator(ctx, RECIPES[0], stone)
    buf = gen.buffer()
    try:
        out = []
        for tile in [(2, 2), (0, 0), (2, 2)]:
            gen.run(tile, buf)
            out.append(np.frombuffer(buf.read(), np.float32).reshape(gen.count, 19)[:, :16].copy())
    finally:
        buf.release()
        gen.release()
        gen.release()  # safe twice
    assert np.array_equal(out[0], out[2]) and not np.array_equal(out[0], out[1])
    assert np.array_equal(out[1], generate_tile(RECIPES[0], stone, 0, 0)[0])
    # tiles side by side in one buffer (the layout of a layer's instance buffer): each at its offset
    gen = TileGenerator(ctx, RECIPES[0], stone)
    both = ctx.buffer(reserve=2 * gen.count * 19 * 4)
    try:
        gen.run((5, -5), both, offset=gen.count * 19 * 4)
        gen.run((0, 0), both)
        got = np.frombuffer(both.read(), np.float32).reshape(2 * gen.count, 19)[:, :16]
    finally:
        both.release()
        gen.release()
    assert np.array_equal(got, generate_tiles(RECIPES[0], stone, [(0, 0), (5, -5)]))

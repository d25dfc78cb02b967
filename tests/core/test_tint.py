"""The record's third level, tinted instances (22 numbers: ``tr tg tb`` after
the 19): the proof that a per-instance field is added in the record table
(core/record.py) and the code that uses it -- files, views, random, checks."""

from __future__ import annotations

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core import record as R
from axialdeform.core.io.params import decode_binary, encode_binary, format_text, parse_text, write_param_chunks
from axialdeform.core.params import (
    as_params,
    extend_params,
    is_extended,
    is_tinted,
    tint_params,
)
from axialdeform.core.quantize import quantization_error_bound


@pytest.fixture(scope="module")
def tinted(stone):
    variation = ad.Variation(scale=(0.5, 1.5), twist=0.8, taper=0.3, tint=0.7, tint_color=(0.9, 0.6, 0.3))
    return ad.random_params(stone, 40, seed=3, variation=variation)


def test_the_field_comes_from_the_table(tinted):
    tint = next(f for f in R.RECORD if f.name == "tint")
    assert (tint.columns, tint.start, tint.level) == (("tr", "tg", "tb"), 19, 2)
    assert R.WIDTHS == (16, 19, 22) and R.TINT == slice(19, 22)
    assert tinted.shape == (40, 22) and is_extended(tinted) and is_tinted(tinted)
    assert np.shares_memory(tinted.tint, tinted) and tinted.tint.shape == (40, 3)
    assert "tint" in dir(tinted) and "tint" not in dir(ad.random_params(ad.load_mesh("stone"), 2, variation=ad.Variation(scale=1.0)))
    with pytest.raises(AttributeError, match=r"only tinted \(n, 22\) instances"):
        _ = R.Instances.of(extend_params(tinted)).tint
    z = R.Instances.zeros(3, tinted=True)
    assert z.shape == (3, 22) and np.all(z.tint == 1.0) and np.all(z.scale == 1.0)


def test_random_tint_keeps_every_other_number(stone, tinted):
    """The tint is drawn after the other numbers of the stream: the first 19
    are those of the same call without it, and pieces give the same rows."""
    same = ad.random_params(stone, 40, seed=3, variation=ad.Variation(scale=(0.5, 1.5), twist=0.8, taper=0.3))
    assert np.array_equal(tinted[:, :19], same)
    assert (tinted.tint >= 0.9 * np.float32([0.9, 0.6, 0.3]) * 0.3 - 1e-6).all()
    assert (tinted.tint <= np.float32([0.9, 0.6, 0.3])).all() and tinted.tint.std(axis=0).min() > 0.01
    from axialdeform.core.variation import iter_random_params

    pieces = list(iter_random_params(stone, 40, seed=3, chunk=7, variation=ad.Variation(scale=(0.5, 1.5), twist=0.8, taper=0.3, tint=0.7,
                                                                                        tint_color=(0.9, 0.6, 0.3))))
    assert np.array_equal(np.concatenate(pieces), tinted)
    for bad in (1.5, -0.1, "x"):
        with pytest.raises(ad.core.ParamError, match="tint"):
            ad.random_params(stone, 2, variation=ad.Variation(tint=bad))
    with pytest.raises(ad.core.ParamError, match="tint_color"):
        ad.random_params(stone, 2, variation=ad.Variation(tint=0.2, tint_color=(1, 2, 0)))


@pytest.mark.parametrize("form", ["text", "float32", "quantized"])
def test_tint_survives_every_file_form(tmp_path, stone, tinted, form):
    path = tmp_path / ("t.txt" if form == "text" else "t.adp")
    ad.write_params(path, tinted, stone, quantize=form == "quantized")
    back = ad.core.read_param_file(path)
    assert back.values.shape == (40, 22)
    if form == "quantized":
        assert back.version == 3
        assert (np.abs(back.values - tinted) <= quantization_error_bound(tinted)).all()
    else:
        assert np.array_equal(back.values, tinted)
    if form == "text":
        assert path.read_text().splitlines()[2].endswith("s tw tp tr tg tb")
    else:
        assert back.version == 3 and path.stat().st_size == 96 + 4 + 40 * (44 if form == "quantized" else 88) + (
            8 * 22 if form == "quantized" else 0)


def test_written_in_pieces_equals_written_whole(tmp_path, stone, tinted):
    for quantize in (False, True):
        whole, pieces = tmp_path / f"w{quantize}.adp", tmp_path / f"p{quantize}.adp"
        ad.write_params(whole, tinted, stone, quantize=quantize)
        write_param_chunks(pieces, lambda: (tinted[k:k + 9] for k in range(0, 40, 9)), 40, 22, stone,
                           quantize=quantize)
        assert whole.read_bytes() == pieces.read_bytes()


def test_a_bad_tint_is_named_by_line_and_field(tinted):
    text = format_text(tinted).splitlines()
    row = text[3].split()
    row[20] = "1.5"  # tg above 1
    text[3] = " ".join(row)
    with pytest.raises(ad.core.ParamFileError, match=r"line 4, field tg: expected a tint in 0\.\.1"):
        parse_text("\n".join(text).encode(), "t.txt")
    bad = np.array(tinted)
    bad[5, 21] = -0.25
    with pytest.raises(ad.core.ParamError, match=r"instance 5, field tb: expected a tint in 0\.\.1"):
        as_params(bad)
    with pytest.raises(ad.core.ParamFileError, match=r"line 2: expected 22 numbers like line 1"):
        parse_text(b" ".join([b"0"] * 15 + [b"1"] * 7) + b"\n" + b" ".join([b"0"] * 15 + [b"1"] * 4), "mixed.txt")


def test_tint_params_and_make_params(stone):
    p = ad.random_params(stone, 4, seed=1)
    t = tint_params(p, (0.2, 0.4, 0.6))
    assert t.shape == (4, 22) and np.array_equal(t[:, :16], p) and np.array_equal(t[:, 16:19], np.tile([1, 0, 0], (4, 1)))
    assert np.allclose(t.tint, [0.2, 0.4, 0.6])
    m = ad.core.make_params(positions=p[:, 10:13], tint=np.full((4, 3), 0.5))
    assert m.shape == (4, 22) and np.all(m.tint == 0.5) and np.all(m.scale == 1.0)
    with pytest.raises(ad.core.ParamError, match=r"tint: expected \(3,\) or \(4, 3\)"):
        tint_params(p, np.ones((3, 3)))
    assert decode_binary(encode_binary(t)).values.shape == (4, 22)


def test_the_geometry_ignores_the_tint(stone, tinted):
    """The bend, the bounds and the CPU reference of a tinted instance are
    those of its first 19 numbers."""
    a = ad.deform(stone.axis, stone.positions, stone.normals, tinted)
    b = ad.deform(stone.axis, stone.positions, stone.normals, tinted[:, :19])
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert np.array_equal(ad.core.instance_bounds(stone, tinted)[0], ad.core.instance_bounds(stone, tinted[:, :19])[0])


def test_a_tint_keeps_its_hue_unless_asked_to_vary_it():
    """``tint`` makes shades of ``tint_color`` (one u an instance: the channels keep their ratios, no stone
    turns pink or mint); ``tint_hue`` lets each channel's u go its own way, in random_params, scatter and a
    generated layer alike, and anything but an amount in 0..1 is refused in words."""
    from axialdeform.core.errors import ParamError
    from axialdeform.core.generate import Generate, generate_tile

    stone = ad.load_mesh("stone")
    color = np.array([0.9, 0.6, 0.3])
    shades = ad.random_params(stone, 200, seed=3, variation=ad.Variation(tint=0.6, tint_color=tuple(color)))[:, R.TINT] / color
    assert np.ptp(shades, axis=1).max() < 1e-6 and np.ptp(shades[:, 0]) > 0.3  # one factor each, varied
    hues = ad.random_params(stone, 200, seed=3, variation=ad.Variation(tint=0.6, tint_color=tuple(color), tint_hue=1.0))[:, R.TINT] / color
    assert np.ptp(hues, axis=1).mean() > 0.1
    half = ad.random_params(stone, 200, seed=3, variation=ad.Variation(tint=0.6, tint_color=tuple(color), tint_hue=0.5))[:, R.TINT] / color
    assert 0.3 < np.ptp(half, axis=1).mean() / np.ptp(hues, axis=1).mean() < 0.7
    surface = np.zeros((16, 16))
    scattered = ad.scatter(surface, stone, 50, ad.Variation(tint=0.6, tint_color=tuple(color)), seed=2)[:, R.TINT] / color
    assert np.ptp(scattered, axis=1).max() < 1e-6
    rec, kept = generate_tile(Generate(rate=2.0, tile=8.0, tint=0.6, tint_color=tuple(color)), stone, 0, 0)
    assert np.ptp(rec[kept][:, R.TINT] / color.astype(np.float32), axis=1).max() < 1e-6
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(ParamError, match="tint_hue"):
            ad.Variation(tint=0.5, tint_hue=bad)
        with pytest.raises(ParamError, match="tint_hue"):
            Generate(rate=1.0, tint=0.5, tint_hue=bad)

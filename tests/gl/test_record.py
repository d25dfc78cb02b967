"""The instance record (core/record.py) is the one home of the layout: the
named views share memory with the array, and the GL program's active
attributes, the page's config and the glTF attributes all equal what the
table generates."""

from __future__ import annotations

import moderngl
import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core import record as R
from axialdeform.gl.shaders import build_program

_GL_TYPES = {1: "f", 2: "2f", 3: "3f", 4: "4f"}


def test_columns_and_slices_come_from_the_table():
    assert R.FIELDS == ("d1u", "d1v", "d2u", "d2v", "d3u", "d3v", "d4u", "d4v", "d5u", "d5v",
                        "px", "py", "pz", "rx", "ry", "rz")
    assert R.EXTENDED_FIELDS[16:] == ("s", "tw", "tp")
    # every column belongs to exactly one field, in order, without gaps
    cols = [c for f in R.RECORD for c in range(f.start, f.stop)]
    assert cols == list(range(22))
    # every shader input covers the columns of whole fields in row order
    inputs = [c for a in R.SHADER_INPUTS for c in range(a.start, a.start + a.size)]
    assert inputs == list(range(22))
    # the levels: each adds whole fields after the last one, its width is a prefix of the row
    assert R.WIDTHS == (16, 19, 22) and R.LEVEL_FIELDS[2][19:] == ("tr", "tg", "tb")
    for level, width in enumerate(R.WIDTHS):
        assert sum(len(f.columns) for f in R.RECORD if f.level <= level) == width
        assert all(f.stop <= width for f in R.RECORD if f.level <= level)


def test_named_views_share_memory_and_write_through(stone):
    p = ad.random_params(stone, 7, seed=3)
    assert isinstance(p, R.Instances) and isinstance(p, np.ndarray)
    assert p.offsets.shape == (7, 5, 2) and p.position.shape == (7, 3) and p.rotation.shape == (7, 3)
    for name in ("offsets", "position", "rotation"):
        assert np.shares_memory(getattr(p, name), p)
    before = np.array(p)
    p.position[:, 1] += 2.0
    p.offsets[:, 4] *= 3.0
    assert np.array_equal(p[:, 11], before[:, 11] + 2.0)
    assert np.array_equal(p[:, 8:10], before[:, 8:10] * 3.0)
    p.rotation = 0.0  # assignment to a view fills the columns
    assert not p[:, 13:16].any()
    assert np.array_equal(np.asarray(p)[:, :8], np.asarray(before)[:, :8])


def test_named_views_of_a_record_of_several_axes():
    """A tree's record (10 more numbers an axis after the first): the same names, each field where the tree
    puts it (the child axes' offsets after axis 0's), offsets as (n, K, 5, 2); written through."""
    mesh = ad.load_mesh("tree", axes="parts")
    k = mesh.axis_count
    p = ad.random_params(mesh, 5, seed=2, variation=ad.Variation(scale=(0.8, 1.2)))
    assert p.shape == (5, R.tree_width(k, 1))
    assert p.offsets.shape == (5, k, 5, 2) and np.array_equal(p.offsets[:, 1].reshape(5, 10), p[:, 10:20])
    assert np.array_equal(p.position, p[:, 10 * k:10 * k + 3]) and np.array_equal(p.scale, p[:, 10 * k + 6])
    p.position[:, 1] += 2.0
    p.rotation = 0.0
    assert np.all(p[:, 10 * k + 1] == p.position[:, 1]) and not p[:, 10 * k + 3:10 * k + 6].any()
    assert np.shares_memory(p.offsets, p) and "scale" in dir(p) and "tint" not in dir(p)
    with pytest.raises(AttributeError, match="tinted"):
        _ = p.tint


def test_extended_views_and_their_errors(stone):
    p = R.Instances.of(ad.core.extend_params(ad.random_params(stone, 4, seed=1)))
    assert p.scale.shape == (4,) and np.all(p.scale == 1.0)
    p.twist[:] = 0.5
    assert np.all(p[:, 17] == 0.5)
    plain = ad.random_params(stone, 4, seed=1)
    with pytest.raises(AttributeError, match="extended"):
        _ = plain.scale
    with pytest.raises(AttributeError, match="no attribute 'banana'"):
        _ = plain.banana
    with pytest.raises(AttributeError, match=r"\(n, 16\)"):
        _ = plain[:, 0].position


@pytest.mark.parametrize("extended", [False, True])
@pytest.mark.parametrize("quantized", [False, True])
def test_the_vertex_shader_declares_what_the_table_generates(ctx, extended, quantized):
    """The compiled program's active instanced attributes (names and sizes)
    equal :func:`gl_layout` -- read from the GL program, not from the text."""
    defines = {}
    if extended:
        defines["AXIAL_EXTENDED"] = 1
    if quantized:
        defines["AXIAL_QUANTIZED"] = 1
    prog = build_program(ctx, "scene.vert", "scene.frag", defines=defines)
    try:
        active = {}
        for name in prog:
            member = prog[name]
            if isinstance(member, moderngl.Attribute) and name.startswith("i_"):
                active[name] = member.dimension
        formats, names, record_bytes = R.gl_layout(extended, quantized)
        expected = {n: int(f[0]) for f, n in zip(formats, names) if n is not None}
        assert active == expected
        assert record_bytes == sum(int(f[0]) * (2 if "u2" in f else 4 if f.endswith("f") else 1) for f in formats)
    finally:
        prog.release()


def test_gltf_receives_the_table(stone):
    from axialdeform.core.io import gltf as export
    from axialdeform.web import build_scene

    assert export.ATTRIBUTES is R.GLTF_ATTRIBUTES
    for kind, cols in R.GLTF_ATTRIBUTES.values():
        assert {"VEC2": 2, "VEC3": 3, "VEC4": 4}[kind] == len(cols)
    scene = build_scene(stone, ad.random_params(stone, 3, seed=1))
    assert "record" not in scene.config  # the page reads the columns from the npm module's recordLayout


def test_instances_zeros_and_of():
    z = R.Instances.zeros(3)
    assert z.shape == (3, 16) and z.dtype == np.float32 and not z.any()
    e = R.Instances.zeros(2, extended=True)
    assert e.shape == (2, 19) and np.all(e.scale == 1.0) and not e.twist.any()
    raw = np.arange(32, dtype=np.float32).reshape(2, 16)
    v = R.Instances.of(raw)
    v.position[:] = 0.0
    assert not raw[:, 10:13].any()  # a view: no copy

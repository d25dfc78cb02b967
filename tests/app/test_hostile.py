"""Hostile input: parameter files and meshes under attack, and
errors a user can act on.

Every bad input must end in an :class:`axialdeform.AxialDeformError`
subclass whose message names the file -- never another exception type, a
MemoryError, a hang, or silently wrong numbers.  Hypothesis runs are bounded
(``max_examples``, no deadline) so the whole file stays well under a minute.
"""

from __future__ import annotations

import os
import struct
import subprocess
import sys
import tracemalloc
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import axialdeform as ad
from axialdeform.core.deform import deform
from axialdeform.core.errors import AxialDeformError, MeshError, ParamError, ParamFileError, ShaderError
from axialdeform.core.io import params as P
from axialdeform.core.quantize import quantization_error_bound

from conftest import DATA, make_mesh

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow], database=None)
RNG = np.random.default_rng(2003)
VALUES = RNG.normal(size=(3, 16)).astype(np.float32)
FLOAT_FILE = P.encode_binary(VALUES)
QUANT_FILE = P.encode_binary(VALUES, quantize=True)


def check_outcome(fn, *args):
    """Call a reader; it must return good values or raise an AxialDeformError.

    Returns the ParamFile / array on success (already checked: (n, 16)
    finite float32) or the error raised."""
    try:
        out = fn(*args)
    except AxialDeformError as exc:
        assert str(exc), "an error without a message"
        return exc
    values = out.values if isinstance(out, P.ParamFile) else out
    assert values.dtype == np.float32 and values.ndim == 2 and values.shape[1] == 16
    assert np.isfinite(values).all()
    return out


def with_crc(body: bytes) -> bytes:
    """Append a correct CRC-32 so a mutation reaches the checks after the checksum."""
    return body + struct.pack("<I", zlib.crc32(body))


def header(count=3, *, version=1, encoding=0, header_size=96, axis=-1, lo=0.0, length=0.0, magic=P.MAGIC):
    return struct.pack("<8sHHIQb3xIdd32s16x", magic, version, encoding, header_size, count, axis, 0, lo, length, bytes(32))


# ---------------------------------------------------------------- binary form


@FUZZ
@given(st.binary(max_size=600))
def test_random_bytes_never_crash(data):
    check_outcome(P.decode_binary, data, "fuzz.adp")
    check_outcome(P.parse_text, data, "fuzz.txt")
    check_outcome(P.decode_binary, P.MAGIC + data, "fuzz.adp")


@FUZZ
@given(
    count=st.one_of(st.integers(0, 8), st.integers(0, 2**64 - 1), st.just(2**60)),
    version=st.one_of(st.just(1), st.integers(0, 2**16 - 1)),
    encoding=st.one_of(st.sampled_from([0, 1]), st.integers(0, 2**16 - 1)),
    header_size=st.one_of(st.just(96), st.integers(0, 2**32 - 1)),
    axis=st.integers(-128, 127),
    lo=st.floats(allow_nan=True, allow_infinity=True),
    length=st.floats(allow_nan=True, allow_infinity=True),
    payload=st.binary(max_size=300),
)
def test_any_header_with_valid_checksum(count, version, encoding, header_size, axis, lo, length, payload):
    """Every header field gets arbitrary values; the CRC is made to match so
    the later checks (count vs length, axis, NaN payload) are reached."""
    data = with_crc(header(count, version=version, encoding=encoding, header_size=header_size, axis=axis,
                           lo=lo, length=length) + payload)
    out = check_outcome(P.decode_binary, data, "hdr.adp")
    if isinstance(out, Exception):
        assert isinstance(out, ParamFileError) and "hdr.adp" in str(out)


@pytest.mark.slow
@pytest.mark.parametrize("quantize", [False, True])
def test_every_single_byte_flip_is_caught(quantize):
    """CRC-32 detects every burst of up to 32 bits: each byte, each of its 255
    other values -> ParamFileError, never different numbers."""
    good = QUANT_FILE if quantize else FLOAT_FILE
    assert np.array_equal(P.decode_binary(good).values, P.decode_binary(good).values)
    flips = 0
    buf = bytearray(good)
    for i in range(len(good)):
        original = buf[i]
        for x in range(1, 256):
            buf[i] = original ^ x
            with pytest.raises(ParamFileError):
                P.decode_binary(bytes(buf), "flip.adp")
            flips += 1
        buf[i] = original
    assert flips == len(good) * 255


@pytest.mark.parametrize("quantize", [False, True])
def test_every_truncation_is_caught(quantize, tmp_path):
    good = QUANT_FILE if quantize else FLOAT_FILE
    for n in range(len(good)):
        with pytest.raises(ParamFileError) as exc:
            P.decode_binary(good[:n], "cut.adp")
        assert "cut.adp" in str(exc.value)
    path = tmp_path / "cut.adp"
    path.write_bytes(good[:150])
    with pytest.raises(ParamFileError, match="cut.adp.*(truncated|count)"):
        P.read_param_file(path)


def test_count_of_2_pow_60_allocates_nothing():
    """The declared count is checked against the length before any allocation."""
    data = with_crc(header(2**60) + bytes(64))
    tracemalloc.start()
    try:
        with pytest.raises(ParamFileError, match=r"count: the header declares 1152921504606846976 instances"):
            P.decode_binary(data, "huge.adp")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 64 * 1024, f"decoding a 200-byte file allocated {peak} bytes"


@pytest.mark.parametrize(
    "data, pattern",
    [
        (b"\x89ADX\r\n\x1a\n" + FLOAT_FILE[8:], "magic"),
        (header(version=4) + FLOAT_FILE[96:], r"version: expected 1 \(16 numbers\), 2 \(19 numbers\), 3 \(22 numbers\), found 4"),
        (with_crc(header(version=7) + FLOAT_FILE[96:-4]), "version"),
        (with_crc(header(encoding=9) + FLOAT_FILE[96:-4]), "encoding"),
        (with_crc(header(header_size=64) + FLOAT_FILE[96:-4]), "header size"),
        (with_crc(header(count=4) + FLOAT_FILE[96:-4]), "count: the header declares 4 instances"),
        (with_crc(header(count=2) + FLOAT_FILE[96:-4]), "count: the header declares 2 instances"),
        (with_crc(header(axis=5) + FLOAT_FILE[96:-4]), "axis"),
        (with_crc(header(axis=1, lo=0.0, length=float("nan")) + FLOAT_FILE[96:-4]), "axis"),
        (with_crc(header(axis=1, lo=0.0, length=-1.0) + FLOAT_FILE[96:-4]), "axis"),
        (FLOAT_FILE[:-4] + b"\0\0\0\0", "checksum"),
    ],
    ids=["magic", "version", "version-crc", "encoding", "header-size", "count-more", "count-less", "axis-index",
         "axis-nan", "axis-negative", "crc"],
)
def test_binary_header_errors_name_file_and_field(data, pattern):
    with pytest.raises(ParamFileError, match=pattern) as exc:
        P.decode_binary(data, "bad.adp")
    assert str(exc.value).startswith("bad.adp: ")


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("quantize", [False, True])
def test_non_finite_values_are_refused(bad, quantize):
    """Policy (params.py): NaN and Inf have no shape; every reader and writer refuses them."""
    v = VALUES.copy()
    v[1, 12] = bad
    with pytest.raises(ParamError, match="instance 1, field pz: expected a finite number"):
        P.encode_binary(v, quantize=quantize)
    if not quantize:  # hand-made file with a NaN and a correct CRC
        data = with_crc(header(3) + v.astype("<f4").tobytes())
        with pytest.raises(ParamFileError, match="nan.adp: instance 1, field pz: expected a finite number"):
            P.decode_binary(data, "nan.adp")
    else:  # a quantization table whose step is NaN / whose decode overflows
        table = struct.pack("<16f16f", *([0.0] * 16), *([bad] + [1.0] * 15))
        data = with_crc(header(1, encoding=1) + table + bytes(32))
        with pytest.raises(ParamFileError, match="nan.adp: .*d1u: expected a finite number"):
            P.decode_binary(data, "nan.adp")


def test_quantized_table_overflow_is_refused():
    table = struct.pack("<16f16f", *([3e38] * 16), *([3e38] * 16))
    data = with_crc(header(1, encoding=1) + table + b"\xff\xff" * 16)
    with pytest.raises(ParamFileError, match="expected a finite number"):
        P.decode_binary(data, "big.adp")


# ------------------------------------------------------------------ text form


ROW = " ".join(["1.5"] * 16)


@pytest.mark.parametrize(
    "text, pattern",
    [
        (ROW.replace("1.5", "nan", 1), "line 1, field d1u: expected a finite number"),
        (ROW + "\n" + ROW.replace("1.5", "inf", 3), "line 2, field d1u: expected a finite number"),
        ("# c\n" + ROW.replace("1.5", "-Infinity", 1), "line 2, field d1u"),
        (" ".join(["1"] * 15), "line 1: expected 16 numbers, found 15"),
        (" ".join(["1"] * 17), "line 1: expected 16 numbers, found 17"),
        (ROW + "\n" + "1,2,3", "line 2: expected 16 numbers, found 3"),
        (ROW.replace("1.5", "abc", 2), "field d1u: expected a number, found 'abc'"),
        (ROW.replace("1.5", "0x10", 1), "expected a number, found '0x10'"),
        (ROW.replace("1.5", "1e39", 1), "1e\\+39 does not fit in float32"),
        ("1 " * 5000, "line 1 is 10000 characters long; expected at most 4096"),
    ],
    ids=["nan", "inf", "neg-inf", "15-cols", "17-cols", "3-cols", "word", "hex", "float32-overflow", "huge-line"],
)
def test_text_errors_name_file_line_and_field(text, pattern):
    with pytest.raises(ParamFileError, match=pattern) as exc:
        P.parse_text(text.encode(), "p.txt")
    assert str(exc.value).startswith("p.txt: ")


def test_text_not_utf8_and_bom():
    with pytest.raises(ParamFileError, match=r"p.txt: not a parameter file: byte 4 is not UTF-8"):
        P.parse_text(b"1 2 \xff\xfe 3", "p.txt")
    bom = P.parse_text(b"\xef\xbb\xbf" + ROW.encode(), "p.txt")  # Windows editors write a BOM
    assert bom.shape == (1, 16) and (bom == 1.5).all()


def test_huge_file_of_comments_and_blank_lines():
    data = (b"#" + b"x" * 4000 + b"\n") * 2000 + b"\n" * 100_000 + ROW.encode()
    assert P.parse_text(data, "big.txt").shape == (1, 16)


@FUZZ
@given(st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=400))
def test_any_unicode_text_never_crashes(text):
    check_outcome(P.parse_text, text.encode("utf-8"), "u.txt")


@FUZZ
@given(st.lists(st.lists(st.one_of(
    st.floats(width=32, allow_nan=False, allow_infinity=False),
    st.floats(), st.sampled_from(["nan", "-inf", "1e400", "1_0", "", "#", ",", "\u00a0", "١٢"]),
    st.integers(-2**70, 2**70)), min_size=14, max_size=18), max_size=6))
@pytest.mark.slow
def test_near_valid_text_never_crashes(rows):
    text = "\n".join(" ".join(str(x) for x in row) for row in rows)
    out = check_outcome(P.parse_text, text.encode(), "near.txt")
    if isinstance(out, Exception):
        assert isinstance(out, ParamFileError) and str(out).startswith("near.txt: ")


@FUZZ
@given(st.lists(st.lists(st.floats(width=32, allow_nan=False, allow_infinity=False), min_size=16, max_size=16),
                max_size=20), st.booleans())
@pytest.mark.slow
def test_valid_values_round_trip_every_form(rows, quantize):
    v = np.array(rows, dtype=np.float32).reshape(-1, 16)
    assert np.array_equal(P.parse_text(P.format_text(v).encode()), v)
    if not quantize:
        assert np.array_equal(P.decode_binary(P.encode_binary(v)).values, v)
    else:
        with np.errstate(over="ignore"):
            span = v.astype(np.float64).max(axis=0, initial=0) - v.astype(np.float64).min(axis=0, initial=0)
        if np.all(span < 3e38):  # a range wider than float32 cannot be quantized
            pf = P.decode_binary(P.encode_binary(v, quantize=True))
            assert np.all(np.abs(pf.values.astype(np.float64) - v) <= quantization_error_bound(v) * 1.0001 + 1e-45)


def test_read_param_file_refuses_non_files(tmp_path):
    with pytest.raises(ParamFileError, match="no such parameter file"):
        P.read_param_file(tmp_path / "missing.adp")
    with pytest.raises(ParamFileError, match="is a folder"):
        P.read_param_file(tmp_path)
    fifo = tmp_path / "pipe.txt"
    os.mkfifo(fifo)
    with pytest.raises(ParamFileError, match="pipe.txt: not a regular file"):
        P.read_param_file(fifo)  # would block forever if it were opened
    text_as_adp = tmp_path / "wrong.adp"
    text_as_adp.write_text(ROW)
    with pytest.raises(ParamFileError, match="wrong.adp: .*magic"):
        P.read_param_file(text_as_adp)
    png = tmp_path / "picture.txt"
    ad.save_png(png.with_suffix(".png"), np.zeros((4, 4, 3), np.uint8))
    png.write_bytes(png.with_suffix(".png").read_bytes())
    with pytest.raises(ParamFileError, match="picture.txt: "):
        P.read_param_file(png)


# --------------------------------------------------------------------- meshes


def _data_files():
    out = []
    for sub in ("edge_cases", "gltf", "gltf/validator"):
        for p in sorted((DATA / sub).iterdir()):
            if p.is_file() and p.suffix.lower() not in (".bin", ".txt", ".md"):
                out.append(p)
    return out


def _loads_and_deforms_or_mesh_error(path) -> str:
    try:
        mesh = ad.load_mesh(path)
    except MeshError as exc:
        assert str(path) in str(exc) or Path(path).name in str(exc), str(exc)
        return "error"
    params = ad.random_params(mesh, 4, seed=7)
    pos, nrm = deform(mesh.axis, mesh.positions, mesh.normals, params)
    assert np.isfinite(pos).all() and np.isfinite(nrm).all()
    assert np.isfinite(mesh.normals).all()
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-5)
    return "loaded"


def test_every_edge_case_mesh_loads_or_raises_mesh_error():
    files = _data_files()
    assert len(files) >= 50, f"the edge-case meshes in {DATA} are missing ({len(files)} found)"
    outcomes = {p.relative_to(DATA).as_posix(): _loads_and_deforms_or_mesh_error(p) for p in files}
    # some expectations from SOURCES.txt: empty, corrupt -> errors; boxes and several meshes load
    assert outcomes["gltf/simple_pole.glb"] == "loaded"  # 11 meshes: one base mesh with 11 parts
    assert outcomes["gltf/validator/empty_file.glb"] == "error"
    assert outcomes["gltf/validator/invalid_magic.glb"] == "error"
    assert outcomes["edge_cases/empty.stl"] == "error"
    assert outcomes["edge_cases/cube.OBJ"] == "loaded"
    assert outcomes["gltf/BoxInterleaved.glb"] == "loaded"


def test_every_edge_case_mesh_gets_axes_from_its_shape_or_a_mesh_error(tmp_path, monkeypatch):
    """axes="skeleton" and "auto" on every mesh that loads (flat planes, single triangles, soups, open
    shells, CAD parts, many bodies): a tree of 1 to 64 axes that bends, or a MeshError in words."""
    monkeypatch.setenv("AXIALDEFORM_CACHE", str(tmp_path))
    tried = 0
    for path in _data_files():
        try:
            mesh = ad.load_mesh(path)
        except ad.core.AxialDeformError:
            continue
        for rule in ("skeleton", "auto"):
            try:
                bent = mesh.with_axes(rule)
            except ad.core.MeshError as exc:
                assert str(exc) and "Traceback" not in str(exc)
                continue
            assert 1 <= bent.axis_count <= 64
            tried += 1
            pos, _ = ad.deform(bent, ad.random_params(bent, 2, seed=1, variation=ad.Variation(bend=(0.1, 0.3))))
            assert np.isfinite(pos).all(), path
    assert tried >= 60


def _obj(tmp_path, name, verts, faces, extra=""):
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in verts]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n" + extra)
    return path


CUBE_V = [(x, y, z) for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)]
CUBE_F = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1), (2, 3, 7), (2, 7, 6), (0, 2, 6),
          (0, 6, 4), (1, 5, 7), (1, 7, 3)]


def test_generated_meshes(tmp_path):
    ok = lambda p: _loads_and_deforms_or_mesh_error(p)  # noqa: E731
    assert ok(_obj(tmp_path, "one.obj", [(0, 0, 0), (1, 0, 0), (0, 0.5, 0)], [(0, 1, 2)])) == "loaded"
    cube = ad.load_mesh(_obj(tmp_path, "cube.obj", CUBE_V, CUBE_F))
    assert cube.axis.index == 0, "ties go to x"
    # a flat plane ALONG the axis is fine ...
    flat = ad.load_mesh(_obj(tmp_path, "flat.obj", [(0, 0, 0), (2, 0, 0), (2, 1, 0), (0, 1, 0)], [(0, 1, 2), (0, 2, 3)]))
    assert flat.axis.length == 2 and ok(flat.name) == "loaded"
    # ... a zero longest extent (every vertex in one point) is an error
    with pytest.raises(MeshError, match=r"point.obj: the mesh's longest extent is 0.0"):
        ad.load_mesh(_obj(tmp_path, "point.obj", [(1, 2, 3)] * 3, [(0, 1, 2)]))
    # quads and n-gons are triangulated
    ngon = tmp_path / "ngon.obj"
    ngon.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\nf 1 2 3 4\nf 4 3 5\n")
    assert ok(ngon) == "loaded" and len(ad.load_mesh(ngon).faces) == 3
    # non-manifold: three triangles on one edge, plus a degenerate (zero area) one
    nm = _obj(tmp_path, "nonmanifold.obj", [(0, 0, 0), (2, 0, 0), (1, 1, 0), (1, -1, 0), (1, 0, 1), (3, 0, 0)],
              [(0, 1, 2), (0, 1, 3), (0, 1, 4), (0, 1, 5)])
    assert ok(nm) == "loaded"
    # collinear vertices only: L > 0 but no face has an area -> default normals, still finite
    line = _obj(tmp_path, "line.obj", [(0, 0, 0), (1, 0, 0), (2, 0, 0)], [(0, 1, 2)])
    assert ok(line) == "loaded"
    # thin across the axis (1e-35 wide, 2 long) is fine: only L has a range
    assert ok(_obj(tmp_path, "thin.obj", [(x * 1e-35, y, z) for x, y, z in CUBE_V], CUBE_F)) == "loaded"
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
    with pytest.raises(MeshError, match=r"nan.obj: vertex 2 has a non-finite coordinate"):
        ad.load_mesh(tmp_path / "nan.obj")
    (tmp_path / "empty.obj").write_text("# nothing\n")
    with pytest.raises(MeshError, match="empty.obj"):
        ad.load_mesh(tmp_path / "empty.obj")
    (tmp_path / "points.obj").write_text("v 0 0 0\nv 1 0 0\n")
    with pytest.raises(MeshError, match="points.obj"):
        ad.load_mesh(tmp_path / "points.obj")


@pytest.mark.parametrize("scale", [1e30, 1e-30, 2e35, 1e-3])
def test_huge_and_tiny_coordinates(scale, tmp_path, ctx):
    """Scaled cubes load with the same unit normals as the unit cube, deform
    without NaN on the CPU and on the GPU (capture), and agree."""
    unit = ad.load_mesh(_obj(tmp_path, "unit.obj", CUBE_V, CUBE_F))
    v = [(x * scale, y * 2 * scale, z * scale) for x, y, z in CUBE_V]
    mesh = ad.load_mesh(_obj(tmp_path, "scaled.obj", v, CUBE_F))
    assert np.isfinite(mesh.axis.length) and mesh.axis.index == 1
    unit_y = ad.load_mesh(_obj(tmp_path, "unit_y.obj", [(x, 2 * y, z) for x, y, z in CUBE_V], CUBE_F))
    assert np.allclose(mesh.normals, unit_y.normals, atol=1e-6), "normals must not depend on the scale"
    assert not np.allclose(unit.normals, (0, 0, 1))
    params = ad.random_params(mesh, 5, seed=1)
    pos, nrm = deform(mesh.axis, mesh.positions, mesh.normals, params)
    assert np.isfinite(pos).all() and np.isfinite(nrm).all()
    with ad.AxialRenderer(ctx, mesh, params) as r:
        gpos, gnrm = r.capture()
    assert np.isfinite(gpos).all() and np.isfinite(gnrm).all()
    extent = np.abs(pos).max()
    assert np.abs(gpos - pos).max() <= 1e-5 * extent
    assert np.abs(gnrm - nrm).max() <= 1e-4


@pytest.mark.parametrize(
    "verts, pattern",
    [
        ([(x * 1e39, y, z) for x, y, z in CUBE_V], r"coordinate -?1e\+39, which does not fit in float32"),
        ([(x * 3e38, y, z) for x, y, z in CUBE_V], r"L=6e\+38 \(x\) is outside the supported range 1e-30..1e\+36"),
        ([(x * 1e-40, y * 1e-40, z * 1e-40) for x, y, z in CUBE_V], r"L=[0-9.]+e-40 \(x\) is outside the supported range"),
        ([(x * 1e-32, y * 1e-32, z * 1e-32) for x, y, z in CUBE_V], r"L=2e-32 \(x\) is outside"),
    ],
    ids=["coordinate-overflow", "extent-overflow", "subnormal-extent", "too-small"],
)
def test_coordinates_float32_cannot_hold(verts, pattern, tmp_path):
    with pytest.raises(MeshError, match=pattern) as exc:
        ad.load_mesh(_obj(tmp_path, "big.obj", verts, CUBE_F))
    assert "big.obj" in str(exc.value)
    with pytest.raises(MeshError, match=pattern):  # BaseMesh from arrays checks the same
        make_mesh(np.array(verts), np.array(CUBE_F), name="arrays")


def test_glb_with_several_meshes_and_garbage_files(tmp_path):
    import trimesh

    scene = trimesh.Scene([trimesh.creation.box(), trimesh.creation.icosphere(subdivisions=1)])
    scene.export(tmp_path / "two.glb")
    two = ad.load_mesh(tmp_path / "two.glb")  # several meshes: one base mesh with one part each
    assert len(two.parts) == 2 and two.vertex_count == 8 + 42
    for suffix in (".glb", ".gltf", ".stl", ".ply", ".obj", ".off"):
        bad = tmp_path / f"garbage{suffix}"
        bad.write_bytes(np.random.default_rng(1).bytes(2000))
        assert _loads_and_deforms_or_mesh_error(bad) == "error"
    with pytest.raises(MeshError, match=r"params.adp: unsupported mesh file type '.adp'; expected one of .obj"):
        ad.load_mesh(tmp_path / "params.adp") if (tmp_path / "params.adp").write_bytes(FLOAT_FILE) else None


# ---------------------------------------------------------- actionable errors


def test_no_gl_context_says_what_to_install(monkeypatch):
    import moderngl

    def fail(*a, **k):
        raise moderngl.Error("eglInitialize failed (0x3001)")

    monkeypatch.setattr(moderngl, "create_standalone_context", fail)
    with pytest.raises(ad.core.ContextError, match="libegl1 libgl1-mesa-dri") as exc:
        ad.create_context()
    assert "eglInitialize failed" in str(exc.value)


def test_broken_shader_names_file_stage_and_line(ctx):
    from axialdeform.gl.shaders import assemble, build_program, shader_source

    files = {
        "broken.vert": '#include "helper.glsl"\nin vec3 in_position;\nvoid main() {\n    gl_Position = vec4(in_position, 1.0)\n}\n',
        "helper.glsl": "float helper(float x) { return x * 2.0; }\n",
    }
    loader = lambda name: files[name] if name in files else shader_source(name)  # noqa: E731
    assembled = assemble("broken.vert", loader=loader)
    assert assembled.files == ["broken.vert", "helper.glsl"]
    with pytest.raises(ShaderError) as exc:
        build_program(ctx, "broken.vert", loader=loader)
    msg = str(exc.value)
    assert "glsl/broken.vert, line 5" in msg and "vertex shader" in msg, msg
    # an error inside the included file is reported in that file
    files["helper.glsl"] = "float helper(float x) {\n    return y;\n}\n"
    files["broken.vert"] = files["broken.vert"].replace("1.0)\n", "1.0);\n")
    with pytest.raises(ShaderError, match=r"glsl/helper.glsl, line 2 \(vertex shader\)"):
        build_program(ctx, "broken.vert", loader=loader)


def test_include_cycle_and_missing_include():
    from axialdeform.gl.shaders import assemble

    files = {"a.glsl": '#include "b.glsl"\n', "b.glsl": '#include "a.glsl"\n'}
    with pytest.raises(ShaderError, match=r"#include cycle: a.glsl -> b.glsl -> a.glsl"):
        assemble("a.glsl", loader=files.__getitem__)
    with pytest.raises(ShaderError, match=r"glsl/nope.glsl: no such shader file"):
        assemble("nope.glsl")


def test_wrong_mesh_for_parameter_file(tmp_path, stone, leaf):
    path = ad.write_params(tmp_path / "stones.adp", ad.random_params(stone, 3, seed=1), stone)
    with pytest.raises(ad.core.MeshMismatchError, match=r"stones.adp: made for .*load the mesh as it was made for"):
        ad.read_params(path, leaf)
    assert ad.read_params(path, leaf, allow_mesh_mismatch=True).shape == (3, 16)


def _cli(argv, capsys):
    from axialdeform.cli import main

    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    return code, err


def test_cli_errors_exit_2_with_one_line(tmp_path, capsys, stone):
    stones = ad.write_params(tmp_path / "stones.adp", ad.random_params(stone, 3, seed=1), stone)
    garbage = tmp_path / "garbage.adp"
    garbage.write_bytes(FLOAT_FILE[:100])
    nanfile = tmp_path / "nan.txt"
    nanfile.write_text(ROW.replace("1.5", "nan", 1))
    cases = [
        (["render", "leaf", stones, "-o", tmp_path / "x.png"], "load the mesh as it was made for"),
        (["info", garbage], "garbage.adp: count: the header declares 3 instances"),
        (["info", nanfile], "nan.txt: line 1, field d1u: expected a finite number"),
        (["render", stones, stones, "-o", tmp_path / "x.png"], "unsupported mesh file type '.adp'"),
        (["random", "stone", "-n", "3", "-o", tmp_path / "p.png"], "unknown parameter file type '.png'"),
        (["convert", garbage, tmp_path / "out.txt"], "garbage.adp"),
    ]
    for argv, expected in cases:
        code, err = _cli(argv, capsys)
        assert code == 2, (argv, err)
        assert err.count("\n") == 1 and expected in err and "Traceback" not in err, err
    assert not (tmp_path / "x.png").exists()


def test_cli_subprocess_has_no_traceback(tmp_path):
    garbage = tmp_path / "garbage.txt"
    garbage.write_bytes(b"\xff\xfe garbage")
    res = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(garbage)], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and "Traceback" not in res.stderr and "not UTF-8" in res.stderr

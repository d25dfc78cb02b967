"""Hostile input, round two: huge outputs made and written in
pieces, bounded by disk rather than memory, and files a glTF refers to read
with the size it declares.

Every test here failed on the code before (a missing API, memory growing
with the count, a file written where the disk could not hold it, a buffer
of any size read), except two guards: the golden files of ``random`` (the
pieces give byte for byte the files the whole-array code wrote; they fail
before only for want of ``RANDOM_CHUNK``) and a buffer of its declared size
still loading.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.cli import main
from axialdeform.core.errors import MeshError, ParamError
from axialdeform.core.io import params as P
from axialdeform.core.quantize import quantization_error_bound
from axialdeform.core.variation import iter_random_params

from helpers.memory import peak_rss_mb

ROOT = Path(__file__).resolve().parents[2]


# ------------------------------------------------------------------ random


@pytest.mark.parametrize("placement", ["grid", "disc", "box"])
@pytest.mark.parametrize("extra", [{}, {"scale": (0.5, 2.0), "twist": 1.0, "taper": 0.3}])
def test_pieces_are_the_whole_array_bit_for_bit(placement, extra):
    leaf = ad.load_mesh("leaf")
    whole = ad.random_params(leaf, 1001, 7, ad.Variation(**extra), placement=placement, up="z")
    for chunk in (1, 97, 1000, 1001, 5000):
        pieces = list(iter_random_params(leaf, 1001, 7, ad.Variation(**extra), chunk=chunk, placement=placement, up="z"))
        assert max(len(p) for p in pieces) <= chunk
        assert np.concatenate(pieces).tobytes() == whole.tobytes()
    assert list(iter_random_params(leaf, 0, 7, ad.Variation(**extra))) == []


def test_iter_random_params_refuses_bad_options_at_once():
    stone = ad.load_mesh("stone")
    with pytest.raises(ParamError, match="placement"):
        iter_random_params(stone, 10, placement="spiral")  # before the first piece is asked for
    with pytest.raises(ParamError, match="chunk"):
        iter_random_params(stone, 10, chunk=0)


#: SHA-256 of ``random stone -n 1000 --seed 5 -o NAME [ARGS]`` written by the
#: code before the pieces (the whole (n, 16|19) array at once)
EXT = ["--scale", "0.5:2", "--twist", "1", "--taper", "0.3"]
GOLDEN = [
    ("g.txt", [], "cf2eb627d16a227843625623a6d56de670592e0660d0fc38167862a4bcf2d07c"),
    ("g.adp", [], "c4dd71d244265a41940015570a2a535f223f6ef4c138869d5882a8222b7eb5b5"),
    ("gq.adp", ["--quantize"], "0149d15396538012a7214bc903ce75236f9b48d2edee7579c93dec9914c34bdd"),
    ("ge.txt", EXT, "1461130ebf9f9da77e75a325ae42955d8c76da468db46302395d83fc1ef665b2"),
    ("ge.adp", EXT, "f61a6f45ff8934d30a4b16c3c26d8574dd37b394a3da07ee7298f4ed94f387db"),
    ("geq.adp", ["--quantize", *EXT], "00c1d03df2d1e14a37984e7cec57bf87648b0ac99b945a0244661e4e00b5d4e6"),
]


@pytest.mark.parametrize("name,args,digest", GOLDEN, ids=[g[0] for g in GOLDEN])
def test_random_in_pieces_writes_the_same_file_as_before(tmp_path, monkeypatch, capsys, name, args, digest):
    from axialdeform.cli import random as random_cli

    monkeypatch.setattr(random_cli, "RANDOM_CHUNK", 64)  # 16 pieces; the quantized table spans them all
    monkeypatch.chdir(tmp_path)
    assert main(["random", "stone", "-n", "1000", "--seed", "5", "-o", name, *args]) == 0
    data = (tmp_path / name).read_bytes()
    assert hashlib.sha256(data).hexdigest() == digest
    # and the same as the in-memory encoder of the whole array
    stone = ad.load_mesh("stone")
    kw = {"scale": (0.5, 2.0), "twist": 1.0, "taper": 0.3} if args[-6:] == EXT else {}
    whole = ad.random_params(stone, 1000, 5, ad.Variation(**kw))
    if name.endswith(".adp"):
        assert data == P.encode_binary(whole, axis=stone.axis, mesh_fingerprint=stone.fingerprint,
                                       quantize="--quantize" in args)
    else:
        assert np.array_equal(P.parse_text(data), whole)


def test_random_checks_free_disk_space_first(tmp_path, monkeypatch, capsys):
    from axialdeform.core.io import safeio

    out = tmp_path / "p.adp"
    monkeypatch.setattr(safeio, "disk_free", lambda path: 100_000)
    assert main(["random", "stone", "-n", "5000", "-o", str(out)]) == 2  # 320 KB: before, written (or disk full)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert str(out) in err[0] and "needs 320100 bytes" in err[0] and "100000 bytes free" in err[0]
    assert "-n/--count at most 1560" in err[0]  # (100000 - 100) // 64
    assert not out.exists()
    assert main(["random", "stone", "-n", "1560", "-o", str(out)]) == 0
    assert out.stat().st_size == P.param_file_bytes(out, 1560) == 1560 * 64 + 100
    # text: an upper bound (every number at its longest)
    assert main(["random", "stone", "-n", "400", "-o", str(tmp_path / "p.txt")]) == 2
    assert "-n/--count at most 358" in capsys.readouterr().err  # (100000 - 8192) // 256
    # a wrong file type is said first, whatever the disk
    assert main(["random", "stone", "-n", "400", "-o", str(tmp_path / "p.png")]) == 2
    assert "unknown parameter file type '.png'" in capsys.readouterr().err


def test_random_count_maximum_is_gl_not_memory(tmp_path, capsys):
    out = tmp_path / "p.adp"
    assert main(["random", "stone", "-n", str(2**31), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "expected at most 2147483647 instances" in err and not out.exists()
    assert main(["random", "stone", "-n", "-1", "-o", str(out)]) == 2
    assert "expected 0 or more instances" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("extra", [[], ["--quantize"]], ids=["float32", "quantized"])
def test_random_memory_does_not_grow_with_the_count(tmp_path, extra):
    """-n 1 200 000 peaks where -n 300 000 does (both several pieces): before,
    the whole array and its copies (about 700 B an instance: +600 MB here)."""
    small = peak_rss_mb(["random", "stone", "-n", 300_000, "--twist", "1", "-o", tmp_path / "a.adp", *extra])
    big = peak_rss_mb(["random", "stone", "-n", 1_200_000, "--twist", "1", "-o", tmp_path / "b.adp", *extra])
    assert big - small < 40, (small, big)
    assert (tmp_path / "b.adp").stat().st_size == P.param_file_bytes("b.adp", 1_200_000, 19, quantize=bool(extra))


# ----------------------------------------------------------------- writers


def test_write_param_chunks_refuses_pieces_that_do_not_add_up(tmp_path):
    path = tmp_path / "p.adp"
    old = P.write_params(path, np.zeros((3, 16), np.float32)).read_bytes()
    v = np.ones((10, 16), np.float32)
    for count in (9, 11):
        with pytest.raises(ParamError, match=f"expected {count}"):
            P.write_param_chunks(path, lambda: (v[:5], v[5:]), count)
        assert path.read_bytes() == old  # the old file is untouched, no temporary left
    with pytest.raises(ParamError, match="19"):
        P.write_param_chunks(path, lambda: (v,), 10, 19)
    bad = v.copy()
    bad[7, 3] = np.nan
    with pytest.raises(ParamError, match="instance 7, field d2v"):  # numbered in the whole file, not the piece
        P.write_param_chunks(path, lambda: (bad[:5], bad[5:]), 10, quantize=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.adp"]


@pytest.mark.slow
def test_quantized_writer_memory_is_bounded(tmp_path):
    """The quantized .adp writer encodes in pieces: beyond the values, its
    peak does not grow with the count (before: float64 copies and the whole
    encoded file in memory, about 16 times the values' size)."""
    values = np.random.default_rng(3).normal(size=(600_000, 16)).astype(np.float32)  # 38 MB
    tracemalloc.start()
    P.write_params(tmp_path / "q.adp", values, quantize=True)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 0.75 * values.nbytes, peak
    pf = P.read_param_file(tmp_path / "q.adp")
    assert pf.encoding == "uint16-quantized"
    assert np.all(np.abs(pf.values - values) <= quantization_error_bound(values))


@pytest.mark.slow
def test_bake_npz_writer_makes_no_copy(tmp_path):
    from axialdeform.core.io.bake import write_npz

    positions = np.zeros((400, 20_000, 3), np.float32)  # 96 MB each
    normals = np.ones((400, 20_000, 3), np.float32)
    tracemalloc.start()
    write_npz(tmp_path / "b.npz", positions, normals)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 0.6 * positions.nbytes, peak  # before: float32 copies of both (2x)
    with np.load(tmp_path / "b.npz") as z:
        assert z["positions"].shape == positions.shape and z["normals"][5, 7, 2] == 1


# -------------------------------------------------------------------- glTF


TRIANGLE = np.array([0, 0, 0, 1, 0, 0, 0, 1, 0], "<f4").tobytes()


def _gltf(folder: Path, byte_length, content: bytes, images=()) -> Path:
    gltf = folder / "t.gltf"
    gltf.write_text(json.dumps({
        "asset": {"version": "2.0"}, "buffers": [{"uri": "data.bin", "byteLength": byte_length}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "images": [{"uri": u} for u in images],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}))
    (folder / "data.bin").write_bytes(content)
    return gltf


@pytest.mark.parametrize("content,found", [(TRIANGLE[:30], "is 30 bytes"), (TRIANGLE + bytes(4), "is 40 bytes"),
                                           (TRIANGLE + bytes(1 << 20), "is 1048612 bytes")],
                         ids=["smaller", "larger", "much-larger"])
def test_gltf_buffer_must_be_its_declared_size(tmp_path, content, found):
    gltf = _gltf(tmp_path, 36, content)
    with pytest.raises(MeshError) as info:
        ad.load_mesh(gltf)
    msg = str(info.value)
    assert msg.startswith(f"{gltf}: data.bin: {found}")  # the file, what it is
    assert "buffers[0].byteLength = 36" in msg and "expected a file of exactly 36 bytes" in msg  # field, expectation


def test_gltf_buffer_of_declared_size_loads_padding_allowed(tmp_path):
    assert ad.load_mesh(_gltf(tmp_path, 36, TRIANGLE)).vertex_count == 3
    assert ad.load_mesh(_gltf(tmp_path, 36, TRIANGLE + bytes(3))).vertex_count == 3  # padding to 4 bytes


def test_gltf_buffer_read_is_bounded_by_the_declaration(tmp_path, monkeypatch):
    """A huge buffer file is refused from its size alone: never read."""
    from axialdeform.core.io import safeio

    gltf = _gltf(tmp_path, 36, b"")
    with open(tmp_path / "data.bin", "wb") as fh:  # sparse: 8 GB that take no disk
        fh.truncate(8 << 30)
    reads = []
    real = safeio.read_sized
    monkeypatch.setattr(safeio, "read_sized", lambda *a, **k: reads.append(str(a[2])) or real(*a, **k))
    with pytest.raises(MeshError, match="is 8589934592 bytes, but t.gltf declares buffers"):
        ad.load_mesh(gltf)
    assert reads == [str(gltf)]  # the glTF itself, never its buffer


@pytest.mark.parametrize("value", [0, -5, "36", 1.5, None])
def test_gltf_buffer_byte_length_must_be_a_whole_number(tmp_path, value):
    gltf = _gltf(tmp_path, value, TRIANGLE)
    with pytest.raises(MeshError, match=r"t.gltf: buffers\[0\].byteLength: expected a whole number of bytes >= 1"):
        ad.load_mesh(gltf)


def test_gltf_image_over_the_cap_is_not_read(tmp_path, monkeypatch):
    """A picture is bounded by MAX_IMAGE_BYTES: over it, the mesh still
    loads without that texture (the loader's warning names the file)."""
    from axialdeform.core.io import safeio

    monkeypatch.setattr(safeio, "MAX_IMAGE_BYTES", 100)
    (tmp_path / "tex").write_bytes(bytes(101))  # no suffix: known as a picture from images[0].uri alone
    gltf = _gltf(tmp_path, 36, TRIANGLE, images=["tex"])
    from axialdeform.core.io.resolver import SafeResolver, gltf_json, gltf_references

    declared = gltf_references(gltf_json(gltf.read_bytes(), "gltf", "t.gltf"))
    assert declared == {"data.bin": ("buffers[0].byteLength", 36), "tex": ("images[0].uri", None)}
    resolver = SafeResolver(tmp_path, declared=declared, referrer="t.gltf")
    with pytest.raises(OSError, match="tex: is 101 bytes; expected a picture referred to by t.gltf"):
        resolver.get("tex")
    from axialdeform.core.material import AssetWarning

    with pytest.warns(AssetWarning, match="tex: is 101 bytes; expected a picture referred to by t.gltf"):
        assert ad.load_mesh(gltf).vertex_count == 3  # refused picture: not a refused mesh


# -------------------------------------------------------------------- bake


def test_bake_cpu_pieces_are_the_whole_bake(tmp_path):
    from axialdeform.core.bake import bake_cpu, bake_cpu_pieces
    from axialdeform.core.io.bake import write_npz_pieces

    stone = ad.load_mesh("stone")
    params = ad.random_params(stone, 503, 3, variation=ad.Variation(bend=0.2))
    wind = ad.Wind(strength=0.2)  # its phase follows the instance index: the pieces must know where they start
    positions, normals = bake_cpu(stone, params, wind=wind, time=0.7)
    pieces = bake_cpu_pieces(stone, params, wind=wind, time=0.7, piece_bytes=50_000)  # 35 instances a piece
    write_npz_pieces(tmp_path / "b.npz", pieces, 503, stone.vertex_count)
    with np.load(tmp_path / "b.npz") as z:
        assert z["positions"].tobytes() == positions.tobytes() and z["normals"].tobytes() == normals.tobytes()
    with pytest.raises(ad.AxialDeformError, match="expected 504"):
        write_npz_pieces(tmp_path / "c.npz", bake_cpu_pieces(stone, params), 504, stone.vertex_count)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.npz"]  # no archive, no spool left


def test_bake_npz_refuses_a_disk_too_small_and_names_a_bad_instance(tmp_path, monkeypatch, capsys):
    from axialdeform.core.io import safeio

    f = tmp_path / "p.adp"
    values = ad.random_params(ad.load_mesh("stone"), 1000, 1)
    P.write_params(f, values)
    out = tmp_path / "b.npz"
    monkeypatch.setattr(safeio, "disk_free", lambda path: 1_000_000)  # 1000 x 58 x 36 B = 2.1 MB needed
    assert main(["bake", "stone", str(f), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(out) in err[0] and "needs 2153536 bytes" in err[0] and "1000000 bytes free" in err[0]
    monkeypatch.undo()
    values[700, 0:10], values[700, 13:16] = 3.4e38, 0.7  # finite, but turned 40 degrees they overflow float32
    P.write_params(f, values)
    assert main(["bake", "stone", str(f), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{f}: instance 700, field" in err and not out.exists()


@pytest.mark.slow
def test_bake_npz_memory_does_not_grow_with_the_count(tmp_path):
    """A CPU bake to .npz is made and written in pieces: 40 000 instances
    (111 MB of output) peak where 10 000 do (before: the whole result, and
    a copy of it while writing)."""
    peaks = []
    for n in (10_000, 40_000):
        params = tmp_path / f"p{n}.adp"
        P.write_params(params, ad.random_params(ad.load_mesh("stone"), n, 2))
        peaks.append(peak_rss_mb(["bake", "stone", params, "-o", tmp_path / f"b{n}.npz"]))
        with np.load(tmp_path / f"b{n}.npz") as z:
            assert z["normals"].shape == (n, 58, 3)
    assert peaks[1] - peaks[0] < 30, peaks


def test_gpu_bake_pieces_are_the_whole_capture(ctx, tmp_path):
    from axialdeform.core.io.bake import write_npz_pieces
    from axialdeform.gl.bake import bake, bake_pieces

    stone = ad.load_mesh("stone")
    params = ad.random_params(stone, 301, 4, variation=ad.Variation(bend=0.2))
    wind = ad.Wind(strength=0.2)
    positions, normals = bake(stone, params, "gpu", ctx=ctx, options=ad.RenderOptions(wind=wind, time=0.4))
    pieces = bake_pieces(stone, params, "gpu", ctx=ctx, options=ad.RenderOptions(wind=wind, time=0.4), piece_bytes=20_000)  # 14 a piece
    write_npz_pieces(tmp_path / "g.npz", pieces, 301, stone.vertex_count)
    with np.load(tmp_path / "g.npz") as z:
        assert z["positions"].tobytes() == positions.tobytes() and z["normals"].tobytes() == normals.tobytes()
    assert ctx.error == "GL_NO_ERROR"


@pytest.mark.slow
def test_scene_export_baked_streams_its_layers(tmp_path):
    """``export SCENE --baked`` hands each layer's arrays to the GLB writer as
    they are and streams them (before: trimesh's exporter, 5.7x the output)."""
    import trimesh

    sys.path.insert(0, str(ROOT / "tools"))
    from big_mesh import torus

    pos, faces = torus(300_000)
    trimesh.Trimesh(pos, faces, process=False).export(tmp_path / "torus.ply")
    mesh = ad.load_mesh(tmp_path / "torus.ply")
    ad.write_params(tmp_path / "p.adp", ad.random_params(mesh, 30, seed=1), mesh)
    (tmp_path / "s.toml").write_text('[[layer]]\nname = "tori"\nmesh = "torus.ply"\nparams = "p.adp"\n')
    peak = peak_rss_mb(["export", tmp_path / "s.toml", "--baked", "-o", tmp_path / "s.glb"])
    out_mb = (tmp_path / "s.glb").stat().st_size / 2**20
    assert out_mb > 150
    assert peak < 2.2 * out_mb + 250, (peak, out_mb)


@pytest.mark.slow
def test_baked_obj_files_hold_every_float32(tmp_path):
    """The plain-mesh OBJ writer: positions and normals read back as the same
    float32 numbers, the triangles as they are."""
    import trimesh

    from axialdeform.core.bake import instance_name

    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 3, seed=2, variation=ad.Variation(bend=0.2))
    ad.write_params(tmp_path / "p.adp", params, mesh)
    assert main(["bake", "stone", str(tmp_path / "p.adp"), "-o", str(tmp_path / "objs"), "--format", "obj"]) == 0
    pos, nrm = ad.deform(mesh.axis, mesh.positions, mesh.normals, params)
    for k in range(3):
        back = trimesh.load(tmp_path / "objs" / instance_name(k, 3, ".obj"), process=False)
        assert np.array_equal(back.vertices.astype(np.float32), pos[k])
        assert np.array_equal(back.faces, mesh.faces)
        assert np.array_equal(back.vertex_normals.astype(np.float32), nrm[k]) or \
            np.abs(back.vertex_normals - nrm[k]).max() < 1e-6

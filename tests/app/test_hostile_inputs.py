"""Hostile input, round two: bounded reads, memory proportional to
the input, outputs that never destroy an input, no non-finite result
written, sizes the GL can make, lazy wireframe edges, one-line CLI errors
that name their file, and API misuse inside the error family.

Every test here failed on the code before these checks (a hang caught by a
subprocess timeout, a traceback, a destroyed input, a file written with
exit 0, an exception outside ``AxialDeformError``, or a missing API),
except ``test_edges_same_as_unique_rows``, a guard that the faster edge
code gives exactly the old result.
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

import axialdeform as ad
from axialdeform.cli import main
from axialdeform.core.errors import ArgumentError, AxialDeformError, ContextError, ParamFileError, PathError
from axialdeform.core.io import params as P
from axialdeform.gl.buffers import InstanceBuffer

ROOT = Path(__file__).resolve().parents[2]
ROW = " ".join(["0.01"] * 10 + ["0", "0", "0", "0", "0", "0"]) + "\n"


def run_cli(*args, timeout=60, cwd=None):
    """The CLI in a child process (a hang is a timeout, not a stuck test run)."""
    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd, env={**os.environ, "PYTHONPATH": str(ROOT)})


def one_error_line(proc, *needles):
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr and "Warning" not in proc.stderr
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


# ------------------------------------------------------- 1. bounded reads


def test_info_refuses_a_fifo_without_blocking(tmp_path):
    fifo = tmp_path / "p.adp"
    os.mkfifo(fifo)
    proc = run_cli("info", fifo, timeout=30)  # before: blocked forever in read_bytes
    one_error_line(proc, str(fifo), "not a regular file")


def test_info_refuses_a_symlink_to_a_device(tmp_path):
    link = tmp_path / "p.txt"
    link.symlink_to("/dev/null")  # /dev/zero would be the attack; /dev/null shows the check without the risk
    proc = run_cli("info", link, timeout=30)
    one_error_line(proc, str(link), "character device")


def _obj_with_mtllib(folder: Path) -> Path:
    obj = folder / "m.obj"
    obj.write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n")
    return obj


@pytest.mark.slow
def test_files_a_mesh_refers_to_are_checked(tmp_path):
    obj = _obj_with_mtllib(tmp_path)
    os.mkfifo(tmp_path / "m.mtl")  # before: trimesh's resolver blocked forever opening it
    code = f"import axialdeform as ad\ntry:\n    ad.load_mesh({str(obj)!r})\nexcept ad.core.MeshError as e:\n    print('ERR', e)\n"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.stdout.startswith("ERR "), proc.stdout + proc.stderr
    assert str(obj) in proc.stdout and "m.mtl" in proc.stdout and "not a regular file" in proc.stdout


@pytest.mark.slow
def test_gltf_buffer_must_be_a_regular_file_of_bounded_size(tmp_path):
    import json

    gltf = tmp_path / "t.gltf"
    gltf.write_text(json.dumps({
        "asset": {"version": "2.0"}, "buffers": [{"uri": "data.bin", "byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}))
    os.mkfifo(tmp_path / "data.bin")  # before: blocked forever opening it
    code = f"import axialdeform as ad\ntry:\n    ad.load_mesh({str(gltf)!r})\nexcept ad.core.MeshError as e:\n    print('ERR', e)\n"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.stdout.startswith("ERR ") and "data.bin: not a regular file" in proc.stdout, proc.stdout + proc.stderr
    (tmp_path / "data.bin").unlink()
    (tmp_path / "data.bin").write_bytes(np.array([0, 0, 0, 1, 0, 0, 0, 1, 0], "<f4").tobytes())
    assert ad.load_mesh(gltf).vertex_count == 3
    from axialdeform.core.io.resolver import SafeResolver

    (tmp_path / "other.mtl").write_bytes(b"x" * 11)
    with pytest.raises(OSError, match="at most 10 bytes"):
        SafeResolver(tmp_path, max_bytes=10).get("other.mtl")


def test_read_regular_refuses_files_over_the_bound(tmp_path):
    from axialdeform.core.io.safeio import read_regular

    f = tmp_path / "a.bin"
    f.write_bytes(b"x" * 100)
    assert read_regular(f, 100) == b"x" * 100
    with pytest.raises(PathError, match="100 bytes; expected thing of at most 99"):
        read_regular(f, 99, "thing")


def test_binary_header_checked_before_the_payload_is_read(tmp_path, monkeypatch):
    """A header that disagrees with the file's size is refused after reading 96 bytes."""
    data = bytearray(P.encode_binary(np.zeros((1000, 16), np.float32)))
    data[16:24] = struct.pack("<Q", 2**40)
    f = tmp_path / "big.adp"
    f.write_bytes(bytes(data))
    tracemalloc.start()
    with pytest.raises(ParamFileError, match="declares 1099511627776 instances"):
        P.read_param_file(f)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 16 * 1024, peak  # before: the whole 64 KB file was read first


# ------------------------------------------------- 2. memory ~ input


@pytest.mark.slow
def test_text_parser_memory(tmp_path):
    """Peak of reading a ~20 MB text file < 3x its size + the result (before: about 27x)."""
    rng = np.random.default_rng(16)
    block = rng.normal(scale=5, size=(1000, 16)).astype(np.float32)
    f = tmp_path / "big.txt"
    P.write_params(f, block)
    body = f.read_bytes()
    f.write_bytes(body * 100)  # 100 000 lines (comment lines repeat too)
    values = np.tile(block, (100, 1))
    size = f.stat().st_size
    assert size > 15e6
    tracemalloc.start()
    out = P.read_params(f)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert np.array_equal(out, values)
    assert peak < 3 * size + out.nbytes, (peak, size)


def test_one_huge_line_is_refused_in_bounded_memory(tmp_path):
    """A 40 MB line: refused after reading the file once (before: about 4x the file)."""
    f = tmp_path / "line.txt"
    f.write_bytes(b"1" * 40_000_000)
    tracemalloc.start()
    with pytest.raises(ParamFileError, match="line 1 is longer than"):
        P.read_param_file(f)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 1.2 * f.stat().st_size, peak


@pytest.mark.slow
def test_text_writer_memory(tmp_path):
    """The text writer formats in pieces: its peak does not grow with the count."""
    values = np.random.default_rng(1).normal(size=(24_000, 16)).astype(np.float32)
    tracemalloc.start()
    P.write_params(tmp_path / "p.txt", values)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 30e6, peak  # before: ~3 KB an instance (72 MB here)
    assert np.array_equal(P.read_params(tmp_path / "p.txt"), values)


def test_random_count_checked_before_allocating(tmp_path, capsys):
    out = tmp_path / "p.adp"
    assert main(["random", "stone", "-n", "1000000000000", "-o", str(out)]) == 2  # before: MemoryError traceback
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "-n/--count" in err[0] and "expected at most" in err[0]
    assert not out.exists()


def test_bake_count_checked_before_allocating(tmp_path, monkeypatch, capsys):
    from axialdeform.core.io import safeio

    f = tmp_path / "p.adp"
    P.write_params(f, np.zeros((1000, 16), np.float32))
    monkeypatch.setattr(safeio, "memory_available", lambda: 1_000_000)  # 1 MB: 1000 x 58 vertices x 24 B does not fit
    # a folder of meshes is baked in memory (a CPU .npz is made in pieces, tests/app/test_streaming.py)
    assert main(["bake", "stone", str(f), "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "instances to bake" in err and "expected at most" in err and str(f) in err


def test_check_count_says_the_maximum():
    from axialdeform.core.io.safeio import MAX_INSTANCES, check_count

    assert check_count(10, 100, budget=1000) == 10
    with pytest.raises(AxialDeformError, match=r"expected at most 10 .*never more than " + str(MAX_INSTANCES)):
        check_count(11, 100, budget=1000)
    for bad in (-1, 1.5, "3", None):
        with pytest.raises(AxialDeformError):
            check_count(bad, 1)


# ------------------------------------------------------------ 3. outputs


@pytest.fixture
def files(tmp_path):
    params = tmp_path / "p.adp"
    P.write_params(params, ad.random_params(ad.load_mesh("stone"), 4, 1), ad.load_mesh("stone"))
    mesh = tmp_path / "m.obj"
    mesh.write_bytes(ad.core.bundled_mesh_path("stone").read_bytes())
    return tmp_path, mesh, params


def test_output_that_is_an_input_is_refused(files, capsys):
    tmp, mesh, params = files
    before = {p: p.read_bytes() for p in (mesh, params)}
    for argv in (["render", mesh, params, "-o", params, "--size", "32x32"],
                 ["render", mesh, params, "-o", mesh, "--size", "32x32"],
                 ["bake", mesh, params, "-o", params],
                 ["export", mesh, params, "-o", tmp / "x.glb"],  # a sane one in between
                 ["convert", params, tmp / "." / params.name],
                 ["random", mesh, "-n", "3", "-o", mesh]):
        status = main([str(a) for a in argv])
        err = capsys.readouterr().err
        if "x.glb" in str(argv[-1]):
            assert status == 0
            continue
        assert status == 2 and "refusing to overwrite an input" in err, (argv, err)
    for p, data in before.items():
        assert p.read_bytes() == data  # before: replaced by a PNG


def test_scene_file_output_that_is_the_scene_is_refused(tmp_path, capsys):
    """``render``/``export`` of a scene file never write over the scene file itself."""
    stone = ad.load_mesh("stone")
    ad.write_params(tmp_path / "p.adp", ad.random_params(stone, 3, seed=1), stone)
    scene = tmp_path / "scene.toml"
    scene.write_text('[[layer]]\nname = "stones"\nmesh = "stone"\nparams = "p.adp"\n')
    before = scene.read_bytes()
    (tmp_path / "link.glb").symlink_to(scene)
    for argv in (["render", scene, "-o", scene, "--size", "16x16"], ["export", scene, "-o", tmp_path / "link.glb"]):
        assert main([str(a) for a in argv]) == 2, argv
        assert "refusing to overwrite an input" in capsys.readouterr().err, argv
    assert scene.read_bytes() == before
    assert main(["render", str(scene), "-o", str(tmp_path / "ok.png"), "--size", "16x16"]) == 0  # a sane one


def test_bundled_mesh_is_an_input_too(tmp_path, capsys):
    """``demo`` and ``render stone`` read the package's stone.obj: never replaced by their output."""
    stone = ad.core.bundled_mesh_path("stone")
    before = stone.read_bytes()
    params = tmp_path / "p.adp"
    P.write_params(params, np.zeros((1, 16), np.float32))
    assert main(["demo", "-o", str(stone), "-n", "2", "--size", "16x16"]) == 2  # before: stone.obj became a PNG
    assert main(["render", "stone", str(params), "-o", str(stone), "--size", "16x16"]) == 2
    assert capsys.readouterr().err.count("refusing to overwrite an input") == 2
    assert stone.read_bytes() == before


def test_output_link_to_input_is_refused(files, capsys):
    tmp, mesh, params = files
    (tmp / "link.png").symlink_to(params)
    assert main(["render", str(mesh), str(params), "-o", str(tmp / "link.png"), "--size", "32x32"]) == 2
    assert "refusing to overwrite an input" in capsys.readouterr().err


def test_non_regular_outputs_are_refused(files, capsys):
    tmp, mesh, params = files
    fifo = tmp / "out.png"
    os.mkfifo(fifo)
    (tmp / "null.png").symlink_to("/dev/null")
    for out in (fifo, tmp / "null.png", "/dev/null"):
        assert main(["render", str(mesh), str(params), "-o", str(out), "--size", "32x32"]) == 2
        err = capsys.readouterr().err
        assert "not a regular file" in err, err
    assert fifo.is_fifo()  # before: replaced by a regular file
    assert os.readlink(tmp / "null.png") == "/dev/null"
    from axialdeform.core.io.atomic import atomic_write_bytes

    with pytest.raises(PathError, match="FIFO"):
        atomic_write_bytes(fifo, b"x")


def test_bake_folder_with_files_needs_overwrite(files, capsys):
    tmp, mesh, params = files
    out = tmp / "baked"
    assert main(["bake", str(mesh), str(params), "-o", str(out)]) == 0
    capsys.readouterr()
    (out / "instance_000099.obj").write_text("stale\n")
    (out / "notes.txt").write_text("mine\n")
    assert main(["bake", str(mesh), str(params), "-o", str(out)]) == 2  # before: wrote 4 beside the stale ones
    assert "--overwrite" in capsys.readouterr().err
    huge = _huge(tmp)
    assert main(["bake", str(mesh), str(huge), "-o", str(out), "--overwrite", "--ignore-mesh-mismatch"]) == 2
    assert len(list(out.iterdir())) == 6  # a failed bake removed nothing
    assert main(["bake", str(mesh), str(params), "-o", str(out), "--overwrite"]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == [f"instance_{i:06d}.obj" for i in range(4)] + ["notes.txt"]


# ---------------------------------------------------------- 4. non-finite


def _huge(tmp_path) -> Path:
    f = tmp_path / "huge.txt"
    f.write_text(" ".join(["3.4e38"] * 13 + ["0.7"] * 3) + "\n")
    return f


@pytest.mark.parametrize("engine", ["cpu", "gpu"])
def test_bake_refuses_non_finite_results(tmp_path, capsys, engine):
    huge = _huge(tmp_path)
    out = tmp_path / "b.npz"
    assert main(["bake", "stone", str(huge), "-o", str(out), "--engine", engine]) == 2  # before: exit 0, inf written
    err = capsys.readouterr().err.strip().splitlines()[-1]
    # refused before anything is made, as render refuses it: the drawable bound (before it, the baked vertices' check)
    assert str(huge) in err and "instance 0" in err and "expected at most 1e+18" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_export_refuses_non_finite_results(tmp_path, capsys):
    huge = _huge(tmp_path)
    out = tmp_path / "b.glb"
    assert main(["export", "stone", str(huge), "-o", str(out)]) == 2  # before: JSON writer traceback
    err = capsys.readouterr().err
    assert "instance 0, field d1u" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_capture_refuses_non_finite_results(ctx, stone):
    params = np.zeros((3, 16), np.float32)
    params[2] = [3.4e38] * 13 + [0.7] * 3
    with ad.AxialRenderer(ctx, stone, params) as r:
        r.capture(0, 2)  # finite instances are fine
        with pytest.raises(AxialDeformError, match=r"instance 2, positions \(vertex \d+, [xyz]\)"):
            r.capture(1, 2)  # before: inf returned


def test_require_finite_names_instance_and_field():
    from axialdeform.core.io.safeio import require_finite

    a = np.zeros((3, 5, 3), np.float32)
    a[2, 4, 1] = np.nan
    with pytest.raises(AxialDeformError, match=r"p\.adp: instance 2, normals \(vertex 4, y\)"):
        require_finite(a, "normals", "xyz", source="p.adp")
    require_finite(np.zeros((0, 5, 3)), "x")


def test_range_warning_past_the_safe_distance(tmp_path, capsys):
    f = tmp_path / "far.txt"
    f.write_text(" ".join(["0"] * 10 + ["1e6", "0", "0", "0", "0", "0"]) + "\n")
    assert main(["bake", "stone", str(f), "-o", str(tmp_path / "far.npz")]) == 0
    err = capsys.readouterr().err
    assert "warning" in err and "px" in err and "safe 100 L" in err
    near = tmp_path / "near.txt"
    near.write_text(ROW)
    assert main(["bake", "stone", str(near), "-o", str(tmp_path / "near.npz")]) == 0
    assert "warning" not in capsys.readouterr().err


# ---------------------------------------------------------------- 5. sizes


def test_size_limit_comes_from_the_context(tmp_path, capsys):
    f = tmp_path / "p.txt"
    f.write_text(ROW)
    ctx = ad.create_context()
    try:
        from axialdeform.gl.context import size_limits

        mw, mh, text = size_limits(ctx)
    finally:
        ctx.release()
    assert "GL_MAX_RENDERBUFFER_SIZE" in text
    assert main(["render", "stone", str(f), "-o", str(tmp_path / "x.png"), "--size", f"{mw + 1}x16"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"1..{mw}" in err[0] and "GL_MAX_RENDERBUFFER_SIZE" in err[0]


def test_size_limited_by_memory(ctx, monkeypatch):
    from axialdeform.core.io import safeio
    from axialdeform.gl.context import Offscreen

    monkeypatch.setattr(safeio, "memory_available", lambda: 10_000_000)
    with pytest.raises(ContextError, match=r"need about .* expected at most about \d+x\d+"):
        Offscreen(ctx, (4000, 4000))


# ------------------------------------------------------------ 6. big meshes


def test_solid_drawing_never_builds_edges(ctx):
    mesh = ad.load_mesh(ad.core.bundled_mesh_path("stone"))  # a fresh mesh: nothing cached
    params = ad.random_params(mesh, 3, 0)
    with ad.AxialRenderer(ctx, mesh, params) as r, ad.Offscreen(ctx, (32, 32)) as target:
        target.use()
        cam = ad.frame_instances(mesh, params, 1.0)
        r.render(cam.view(), cam.projection(1.0), "solid")
        assert "edges" not in mesh.__dict__  # before: built in the constructor
        r.render(cam.view(), cam.projection(1.0), "wireframe")
        assert "edges" in mesh.__dict__


def test_edges_same_as_unique_rows():
    mesh = ad.load_mesh("stone")
    e = mesh.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    assert np.array_equal(mesh.edges, np.unique(np.sort(e, axis=1), axis=0).astype(np.uint32))


# ------------------------------------------------------------- 7. messages


def test_disk_full_names_the_file(tmp_path, monkeypatch, capsys):
    import errno

    def full(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "fsync", full)
    out = tmp_path / "p.adp"
    assert main(["random", "stone", "-n", "3", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert str(out) in err and "the disk is full" in err  # before: the file was not named
    assert not out.exists() and not list(tmp_path.iterdir())


def test_axis_length_zero_in_a_header_names_the_file(tmp_path, capsys):
    body = bytearray(P.encode_binary(np.zeros((1, 16), np.float32))[:-4])
    body[24:25] = struct.pack("<b", 1)
    body[40:48] = struct.pack("<d", 0.0)
    f = tmp_path / "zero.adp"
    f.write_bytes(bytes(body) + struct.pack("<I", zlib.crc32(bytes(body))))
    assert main(["info", str(f)]) == 2  # before: MeshError without the file's name
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(f) in err[0] and "axis" in err[0]


@pytest.mark.slow
def test_numpy_warnings_never_reach_the_terminal(tmp_path):
    proc = run_cli("bake", "stone", _huge(tmp_path), "-o", tmp_path / "x.npz", "--engine", "cpu")
    assert proc.returncode == 2
    assert "RuntimeWarning" not in proc.stderr and "Traceback" not in proc.stderr
    assert all(line.startswith("axialdeform bake: ") for line in proc.stderr.strip().splitlines()), proc.stderr


# ---------------------------------------------------------------- 7. API


def test_empty_instance_buffer_reads(ctx):
    for quantized in (False, True):
        buf = InstanceBuffer(ctx, quantized=quantized)
        try:
            out = buf.read()  # before: moderngl "cannot map the buffer"
            assert out.shape == (0, 16) and out.dtype == np.float32
        finally:
            buf.release()


@pytest.mark.parametrize("start", ["1", None, float("nan"), 1.0, True])
def test_update_params_start_must_be_an_integer(ctx, stone, start):
    params = ad.random_params(stone, 4, 0)
    with ad.AxialRenderer(ctx, stone, params) as r:
        with pytest.raises(ArgumentError, match="start: expected an integer"):
            r.update_params(params[:1], start=start)
        r.update_params(params[:1], start=np.int64(2))
        assert np.array_equal(r.instances.read()[2], params[0])


@pytest.mark.parametrize("view", [np.zeros((4, 4)), np.full((4, 4), np.nan), np.eye(3)])
def test_bad_view_matrices(ctx, stone, view):
    with ad.AxialRenderer(ctx, stone, ad.random_params(stone, 2, 0)) as r, ad.Offscreen(ctx, (16, 16)) as t:
        t.use()
        with pytest.raises(ArgumentError, match="view: expected"):
            r.render(view, np.eye(4))


def test_every_call_after_release_is_an_axialdeform_error(stone):
    ctx = ad.create_context()
    params = ad.random_params(stone, 2, 0)
    r = ad.AxialRenderer(ctx, stone, params)
    target = ad.Offscreen(ctx, (8, 8))
    buf = InstanceBuffer(ctx, params)
    other = InstanceBuffer(ctx, params)
    other.release()
    for call in (other.read, lambda: other.set(params), lambda: other.update(params[:1])):
        with pytest.raises(AxialDeformError, match="was released"):
            call()
    ctx.release()
    calls = [lambda: r.render(np.eye(4), np.eye(4)), lambda: r.set_params(params), r.capture,
             lambda: r.update_params(params[:1]), target.use, target.read, buf.read,
             lambda: ad.AxialRenderer(ctx, stone, params), lambda: ad.Offscreen(ctx, (8, 8)),
             lambda: ad.bake(stone, params, "gpu", ctx=ctx), lambda: ad.render_image(stone, params, (8, 8), ctx=ctx)]
    for call in calls:
        with pytest.raises(AxialDeformError, match="released"):
            call()
    for obj in (r, target, buf):  # release stays safe, twice
        obj.release()
        obj.release()


# ----------------------------------------------------------- 8. the fuzzer

sys.path.insert(0, str(ROOT / "tools"))
from hypothesis import HealthCheck, given, settings  # noqa: E402

import fuzz_params  # noqa: E402


@pytest.mark.slow
@settings(max_examples=80, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(case=fuzz_params.strategies()["mesh_file"])
def test_generated_mesh_files_load_or_name_the_file(tmp_path_factory, case):
    folder = tmp_path_factory.getbasetemp() / "fuzz-meshes"
    folder.mkdir(exist_ok=True)
    fuzz_params.prepare_folder(folder)
    verdict = fuzz_params.check_mesh_file(folder, *case)
    assert not verdict.startswith("crash"), (verdict, case)


@pytest.mark.slow
def test_fuzz_every_command_briefly():
    # every command in turn, twice (view headless, bench tiny, scatter, web with --serve,
    # scene files), each in a forked child with its peak RSS checked; big inputs of 1 MB
    # in a fresh process: this one holds GL contexts, whose llvmpipe threads a fork does not copy
    n = 2 * len(fuzz_params.COMMANDS)
    proc = subprocess.run([sys.executable, str(ROOT / "tools" / "fuzz_params.py"), "--target", "commands", "--seconds",
                           "150", "--seed", "2003", "--big-mb", "1", "--cases", str(n), "--cycle"],
                          capture_output=True, text=True, timeout=600, env={**os.environ, "PYTHONPATH": str(ROOT)})
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    assert f"fuzz commands: {n} command lines" in out, out
    assert "0 crashes, 0 hangs" in out and "0 over the memory bound" in out, out
    for command in ("view", "bench", "scatter", "web", "scene-"):
        assert f"| {command}" in out, out


def test_fuzz_runner_sees_what_in_process_capture_missed(tmp_path):
    # the forked runner judges exactly what a user sees: exit status, lines on stderr, a hang
    ok = fuzz_params.run_isolated(["random", "stone", "-n", "3", "-o", str(tmp_path / "p.adp")])
    assert ok["verdict"] == "ok" and ok["peak_rss"] > 10 * 2**20 and "wrote" in ok["stdout"], ok
    bad = fuzz_params.run_isolated(["random", "stone", "-n", "-3", "-o", str(tmp_path / "q.adp")])
    assert bad["verdict"] == "error", bad
    os.mkfifo(tmp_path / "fifo.adp")
    hang = fuzz_params.run_isolated(["info", str(tmp_path / "fifo.adp")], timeout=2.0)
    assert hang["verdict"] == "error", hang  # refused, not read: a blocked read would be a hang
    assert fuzz_params._verdict(["info"], 0, {"code": 0, "how": "returned"}, "x.py:3: UserWarning: w\n").startswith(
        "crash: stray stderr")
    assert fuzz_params._verdict(["info"], 0, {"code": 70, "how": "exception"}, "Traceback\nKeyError: 1\n") == \
        "crash: KeyError: 1"


def test_fuzz_params_briefly(capsys):
    assert fuzz_params.fuzz_params(1.0, seed=16) == 0
    assert "0 crashes" in capsys.readouterr().out


# ------------------------------------- found by fuzzing every command (s16fuzz)
# Each failed before its fix: a hang (the subprocess timeout), a traceback, or
# a second stderr line.


def _png(path, array):
    from PIL import Image

    Image.fromarray(array).save(path)
    return path


def test_scatter_refuses_a_fifo_height_map_without_blocking(tmp_path):
    fifo = tmp_path / "hm.png"
    os.mkfifo(fifo)
    proc = run_cli("scatter", fifo, "stone", "-n", "5", "-o", tmp_path / "o.adp", timeout=30)  # before: blocked forever
    one_error_line(proc, str(fifo), "not a regular file")
    assert not (tmp_path / "o.adp").exists()


def test_density_map_must_be_a_regular_file(tmp_path, capsys):
    hm = _png(tmp_path / "hm.png", np.full((8, 8), 128, np.uint8))
    link = tmp_path / "d.png"
    link.symlink_to("/dev/null")
    assert main(["scatter", str(hm), "stone", "-n", "3", "-o", str(tmp_path / "o.adp"), "--density", str(link)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(link) in err[0] and "character device" in err[0], err


@pytest.mark.slow
def test_scatter_refuses_a_decompression_bomb_in_one_line(tmp_path):
    bomb = _png(tmp_path / "bomb.png", np.zeros((12000, 16000), np.uint8))  # 192 M pixels in ~190 kB
    assert bomb.stat().st_size < 1_000_000
    proc = run_cli("scatter", bomb, "stone", "-n", "5", "-o", tmp_path / "o.adp", timeout=60)  # before: a traceback
    one_error_line(proc, str(bomb), "decompression bomb")


def test_height_map_pixels_checked_against_memory_before_decoding(tmp_path, monkeypatch, capsys):
    from axialdeform.core import surface as scatter
    from axialdeform.core.io import safeio

    hm = _png(tmp_path / "hm.png", np.full((200, 300), 128, np.uint8))
    budget = 200 * 300 * scatter.SURFACE_BYTES_PER_PIXEL  # 0.8 of this is less than the map needs
    monkeypatch.setattr(safeio, "memory_available", lambda: budget)
    decoded = []
    monkeypatch.setattr(np, "asarray", lambda *a, **k: decoded.append(1) or np.array(*a, **k))
    with pytest.raises(ad.core.ScatterError, match=r"300x200 pixels needs about .*expected at most 48000 pixels") as info:
        scatter.load_surface(hm)
    assert str(hm) in str(info.value) and not decoded
    monkeypatch.undo()
    assert len(scatter.load_surface(hm).mesh.faces) == 2 * 199 * 299  # within memory: read as before


def test_scene_file_must_be_a_regular_file(tmp_path):
    fifo = tmp_path / "scene.toml"
    os.mkfifo(fifo)
    proc = run_cli("render", fifo, "-o", tmp_path / "o.png", timeout=30)  # before: blocked forever in read_text
    one_error_line(proc, str(fifo), "not a regular file (a FIFO)")


def test_scene_file_symlink_to_a_device_is_refused(tmp_path, capsys):
    link = tmp_path / "scene.toml"
    link.symlink_to("/dev/null")  # /dev/zero is the attack (before: read until memory ran out); /dev/null shows the check
    assert main(["bake", str(link), "-o", str(tmp_path / "o.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(link) in err[0] and "character device" in err[0], err


def test_scene_include_of_a_fifo_is_refused(tmp_path):
    os.mkfifo(tmp_path / "inc.toml")
    scene = tmp_path / "scene.toml"
    scene.write_text('include = ["inc.toml"]\n')
    proc = run_cli("export", scene, "-o", tmp_path / "o.glb", timeout=30)  # before: blocked forever
    one_error_line(proc, "inc.toml", "FIFO")


@pytest.mark.parametrize("port", ["70000", "-1"])
def test_web_serve_port_out_of_range_is_one_line(tmp_path, capsys, port):
    params = tmp_path / "p.adp"
    assert main(["random", "stone", "-n", "3", "-o", str(params)]) == 0
    capsys.readouterr()
    # before: OverflowError traceback from socket.bind after the page was written
    assert main(["web", "stone", str(params), "-o", str(tmp_path / "w"), "--serve", "--port", port]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"axialdeform web: error: --port: expected a TCP port 0..65535 (0: any free one), found {port}"]
    from axialdeform.web import make_server

    (tmp_path / "w2").mkdir()
    with pytest.raises(AxialDeformError, match="expected a TCP port"):
        make_server(tmp_path / "w2", int(port))


def test_library_warnings_are_one_line_on_the_cli(tmp_path, capsys):
    tet = tmp_path / "tet.obj"
    tet.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
    # before: "…/renderer.py:180: UserWarning: …" and the source line: two stray lines
    assert main(["view", str(tet), "-n", "5", "--headless", "--frames", "1", "--size", "32x24", "--lod"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"axialdeform view: warning: {tet}: 4 triangles are too few to simplify "
                   "(LOD needs a part of at least 48; the largest has 4); drawing one level"], err


def test_framing_a_big_mesh_in_bounded_memory():
    from axialdeform.core.bounds import _support_indices

    rng = np.random.default_rng(4)
    positions = rng.normal(size=(300_000, 3)).astype(np.float32)
    tracemalloc.start()
    try:
        idx = _support_indices(positions)  # before: a (300 000, 200) float64 product, 460 MB, and a copy
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 80 * 2**20, peak / 2**20
    p = positions.astype(np.float64)  # the same vertices as one product over all of them
    k = np.arange(194) + 0.5
    z, phi = 1.0 - 2.0 * k / 194, np.pi * (1.0 + 5.0**0.5) * k
    dirs = np.concatenate([np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], 1),
                           np.eye(3), -np.eye(3)])
    assert np.array_equal(idx, np.unique(np.argmax((p - p.mean(axis=0)) @ dirs.T, axis=0)))


def test_view_count_checked_before_allocating(capsys):
    # before: random_params allocated, and the MemoryError became "out of memory" without the limit
    assert main(["view", "stone", "-n", str(10**12), "--headless", "--frames", "1", "--size", "32x24"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("axialdeform view: error: -n/--count: 1000000000000 instances need about")
    assert "expected at most" in err[0]


def test_headless_view_size_limit_comes_from_the_context(capsys):
    # before: "could not open the viewer window (Error: the framebuffer is not complete (INCOMPLETE_ATTACHMENT))"
    assert main(["view", "stone", "-n", "3", "--headless", "--frames", "1", "--size", "100000x16"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "100000x16 pixels; expected 1.." in err[0] and "GL_MAX_RENDERBUFFER_SIZE" in err[0], err


def test_bench_report_from_must_be_a_regular_file(tmp_path, capsys):
    fifo = tmp_path / "details.json"
    os.mkfifo(fifo)
    proc = run_cli("bench", "--report-from", fifo, timeout=30)  # before: blocked forever in read_text
    one_error_line(proc, str(fifo), "not a regular file (a FIFO)")
    link = tmp_path / "zero.json"
    link.symlink_to("/dev/null")  # /dev/zero is the attack (before: 8 GB and counting); /dev/null shows the check
    assert main(["bench", "--report-from", str(link)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(link) in err[0] and "character device" in err[0], err
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000)
    assert main(["bench", "--report-from", str(deep)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "invalid JSON" in err[0], err


def test_scatter_checks_its_output_before_the_work(tmp_path, capsys, monkeypatch):
    from axialdeform.core import scatter

    hm = _png(tmp_path / "hm.png", np.full((8, 8), 128, np.uint8))
    density = tmp_path / "d.adp"  # an image under another name
    from PIL import Image

    Image.fromarray(np.full((4, 4), 200, np.uint8)).save(density, format="PNG")
    before = density.read_bytes()
    monkeypatch.setattr(scatter, "scatter", lambda *a, **k: pytest.fail("scattered before checking the output"))
    # before: the terrain was scattered first, then write_params refused the name (or replaced the input)
    assert main(["scatter", str(hm), "stone", "-n", "3", "-o", str(tmp_path / "o.txt"), "--quantize"]) == 2
    assert "the quantized form is binary only" in capsys.readouterr().err
    assert main(["scatter", str(hm), "stone", "-n", "3", "-o", str(density), "--density", str(density)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is the input file" in err[0], err
    assert density.read_bytes() == before


def test_unreadable_image_message_names_the_file_not_a_descriptor(tmp_path, capsys):
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"not a png at all")
    assert main(["scatter", str(junk), "stone", "-n", "3", "-o", str(tmp_path / "o.adp")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"axialdeform scatter: error: SURFACE {junk}: could not read the image (not an image format Pillow recognises)"


# ------------------------------------ bounded time for huge jobs (s16caps)
# Found by fuzzing every command: a 0.5 M-face mesh x 61 700 instances (view),
# 82 000 OBJ files (bake -o FOLDER) ran past 30 s of CPU with no warning.
# Each refusal below is exit 2, one line, nothing written, before the work.


def test_render_refuses_a_frame_over_the_triangle_budget(files, capsys, monkeypatch):
    from axialdeform.gl import context

    tmp, mesh, params = files  # 4 stones x 112 triangles = 448 a frame
    out = tmp / "r.png"
    real = context.create_context
    monkeypatch.setattr(context, "create_context", lambda *a, **k: pytest.fail("a context before the check"))
    assert main(["render", str(mesh), str(params), "-o", str(out), "--size", "32x24", "--max-triangles", "447"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and not out.exists(), err
    for needle in (f"{mesh} x {params}", "4 instances x 112 triangles = 448 triangles a frame (solid)",
                   "over the limit of 447", "expected at most 3 instances", "--max-triangles N"):
        assert needle in err[0], err[0]
    # wireframe: 1.5 edges a triangle, plus the hidden-line pass unless --fast
    argv = ["render", str(mesh), str(params), "-o", str(out), "--size", "32x24", "--mode", "wireframe"]
    assert main(argv + ["--max-triangles", "1119"]) == 2
    assert "x 2.5 for wireframe" in capsys.readouterr().err
    assert main(argv + ["--max-triangles", "671", "--fast"]) == 2
    assert "x 1.5 for wireframe" in capsys.readouterr().err
    assert main(argv + ["--max-triangles", "2239", "--stats"]) == 2  # --stats times one more frame
    assert "x 2 frames = 2240" in capsys.readouterr().err
    monkeypatch.setattr(context, "create_context", real)
    # at the limit it draws: the limit is raised by --max-triangles
    assert main(["render", str(mesh), str(params), "-o", str(out), "--size", "32x24", "--max-triangles", "448"]) == 0
    assert out.exists()


def test_drawn_triangles_count_only_the_parts_drawn():
    from dataclasses import replace

    from axialdeform.cli._common import drawn_triangles
    from axialdeform.core.material import Part

    stone = ad.load_mesh("stone")
    two = replace(stone, parts=(Part("a", 0, 100), Part("b", 100, 12)))
    assert drawn_triangles(two) == 112 and drawn_triangles(two, ["b"]) == 12
    assert drawn_triangles(two, ["a", "b", "a"]) == 112
    with pytest.raises(AxialDeformError, match="no part 'c'"):
        drawn_triangles(two, ["c"])


def test_default_triangle_budget_refuses_huge_jobs_before_the_work(tmp_path, capsys, monkeypatch):
    from axialdeform.cli._common import MAX_TRIANGLES
    from axialdeform.core import variation

    assert MAX_TRIANGLES == 50_000_000  # the documented default (README, docs/reliability.md)
    shot = tmp_path / "v.png"
    monkeypatch.setattr(variation, "random_params", lambda *a, **k: pytest.fail("parameters made before the check"))
    # 450 000 stones x 112 = 50.4 M triangles: before, the viewer drew them
    assert main(["view", "stone", "--headless", "--frames", "1", "-n", "450000", "--size", "32x24",
                 "--screenshot", str(shot)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "stone x -n 450000: 450000 instances x 112 triangles" in err[0], err
    assert "over the limit of 50000000" in err[0] and not shot.exists()
    out = tmp_path / "d.png"
    # demo draws solid and wireframe side by side: 150 000 x 112 x 3.5 = 58.8 M
    assert main(["demo", "-n", "150000", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "x 3.5 for solid + wireframe" in err[0] and not out.exists(), err


def test_the_interactive_viewer_is_not_capped(monkeypatch, capsys):
    """A window is watched and closed by its user (a million stones at full
    detail is its point): only ``--headless`` frames are counted."""
    import axialdeform.viewer as viewer_module
    from axialdeform.cli._common import check_triangles

    assert check_triangles([("a", 10**9, 10**6)], "wireframe", 1, frames=0) == 0
    with pytest.raises(AxialDeformError, match="over the limit of 1"):
        check_triangles([("a", 10**9, 10**6)], "wireframe", 1, frames=1)
    reached = []

    class Stop(AxialDeformError):
        pass

    def create(mesh, params, **kwargs):
        reached.append((len(params), kwargs["headless"]))
        raise Stop("stopped before opening a window")

    monkeypatch.setattr(viewer_module.Viewer, "create", staticmethod(create))
    assert main(["view", "stone", "-n", "450000"]) == 2  # 50.4 M triangles: over the default, not refused
    assert reached == [(450000, False)] and "stopped before opening a window" in capsys.readouterr().err
    assert main(["view", "stone", "-n", "450000", "--headless"]) == 2
    assert reached == [(450000, False)] and "over the limit of 50000000" in capsys.readouterr().err


def test_view_with_a_parameter_file_checks_the_budget(files, capsys):
    tmp, mesh, params = files
    shot = tmp / "v.png"
    argv = ["view", str(mesh), str(params), "--headless", "--frames", "1", "--size", "32x24", "--screenshot", str(shot)]
    assert main(argv + ["--max-triangles", "447", "--lod"]) == 2  # LOD: every instance may be near (level 0)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{mesh} x {params}: 4 instances x 112 triangles" in err[0] and not shot.exists(), err
    # --headless draws every one of --frames: a job of 2 frames counts both
    argv2 = [a if a != "1" else "2" for a in argv]
    assert main(argv2 + ["--max-triangles", "895"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "448 triangles a frame (solid), x 2 frames = 896" in err[0] and not shot.exists(), err
    assert main(argv + ["--max-triangles", "448"]) == 0 and shot.exists()


def test_scene_render_and_view_check_every_layer(files, capsys):
    tmp, mesh, params = files
    scene = tmp / "s.toml"
    scene.write_text(f'[[layer]]\nname = "a"\nmesh = "stone"\nparams = "{params.name}"\n'
                     f'[[layer]]\nname = "b"\nmesh = "{mesh.name}"\nparams = "{params.name}"\n')
    out = tmp / "s.png"
    assert main(["render", str(scene), "-o", str(out), "--size", "32x24", "--max-triangles", "895"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and not out.exists(), err
    assert f"{scene}: layer a: 4 instances x 112 triangles; {scene}: layer b: 4 instances x 112 triangles" in err[0]
    assert "= 896 triangles a frame" in err[0] and "fewer instances or smaller meshes" in err[0]
    assert main(["view", str(scene), "--headless", "--frames", "1", "--size", "32x24", "--max-triangles", "895"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert main(["render", str(scene), "-o", str(out), "--size", "32x24", "--max-triangles", "896"]) == 0
    assert out.exists()


def _refused_over_the_limit(tmp_path, capsys, command, out, limit, needles):
    """``command stone many.adp -o out`` with one instance over ``limit`` is one
    error line naming the files, the count, the limit and ``needles``, nothing
    written; returns a parameter file of 3 instances for the limits around it."""
    many = tmp_path / "many.adp"
    P.write_params(many, np.zeros((limit + 1, 16), np.float32))
    assert main([command, "stone", str(many), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and not out.exists(), err
    for needle in (str(out), str(many), f"{limit + 1} instances", f"over the limit of {limit}", *needles):
        assert needle in err[0], err[0]
    few = tmp_path / "few.adp"
    P.write_params(few, np.zeros((3, 16), np.float32))
    return few


def test_bake_folder_refuses_more_files_than_the_limit(tmp_path, capsys, monkeypatch):
    from axialdeform.cli._common import MAX_BAKE_FILES
    from axialdeform.gl import bake as gl_bake

    assert MAX_BAKE_FILES == 10_000  # the documented default
    out = tmp_path / "baked"
    real = gl_bake.bake
    monkeypatch.setattr(gl_bake, "bake", lambda *a, **k: pytest.fail("deformed before the check"))
    # before: 10 001 OBJ files
    few = _refused_over_the_limit(tmp_path, capsys, "bake", out, MAX_BAKE_FILES, ("--max-files N", "-o OUT.npz"))
    assert main(["bake", "stone", str(few), "-o", str(out), "--max-files", "2"]) == 2
    assert "3 files, over the limit of 2" in capsys.readouterr().err and not out.exists()
    monkeypatch.setattr(gl_bake, "bake", real)
    assert main(["bake", "stone", str(few), "-o", str(out), "--max-files", "3"]) == 0  # at the limit: written
    assert sorted(p.name for p in out.iterdir()) == [f"instance_{i:06d}.obj" for i in range(3)]
    # an .npz has no file limit
    assert main(["bake", "stone", str(few), "-o", str(tmp_path / "b.npz"), "--max-files", "1"]) == 0


def test_export_baked_refuses_more_meshes_than_the_limit(tmp_path, capsys, monkeypatch):
    from axialdeform.cli._common import MAX_EXPORT_MESHES
    from axialdeform.core.io import gltf as export

    assert MAX_EXPORT_MESHES == 10_000  # the documented default
    out = tmp_path / "e.glb"
    real = export.export_baked
    monkeypatch.setattr(export, "export_baked", lambda *a, **k: pytest.fail("baked before the check"))
    # before: 10 001 glTF meshes and nodes
    few = _refused_over_the_limit(tmp_path, capsys, "export", out, MAX_EXPORT_MESHES, ("--max-meshes N", "--instanced"))
    assert main(["export", "stone", str(tmp_path / "many.adp"), "-o", str(out), "--instanced"]) == 0  # no limit
    out.unlink()
    assert main(["export", "stone", str(few), "-o", str(out), "--max-meshes", "2"]) == 2
    assert "over the limit of 2" in capsys.readouterr().err and not out.exists()
    monkeypatch.setattr(export, "export_baked", real)
    assert main(["export", "stone", str(few), "-o", str(out), "--max-meshes", "3"]) == 0 and out.exists()

"""Extended instances (19 numbers: s tw tp): CPU reference,
an independent evaluation of the spec, GPU capture, files."""

from __future__ import annotations

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.deform import deform, rotation_matrices
from axialdeform.core.params import extend_params, make_params
from axialdeform.core.quantize import quantization_error_bound
from axialdeform.gl.renderer import AxialRenderer

from conftest import data_mesh, make_mesh


def _permuted(mesh, shift: int, name: str):
    """The mesh with its coordinates cycled (an even permutation keeps the winding):
    the longest extent moves from x to y (shift 1) or z (shift 2)."""
    perm = np.roll(np.arange(3), shift)
    return make_mesh(np.asarray(mesh.positions, dtype=np.float64)[:, perm], mesh.faces, name=name)


@pytest.fixture(scope="module")
def real_meshes():
    bunny = ad.load_mesh(data_mesh("classic/bunny_trimesh.ply"))
    rock = ad.load_mesh(data_mesh("base/rock_caustics.obj"))
    meshes = {
        "bunny-x": bunny,
        "bunny-y": _permuted(bunny, 1, "bunny-y"),
        "bunny-z": _permuted(bunny, 2, "bunny-z"),
        "rock-z": _permuted(rock, 2, "rock-z"),
        "blade-y": ad.load_mesh(data_mesh("base/grass_blade_flora.obj")),
        "suzanne-x": ad.load_mesh(data_mesh("gltf/monkey.glb")),
    }
    assert {m.axis.index for m in meshes.values()} == {0, 1, 2}
    return meshes


def extended(mesh, n=12, seed=5):
    p = ad.random_params(mesh, n, seed=seed, variation=ad.Variation(bend=0.1))
    rng = np.random.default_rng(seed)
    e = extend_params(p)
    e[:, 16] = rng.uniform(0.4, 2.5, n)
    e[:, 17] = rng.uniform(-4.0, 4.0, n)
    e[:, 18] = rng.uniform(-0.8, 0.9, n)
    return e


# ---------------------------------------------------------------- the spec, evaluated directly


def _spec_map(mesh, inst, v):
    """V'' of the spec for one instance and points v (k, 3), float64, written from the
    formulas of the extension section (no code shared with core.deform)."""
    a = mesh.axis.index
    i, j = [c for c in range(3) if c != a]
    lo, L = mesh.axis.lo, mesh.axis.length
    pos = np.asarray(mesh.positions, dtype=np.float64)
    cen = (pos.min(axis=0) + pos.max(axis=0)) / 2
    t = np.clip((v[:, a] - lo) / L, 0, 1)
    d = np.asarray(inst[:10], dtype=np.float64).reshape(5, 2)
    from math import comb

    B = np.stack([comb(4, m) * t**m * (1 - t) ** (4 - m) for m in range(5)], axis=1)
    D = B @ d
    s, tw, tp = (float(x) for x in inst[16:19])
    k = 1 - tp * t
    th = tw * t
    w = np.stack([v[:, i] - cen[i], v[:, j] - cen[j]], axis=1)
    wr = np.stack([np.cos(th) * w[:, 0] - np.sin(th) * w[:, 1], np.sin(th) * w[:, 0] + np.cos(th) * w[:, 1]], axis=1)
    out = np.empty_like(v)
    out[:, a] = v[:, a]
    out[:, i] = cen[i] + k * wr[:, 0] + D[:, 0]
    out[:, j] = cen[j] + k * wr[:, 1] + D[:, 1]
    return out


def _spec_world(mesh, inst, idx):
    """World position and normal of vertices idx: J by central differences,
    cof(J) by cross products of J's columns, n'' = normalize(cof(J) n), R n''."""
    inst = np.asarray(inst, dtype=np.float64)
    L = mesh.axis.length
    h = 1e-5 * L
    R = rotation_matrices(inst[13:16])
    pos, nrm = [], []
    for k in idx:  # a few vertices: a test, not a hot path
        v = np.asarray(mesh.positions[k], dtype=np.float64)
        cols = []
        for c in range(3):
            e = np.zeros(3)
            e[c] = h
            cols.append((_spec_map(mesh, inst, (v + e)[None])[0] - _spec_map(mesh, inst, (v - e)[None])[0]) / (2 * h))
        J = np.stack(cols, axis=1)
        cof = np.stack([np.cross(J[:, 1], J[:, 2]), np.cross(J[:, 2], J[:, 0]), np.cross(J[:, 0], J[:, 1])], axis=1)
        n = cof @ np.asarray(mesh.normals[k], dtype=np.float64)
        nrm.append(R @ (n / np.linalg.norm(n)))
        pos.append(R @ (inst[16] * _spec_map(mesh, inst, v[None])[0]) + inst[10:13])
    return np.array(pos), np.array(nrm)


def test_cof_by_cross_products_is_det_times_inverse_transpose():
    J = np.random.default_rng(0).normal(size=(3, 3)) + 2 * np.eye(3)
    cof = np.stack([np.cross(J[:, 1], J[:, 2]), np.cross(J[:, 2], J[:, 0]), np.cross(J[:, 0], J[:, 1])], axis=1)
    np.testing.assert_allclose(cof, np.linalg.det(J) * np.linalg.inv(J).T, atol=1e-12)


@pytest.mark.parametrize("name", ["bunny-x", "blade-y", "rock-z", "bunny-y"])
def test_cpu_reference_equals_the_spec_evaluated_directly(real_meshes, name):
    mesh = real_meshes[name]
    params = extended(mesh, n=4)
    pos, nrm = deform(mesh.axis, mesh.positions, mesh.normals, params)
    L = mesh.axis.length
    a = mesh.axis.index
    t = mesh.axis.parameter(mesh.positions)
    inner = np.flatnonzero((t > 0.02) & (t < 0.98))  # central differences need room on both sides
    idx = inner[np.linspace(0, len(inner) - 1, 7).astype(int)]
    for r in range(len(params)):
        sp, sn = _spec_world(mesh, params[r], idx)
        scale = max(1.0, float(np.abs(params[r, 10:13]).max()) / L)
        np.testing.assert_allclose(pos[r, idx], sp, atol=2e-6 * L * scale * params[r, 16])
        np.testing.assert_allclose(nrm[r, idx], sn, atol=1e-5)
    assert a in (0, 1, 2)


def test_twist_and_taper_do_something_and_keep_the_base_section(real_meshes):
    mesh = real_meshes["blade-y"]
    p = make_params(count=1, scale=1.0, twist=np.pi / 2, taper=0.5)
    plain = make_params(count=1)
    a = deform(mesh.axis, mesh.positions, mesh.normals, p)[0][0]
    b = deform(mesh.axis, mesh.positions, mesh.normals, plain)[0][0]
    t = mesh.axis.parameter(mesh.positions)
    assert np.abs(a - b)[t > 0.5].max() > 0.01 * mesh.axis.length
    np.testing.assert_array_equal(a[t == 0], b[t == 0])
    # the along-axis coordinate never changes
    np.testing.assert_array_equal(a[:, 1], b[:, 1])


@pytest.mark.parametrize("name", ["bunny-x", "bunny-z", "blade-y", "suzanne-x"])
def test_identity_extension_is_bitwise_the_16_number_result_cpu(real_meshes, name):
    mesh = real_meshes[name]
    p = ad.random_params(mesh, 30, seed=2)
    a = deform(mesh.axis, mesh.positions, mesh.normals, p)
    b = deform(mesh.axis, mesh.positions, mesh.normals, extend_params(p))
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


@pytest.mark.parametrize("quantized", [False, True])
def test_gpu_capture_equals_cpu_on_real_meshes(ctx, real_meshes, quantized):
    for name, mesh in real_meshes.items():
        L = mesh.axis.length
        params = extended(mesh, n=10)
        with AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(quantized=quantized)) as r:
            assert r.extended and r.instances.record_bytes == (40 if quantized else 76)
            gpu = r.capture()
            on_gpu = r.instances.read()
        if not quantized:
            np.testing.assert_array_equal(on_gpu, params)
        cpu = deform(mesh.axis, mesh.positions, mesh.normals, on_gpu)
        reach = max(1.0, float(np.abs(params[:, 10:13]).max()) / L)  # world positions far from 0 round coarser
        err = np.abs(gpu[0] - cpu[0]).max() / L
        assert err <= 1e-5 * reach, f"{name}: positions differ by {err:.3g} L"
        assert np.abs(gpu[1] - cpu[1]).max() <= 1e-5, name


@pytest.mark.parametrize("quantized", [False, True])
def test_identity_extension_is_bitwise_the_16_number_result_gpu(ctx, real_meshes, quantized):
    mesh = real_meshes["bunny-y"]
    p = ad.random_params(mesh, 6, seed=4)
    with AxialRenderer(ctx, mesh, p, options=ad.RenderOptions(quantized=quantized)) as r:
        a = r.capture()
    with AxialRenderer(ctx, mesh, extend_params(p), options=ad.RenderOptions(quantized=quantized)) as r:
        b = r.capture()
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


def test_renderer_widths(ctx, stone):
    p = ad.random_params(stone, 3, seed=1)
    with AxialRenderer(ctx, stone, p, options=ad.RenderOptions(extended=True)) as r:  # 16 numbers into an extended renderer
        got = r.instances.read()
        assert got.shape == (3, 19)
        np.testing.assert_array_equal(got[:, 16:], [[1, 0, 0]] * 3)
    with AxialRenderer(ctx, stone, p) as r:
        with pytest.raises(ad.core.ParamError, match="extended=True"):
            r.set_params(extend_params(p))


# ---------------------------------------------------------------- files


def test_text_file_19_numbers_round_trip(tmp_path, stone):
    e = extended(stone, n=9)
    path = ad.write_params(tmp_path / "e.txt", e, stone)
    back = ad.read_params(path, stone)
    assert back.shape == (9, 19)
    np.testing.assert_array_equal(back, e)
    assert "s tw tp" in path.read_text()


def test_text_file_mixed_widths_name_the_line(tmp_path):
    row16 = " ".join(["0"] * 16)
    row19 = " ".join(["0"] * 16 + ["1", "0", "0"])
    path = tmp_path / "mixed.txt"
    path.write_text(f"# comment\n{row19}\n{row19}\n{row16}\n")
    with pytest.raises(ad.core.ParamFileError, match=r"mixed.txt: line 4: expected 19 numbers like line 2, found 16"):
        ad.read_params(path)


@pytest.mark.parametrize("field,value,expected", [("s", "0", "s > 0"), ("s", "-2", "s > 0"), ("tp", "1", "tp < 1"),
                                                  ("tp", "1.5", "tp < 1")])
def test_bad_extension_values_are_refused_naming_line_and_field(tmp_path, field, value, expected):
    extra = {"s": ["1", "0", "0"], "tp": ["1", "0", "0"]}[field]
    extra[0 if field == "s" else 2] = value
    path = tmp_path / "bad.txt"
    path.write_text(" ".join(["0"] * 16 + ["1", "0", "0"]) + "\n" + " ".join(["0"] * 16 + extra) + "\n")
    with pytest.raises(ad.core.ParamFileError, match=rf"line 2, field {field}: expected a (scale|taper) {expected}"):
        ad.read_params(path)


def test_binary_version_2_lossless_and_quantized(tmp_path, stone):
    from axialdeform.core.io import params as P

    e = extended(stone, n=50)
    path = ad.write_params(tmp_path / "e.adp", e, stone)
    assert path.stat().st_size == 96 + 50 * 76 + 4
    pf = P.read_param_file(path)
    assert pf.version == 2 and pf.values.shape == (50, 19)
    np.testing.assert_array_equal(pf.values, e)
    q = ad.write_params(tmp_path / "q.adp", e, stone, quantize=True)
    assert q.stat().st_size == 96 + 19 * 8 + 50 * 38 + 4
    back = ad.read_params(q, stone)
    assert back.shape == (50, 19)
    assert (np.abs(back.astype(np.float64) - e) <= quantization_error_bound(e)).all()
    # 16-number files are unchanged: version 1, 64 bytes an instance
    p16 = e[:, :16]
    data = P.encode_binary(p16)
    assert P.read_binary_header(data).version == 1 and len(data) == 96 + 16 * 64 * 50 // 16 + 4
    np.testing.assert_array_equal(P.decode_binary(data).values, p16)


def test_extend_and_make_params():
    p = make_params(count=2, scale=[2.0, 3.0], taper=0.25)
    assert p.shape == (2, 19)
    np.testing.assert_array_equal(p[:, 16:], [[2, 0, 0.25], [3, 0, 0.25]])
    assert make_params(count=2).shape == (2, 16)
    with pytest.raises(ad.core.ParamError, match="field s: expected a scale s > 0"):
        make_params(count=1, scale=0.0)


# ---------------------------------------------------------------- command line


def _run(*args, cwd=None):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_cli_time_without_wind_is_an_error(tmp_path):
    proc = _run("bake", "leaf", "missing.adp", "-o", tmp_path / "x.npz", "--time", "2")
    assert proc.returncode == 2 and proc.stderr.strip() == (
        "axialdeform bake: error: --time: only meaningful with --wind (the wind is the only thing that moves with time)")
    assert not (tmp_path / "x.npz").exists()


@pytest.mark.parametrize("args,expected", [
    (("--scale", "0:1"), r"--scale: expected MIN:MAX with 0 < MIN <= MAX"),
    (("--scale", "2:1"), r"--scale: expected MIN:MAX with 0 < MIN <= MAX"),
    (("--taper", "1.5"), r"--taper: expected a number < 1"),
    (("--twist", "nan"), r"--twist: expected a finite number"),
])
def test_cli_random_bad_extension_is_one_line_exit_2(tmp_path, args, expected):
    import re

    proc = _run("random", "leaf", "-n", "5", *args, "-o", tmp_path / "x.adp")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and re.search(expected, lines[0]), proc.stderr
    assert not (tmp_path / "x.adp").exists()


@pytest.mark.slow
def test_cli_random_extended_then_bake_cpu_and_gpu_with_wind_agree(tmp_path, leaf):
    out = tmp_path / "e.adp"
    proc = _run("random", "leaf", "-n", "300", "--seed", "4", "--scale", "0.5:1.5", "--twist", "1.2", "--taper", "0.6",
                "--placement", "disc", "-o", out)
    assert proc.returncode == 0, proc.stderr
    e = ad.read_params(out, leaf)
    assert e.shape == (300, 19)
    assert 0.5 <= e[:, 16].min() and e[:, 16].max() <= 1.5 and np.abs(e[:, 17]).max() <= 1.2
    assert 0 <= e[:, 18].min() and e[:, 18].max() <= 0.6
    np.testing.assert_array_equal(e[:, :16], ad.random_params(leaf, 300, 4, placement="disc"))
    for engine in ("cpu", "gpu"):
        proc = _run("bake", "leaf", out, "-o", tmp_path / f"{engine}.npz", "--engine", engine, "--time", "2.5",
                    "--wind", "0.25,0.6,0.9,5", "--wind-dir", "1,0,0.5")
        assert proc.returncode == 0, proc.stderr
    cpu, gpu = np.load(tmp_path / "cpu.npz"), np.load(tmp_path / "gpu.npz")
    L = leaf.axis.length
    reach = max(1.0, float(np.abs(e[:, 10:13]).max()) / L)
    assert np.abs(cpu["positions"] - gpu["positions"]).max() <= 1e-5 * L * reach
    assert np.abs(cpu["normals"] - gpu["normals"]).max() <= 1e-5
    still = ad.bake(leaf, e, "cpu")
    assert np.abs(cpu["positions"] - still[0]).max() > 0.05 * L  # the wind did move them
    proc = _run("render", "leaf", out, "-o", tmp_path / "r.png", "--size", "96x64", "--wind", "0.25", "--time", "1")
    assert proc.returncode == 0 and (tmp_path / "r.png").stat().st_size > 0, proc.stderr


# ---------------------------------------------------------------- fit --extended


@pytest.mark.slow
def test_fit_extended_recovers_scale_twist_taper(stone, tmp_path):
    from axialdeform.core.fit import fit_params

    p = extended(stone, n=6, seed=8)
    p[:, 17] = np.clip(p[:, 17], -1.5, 1.5)
    shapes = ad.bake(stone, p)[0]
    res = fit_params(stone, shapes, extended=True)
    assert res.params.shape == (6, 19)
    assert res.max.max() < 1e-5
    np.testing.assert_allclose(res.params[:, 16:], p[:, 16:], atol=1e-4)
    # the 16-number fit cannot reproduce them: the extension is really needed
    assert fit_params(stone, shapes).max.max() > 1e-3
    # and from the command line
    folder = tmp_path / "variants"
    from axialdeform.core.io.bake import write_mesh_folder

    write_mesh_folder(folder, stone, (shapes, ad.bake(stone, p)[1]), "obj")
    out = tmp_path / "fit.adp"
    proc = _run("fit", "stone", folder, "-o", out, "--extended")
    assert proc.returncode == 0, proc.stderr
    np.testing.assert_allclose(ad.read_params(out, stone)[:, 16:], p[:, 16:], atol=1e-4)


# ---------------------------------------------------------------- golden bytes of the 16-number forms

#: sha256 of the three forms of _golden_values(), written by the code BEFORE the extension
#: (commit 50bd219): 16-number files must stay byte-identical
GOLDEN_16 = {
    "float32": (548, "6b9762f3296c124f98818f5b5077a0d0b762cd7c885f71e20df3441ebacc3dab"),
    "quantized": (452, "8ff252ddb801d9859f65b12408748404f7004415e7157acc47b820695d5974c6"),
    "text": (1314, "25878adbbf71929152ff897672eafda7d7802aa4253fbcb62064ef83b18faf13"),
}


def _golden_values():
    v = (np.arange(7 * 16, dtype=np.float64).reshape(7, 16) * 0.37 - 11.0).astype(np.float32)
    v[:, 13:] = np.sin(v[:, 13:])
    return v


def _forms(values):
    from axialdeform.core.axis import ControlAxis
    from axialdeform.core.io import params as P

    ax, fp = ControlAxis(1, -0.25, 2.5), bytes(range(32))
    return {"float32": P.encode_binary(values, axis=ax, mesh_fingerprint=fp),
            "quantized": P.encode_binary(values, axis=ax, mesh_fingerprint=fp, quantize=True),
            "text": P.format_text(values, "golden").encode()}


def test_16_number_files_are_byte_identical_to_before_the_extension():
    import hashlib

    from axialdeform.core.io import params as P

    values = _golden_values()
    for name, data in _forms(values).items():
        assert (len(data), hashlib.sha256(data).hexdigest()) == GOLDEN_16[name], name
    back = P.decode_binary(_forms(values)["float32"]).values
    np.testing.assert_array_equal(back, values)
    # the same numbers as extended instances are a different (version 2) file that decodes to the same shapes
    ext = _forms(extend_params(values))
    assert P.read_binary_header(ext["float32"]).version == 2 and len(ext["float32"]) == 96 + 7 * 76 + 4
    np.testing.assert_array_equal(P.decode_binary(ext["float32"]).values[:, :16], values)

"""Bounded fuzzing of the parameter-file readers, the mesh readers and every command.

    python3 tools/fuzz_params.py --seconds 60 [--seed 1] [--target params|meshes|commands|all]

``params`` (the default, as before issue 16):

Mutates valid parameter files (float32 binary, quantized binary, text) --
bit flips, byte overwrites, truncation, splices of two files, inserted and
deleted runs, header fields set to extreme values with the CRC-32 made to
match -- and feeds each to ``decode_binary`` and ``parse_text`` (in memory;
nothing is written).  Every input must either decode to finite ``(n, 16)
float32`` values or raise an ``AxialDeformError``.  A *crash* is any other
exception (or a MemoryError); *undetected* is a binary input whose bytes were
changed without fixing the CRC that still decoded to different values.

``meshes``: OBJ, PLY (ascii) and glTF (embedded) text drawn from the
hypothesis strategies below (valid, near-valid and hostile: huge counts,
NaN, out-of-range indices, missing/hostile referenced files) fed to
``load_mesh``: a ``BaseMesh`` with finite positions or a ``MeshError``.

``commands``: every command of the CLI (``info convert random render bake
export fit demo``) run in-process with fuzzed inputs (mutated parameter
files, generated meshes, outputs that are inputs, FIFOs, symlinks to
``/dev/null``, folders of stale files, absurd ``-n`` and ``--size``): exit 0,
or exit 2 with ONE error line on stderr (plus ``warning:`` lines); any
exception escaping ``main``, any other output on stderr, a FIFO or device
replaced, or a case running over 30 s (a hang) is a failure.

Prints one summary line per target (cases, crashes, hangs, peak RSS and the
largest input) and a few examples of any failure; exit status 1 if anything
failed.
"""

from __future__ import annotations

import argparse
import struct
import sys
import time
import zlib
from collections import Counter

import numpy as np

from axialdeform.core import params as P
from axialdeform.core.errors import AxialDeformError


def corpus(rng: np.random.Generator) -> list[tuple[str, bytes]]:
    v = rng.normal(scale=3.0, size=(int(rng.integers(0, 40)), 16)).astype(np.float32)
    return [
        ("float32", P.encode_binary(v)),
        ("quantized", P.encode_binary(v, quantize=True)),
        ("text", P.format_text(v, "fuzz").encode()),
        ("csv", "\n".join(",".join(repr(float(x)) for x in row) for row in v).encode()),
    ]


def with_crc(body: bytes) -> bytes:
    return body + struct.pack("<I", zlib.crc32(body))


def mutate(data: bytes, other: bytes, rng: np.random.Generator) -> tuple[str, bytes, bool]:
    """One mutation; returns (kind, bytes, crc_fixed)."""
    b = bytearray(data)
    kind = rng.choice(["bitflip", "bytes", "truncate", "splice", "insert", "delete", "header", "text-token"])
    if kind == "bitflip" and b:
        for _ in range(int(rng.integers(1, 4))):
            i = int(rng.integers(len(b)))
            b[i] ^= 1 << int(rng.integers(8))
    elif kind == "bytes" and b:
        for _ in range(int(rng.integers(1, 9))):
            b[int(rng.integers(len(b)))] = int(rng.integers(256))
    elif kind == "truncate":
        b = b[: int(rng.integers(len(b) + 1))]
    elif kind == "splice":
        b = b[: int(rng.integers(len(b) + 1))] + bytearray(other[int(rng.integers(len(other) + 1)) :])
    elif kind == "insert":
        i = int(rng.integers(len(b) + 1))
        b[i:i] = rng.bytes(int(rng.integers(1, 64)))
    elif kind == "delete" and b:
        i = int(rng.integers(len(b)))
        del b[i : i + int(rng.integers(1, 64))]
    elif kind == "header" and len(b) >= P.HEADER_SIZE + 4 and b[:8] == P.MAGIC:
        # an extreme value in one header field, CRC fixed so later checks run
        field = rng.choice(["version", "encoding", "header_size", "count", "axis", "lo", "length", "table"])
        off, fmt = {"version": (8, "<H"), "encoding": (10, "<H"), "header_size": (12, "<I"), "count": (16, "<Q"),
                    "axis": (24, "<b"), "lo": (32, "<d"), "length": (40, "<d"), "table": (96, "<f")}[field]
        size = struct.calcsize(fmt)
        if fmt in ("<d", "<f"):
            value = float(rng.choice([np.nan, np.inf, -np.inf, 0.0, -1.0, 3e38, 1e-45] + ([1e308] if fmt == "<d" else [])))
        elif fmt == "<b":
            value = int(rng.integers(-128, 128))
        else:
            choices = [0, 1, 2, 2**60, 2**(8 * size) - 1, int(rng.integers(0, 2**(8 * size) - 1, dtype=np.uint64))]
            value = choices[int(rng.integers(len(choices)))] % 2**(8 * size)
        if off + size <= len(b) - 4:
            b[off : off + size] = struct.pack(fmt, value)
        return f"header-{field}", with_crc(bytes(b[:-4])), True
    elif kind == "text-token":
        text = bytes(b).decode("utf-8", "replace").split(" ")
        if text:
            text[int(rng.integers(len(text)))] = str(rng.choice(["nan", "inf", "-inf", "1e39", "", "\xff", "x" * 5000, "1,2",
                                                                  "\u2028", "0x1p3", "#", "9" * 400]))
        return kind, " ".join(text).encode("utf-8", "surrogateescape"), False
    return str(kind), bytes(b), False


def check(fn, data: bytes, name: str):
    """'ok' (finite (n, 16) float32), 'error' (AxialDeformError) or 'crash: ...'."""
    try:
        out = fn(data, name)
    except AxialDeformError as exc:
        return "error" if str(exc) else "crash: empty message", None
    except BaseException as exc:  # noqa: BLE001 - that is the point of a fuzzer
        return f"crash: {type(exc).__name__}: {exc}"[:200], None
    values = out.values if isinstance(out, P.ParamFile) else out
    if not (isinstance(values, np.ndarray) and values.dtype == np.float32 and values.ndim == 2
            and values.shape[1] == 16 and np.isfinite(values).all()):
        return "crash: silent garbage", None
    return "ok", values


def fuzz_params(seconds: float, seed: int) -> int:
    class args:  # noqa: N801 - the old main's namespace
        pass

    args.seconds, args.seed = seconds, seed
    rng = np.random.default_rng(args.seed)
    tried, outcomes, kinds, failures = 0, Counter(), Counter(), []
    end = time.monotonic() + args.seconds
    while time.monotonic() < end:
        files = corpus(rng)
        for _ in range(200):
            (src_kind, data), (_, other) = (files[int(i)] for i in rng.integers(len(files), size=2))
            kind, mutated, crc_fixed = mutate(data, other, rng)
            kinds[kind] += 1
            for fn, name in ((P.decode_binary, "fuzz.adp"), (P.parse_text, "fuzz.txt")):
                tried += 1
                verdict, values = check(fn, mutated, name)
                outcomes[verdict.split(":")[0]] += 1
                if verdict.startswith("crash"):
                    failures.append((verdict, src_kind, kind, mutated[:80]))
                elif (verdict == "ok" and fn is P.decode_binary and not crc_fixed and mutated != data
                      and src_kind in ("float32", "quantized")
                      and not np.array_equal(values, P.decode_binary(data).values)):
                    outcomes["undetected"] += 1
                    failures.append(("undetected corruption", src_kind, kind, mutated[:80]))
    crashes = sum(1 for f in failures if f[0].startswith("crash"))
    undetected = outcomes["undetected"]
    print(f"fuzz_params: {tried} inputs tried in {args.seconds:g} s (seed {args.seed}): "
          f"{outcomes['ok']} decoded, {outcomes['error']} refused with an AxialDeformError, "
          f"{crashes} crashes, {undetected} undetected corruptions; mutations: "
          + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())))
    for verdict, src_kind, kind, head in failures[:5]:
        print(f"  {verdict} ({src_kind}, {kind}): {head!r}", file=sys.stderr)
    return 1 if failures else 0


# ============================================================ mesh strategies

def _strategies():
    """Hypothesis strategies for mesh files (built on first use: hypothesis
    is a test dependency, the params fuzzer does not need it)."""
    from hypothesis import strategies as st

    weird = st.sampled_from(["nan", "inf", "-inf", "1e39", "-0", "1e-45", "3.4e38", "", "x", "1e400", "0x10"])
    number = st.one_of(st.floats(-1e3, 1e3, allow_nan=False).map(lambda x: f"{x:.6g}"), weird,
                       st.floats(allow_nan=True, allow_infinity=True, width=64).map(repr))
    index = st.one_of(st.integers(-3, 12), st.sampled_from([0, 2**31, 2**63, -(2**40)]))

    plain = st.floats(-1e3, 1e3, allow_nan=False).map(lambda x: f"{x:.6g}")

    @st.composite
    def obj_text(draw):
        hostile = draw(st.integers(0, 2)) == 0  # else a mesh that should load
        num = number if hostile else plain
        n = draw(st.integers(0 if hostile else 3, 8))
        idx = index if hostile else st.integers(1, n)
        lines = [f"v {draw(num)} {draw(num)} {draw(num)}" for _ in range(n)]
        if draw(st.booleans()):
            lines += [f"vn {draw(num)} {draw(num)} {draw(num)}" for _ in range(draw(st.integers(0, n)))]
        for _ in range(draw(st.integers(0 if hostile else 1, 6))):
            k = draw(st.integers(1 if hostile else 3, 5))
            lines.append("f " + " ".join(str(draw(idx)) for _ in range(k)))
        if draw(st.integers(0, 4)) == 0:
            lines.insert(0, draw(st.sampled_from(["mtllib m.mtl", "mtllib fifo.mtl", "mtllib ../../etc/passwd",
                                                  "mtllib /dev/zero", "usemtl nothing", "o a\no b", "g x"])))
        if draw(st.integers(0, 5)) == 0:
            lines.insert(draw(st.integers(0, len(lines))), draw(st.text(max_size=40)))
        return "\n".join(lines) + "\n"

    @st.composite
    def ply_text(draw):
        hostile = draw(st.integers(0, 2)) == 0
        num = number if hostile else plain
        nv = draw(st.one_of(st.integers(0, 6), st.sampled_from([2**31, 2**62, -1]))) if hostile else draw(st.integers(3, 6))
        nf = draw(st.one_of(st.integers(0, 4), st.sampled_from([2**31, 10**12]))) if hostile else draw(st.integers(1, 4))
        index = st.one_of(st.integers(-3, 12), st.sampled_from([0, 2**31, 2**63, -(2**40)])) if hostile \
            else st.integers(0, nv - 1)
        head = ["ply", "format ascii 1.0", f"element vertex {nv}", "property float x", "property float y",
                "property float z", f"element face {nf}", "property list uchar int vertex_indices", "end_header"]
        body = [f"{draw(num)} {draw(num)} {draw(num)}" for _ in range(min(nv, 6) if nv > 0 else 0)]
        for _ in range(min(nf, 4)):
            k = draw(st.integers(0, 5)) if hostile else 3
            body.append(" ".join([str(k)] + [str(draw(index)) for _ in range(k)]))
        if hostile and draw(st.booleans()):
            body = body[: draw(st.integers(0, len(body)))]  # truncated
        return "\n".join(head + body) + "\n"

    @st.composite
    def gltf_text(draw):
        import base64
        import json

        n = draw(st.integers(0, 5))
        pos = np.array([[draw(st.floats(-10, 10, allow_nan=False)) for _ in range(3)] for _ in range(n)], "<f4")
        if n and draw(st.integers(0, 5)) == 0:
            pos[draw(st.integers(0, n - 1)), 0] = draw(st.sampled_from([np.nan, np.inf, 3e38]))
        data = pos.tobytes()
        uri = draw(st.sampled_from(["embedded", "fifo.bin", "missing.bin", "/dev/zero", "../../x.bin"]))
        uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode() if uri == "embedded" else uri
        count = draw(st.one_of(st.just(n), st.integers(0, 8), st.sampled_from([2**31, 2**40])))
        doc = {"asset": {"version": draw(st.sampled_from(["2.0", "1.0", "9"]))},
               "buffers": [{"uri": uri, "byteLength": draw(st.one_of(st.just(len(data)), st.integers(0, 2**40)))}],
               "bufferViews": [{"buffer": draw(st.sampled_from([0, 0, 1, -1])), "byteLength": len(data)}],
               "accessors": [{"bufferView": 0, "componentType": draw(st.sampled_from([5126, 5126, 5123, 1])),
                              "count": count, "type": draw(st.sampled_from(["VEC3", "VEC3", "SCALAR", "MAT4"]))}],
               "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": draw(st.sampled_from([4, 4, 0, 99]))}]}],
               "nodes": [{"mesh": draw(st.sampled_from([0, 0, 3]))}], "scenes": [{"nodes": [0]}]}
        text = json.dumps(doc)
        if draw(st.integers(0, 6)) == 0:
            text = text[: draw(st.integers(0, len(text)))]
        return text

    mesh_file = st.one_of(st.tuples(st.just(".obj"), obj_text()), st.tuples(st.just(".ply"), ply_text()),
                          st.tuples(st.just(".gltf"), gltf_text()))
    return {"obj": obj_text(), "ply": ply_text(), "gltf": gltf_text(), "mesh_file": mesh_file}


def strategies():
    """``{"obj", "ply", "gltf", "mesh_file"}``: hypothesis strategies of mesh file text
    (``mesh_file`` draws ``(suffix, text)``)."""
    global _STRATEGIES
    if _STRATEGIES is None:
        _STRATEGIES = _strategies()
    return _STRATEGIES


_STRATEGIES = None


def prepare_folder(folder) -> None:
    """The files generated meshes may refer to: a FIFO, a small material library."""
    import os
    from pathlib import Path

    folder = Path(folder)
    if not (folder / "fifo.mtl").exists():
        os.mkfifo(folder / "fifo.mtl")
        os.mkfifo(folder / "fifo.bin")
        (folder / "m.mtl").write_text("newmtl a\nKd 1 0 0\n")


def check_mesh_file(folder, suffix: str, text: str, k: int = 0) -> str:
    """Write one generated mesh file and load it: 'ok', 'error' or 'crash: ...'."""
    from pathlib import Path

    from axialdeform.core.mesh import load_mesh

    path = Path(folder) / f"case{k % 50}{suffix}"
    path.write_text(text, encoding="utf-8", errors="surrogateescape")
    try:
        mesh = load_mesh(path)
    except AxialDeformError as exc:
        return "error" if str(exc).startswith(str(path)) else f"crash: message does not name the file: {exc}"[:200]
    except BaseException as exc:  # noqa: BLE001
        return f"crash: {type(exc).__name__}: {exc}"[:200]
    if not np.isfinite(mesh.positions).all() or not np.isfinite(mesh.normals).all():
        return "crash: non-finite mesh"
    return "ok"


class _TimeUp(Exception):
    pass


class _Hang(BaseException):
    pass


def _drive(strategy, seconds: float, seed: int, body) -> int:
    """Call ``body(example)`` for examples of ``strategy`` until ``seconds`` pass."""
    from hypothesis import HealthCheck, Phase, Verbosity, given, seed as hseed, settings

    end = time.monotonic() + seconds
    count = [0]

    @hseed(seed)
    @settings(max_examples=10**9, deadline=None, database=None, phases=[Phase.generate], verbosity=Verbosity.quiet,
              suppress_health_check=list(HealthCheck))
    @given(strategy)
    def run(example):
        if time.monotonic() > end:
            raise _TimeUp
        count[0] += 1
        body(example)

    try:
        run()
    except _TimeUp:
        pass
    return count[0]


def _peak_rss() -> int:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB


def fuzz_meshes(seconds: float, seed: int) -> int:
    import tempfile

    outcomes, failures = Counter(), []
    with tempfile.TemporaryDirectory(prefix="fuzz-meshes-") as tmp:
        prepare_folder(tmp)

        def body(case):
            suffix, text = case
            t0 = time.monotonic()
            verdict = check_mesh_file(tmp, suffix, text, sum(outcomes.values()))
            if time.monotonic() - t0 > 30:
                verdict = "hang: over 30 s"
            outcomes[verdict.split(":")[0]] += 1
            if verdict.startswith(("crash", "hang")):
                failures.append((verdict, suffix, text[:120]))

        tried = _with_alarm(lambda: _drive(strategies()["mesh_file"], seconds, seed, body))
    print(f"fuzz meshes: {tried} mesh files in {seconds:g} s (seed {seed}): {outcomes['ok']} loaded, "
          f"{outcomes['error']} refused with a MeshError naming the file, {outcomes['crash']} crashes, "
          f"{outcomes['hang']} hangs over 30 s; peak RSS {_peak_rss() / 2**20:.0f} MB")
    for verdict, suffix, head in failures[:5]:
        print(f"  {verdict} ({suffix}): {head!r}", file=sys.stderr)
    return 1 if failures else 0


def _with_alarm(fn):
    return fn()


# ============================================================ every command

COMMANDS = ("info", "convert", "random", "render", "bake", "export", "fit", "demo")


def _command_case(rng: np.random.Generator, tmp, mesh_texts: list) -> tuple[list[str], dict]:
    """One fuzzed command line and what must hold afterwards."""
    import os
    from pathlib import Path

    from axialdeform.core.mesh import bundled_mesh_path

    tmp = Path(tmp)
    k = int(rng.integers(1 << 30))
    stone = str(bundled_mesh_path("stone"))
    # a mesh: bundled, copied, or generated (possibly hostile)
    pick = rng.integers(4)
    if pick == 0 and mesh_texts:
        suffix, text = mesh_texts[int(rng.integers(len(mesh_texts)))]
        mesh = tmp / f"m{k}{suffix}"
        mesh.write_text(text, encoding="utf-8", errors="surrogateescape")
        mesh = str(mesh)
    elif pick == 1:
        mesh = str(tmp / f"m{k}.obj")
        Path(mesh).write_bytes(Path(stone).read_bytes())
    else:
        mesh = rng.choice(["stone", "leaf", stone])
    # parameters: valid, mutated, huge, or a special file
    files = corpus(rng)
    src_kind, data = files[int(rng.integers(len(files)))]
    r = rng.random()
    if r < 0.4:
        _kind, data, _ = mutate(data, files[0][1], rng)
    elif r < 0.5:
        data = (" ".join(["3.4e38"] * 13 + ["0.7"] * 3) + "\n").encode()
    elif r < 0.55:
        data = (" ".join(["0"] * 10 + ["1e7", "0", "0", "0", "0", "0"]) + "\n").encode()
    suffix = ".adp" if src_kind in ("float32", "quantized") or rng.random() < 0.2 else ".txt"
    params = tmp / f"p{k}{suffix}"
    special = rng.random()
    if special < 0.04:
        os.mkfifo(params)
    elif special < 0.08:
        params.symlink_to(rng.choice(["/dev/null", "/dev/zero"]))
    elif special < 0.1:
        params.mkdir()
    else:
        params.write_bytes(data)
    params = str(params)
    # an output: new, an input, a FIFO, a symlink to /dev/null, a folder of stale files
    def output(ext):
        o = rng.random()
        if o < 0.08:
            return params
        if o < 0.12:
            return mesh if mesh not in ("stone", "leaf") else params
        path = tmp / f"o{k}{ext}"
        if o < 0.16:
            os.mkfifo(path)
        elif o < 0.2:
            path.symlink_to("/dev/null")
        return str(path)

    size = rng.choice(["16x16", "24x8", "0x5", "100000x16", "16x16x16", "axb", "1x1"])
    # absurd counts are refused before allocating; a count that fits in memory
    # is honoured (20 000 000 takes ~7 GB and ~30 s: legitimate, left out here)
    count = str(rng.choice([0, 1, 5, -3, 10**12, 2**31, 2**40, 20_000]))
    command = COMMANDS[int(rng.integers(len(COMMANDS)))]
    if command == "info":
        argv = ["info", params]
    elif command == "convert":
        argv = ["convert", params, output(str(rng.choice([".adp", ".txt", ".csv", ".xyz"])))]
        if rng.random() < 0.5:
            argv += ["--mesh", mesh]
        if rng.random() < 0.3:
            argv += ["--quantize"]
    elif command == "random":
        argv = ["random", mesh, "-n", count if rng.random() < 0.3 else str(rng.integers(0, 50)), "-o",
                output(str(rng.choice([".adp", ".txt"]))), "--bend", str(rng.choice([0.1, 1e30, -1, 0]))]
    elif command == "render":
        argv = ["render", mesh, params, "-o", output(".png"), "--size", size, "--mode",
                str(rng.choice(["solid", "flat", "wireframe"]))]
    elif command == "bake":
        if rng.random() < 0.5:
            out = output(".npz")
        else:
            out = str(tmp / f"bk{k % 5}")  # folders that often hold an earlier bake
        argv = ["bake", mesh, params, "-o", out, "--engine", str(rng.choice(["cpu", "gpu"]))]
        if rng.random() < 0.3:
            argv += ["--overwrite"]
    elif command == "export":
        argv = ["export", mesh, params, "-o", output(".glb"), str(rng.choice(["--baked", "--instanced"]))]
    elif command == "fit":
        argv = ["fit", mesh, rng.choice([mesh, stone, params]), "-o", output(".adp")]
    else:
        argv = ["demo", "-o", output(".png"), "-n", count if rng.random() < 0.5 else "3", "--size", size]
    if "--ignore-mesh-mismatch" not in argv and command in ("render", "bake", "export") and rng.random() < 0.5:
        argv.append("--ignore-mesh-mismatch")
    return [str(a) for a in argv], {"specials": [p for p in (argv[-1], *argv) if _special(p)]}


def _special(path) -> bool:
    import os
    import stat

    try:
        st = os.lstat(path)
    except (OSError, ValueError):
        return False
    return stat.S_ISFIFO(st.st_mode) or stat.S_ISLNK(st.st_mode)


def run_command(argv: list[str], timeout: float = 30.0) -> tuple[str, float]:
    """Run one command in-process: (verdict, seconds).  'ok', 'error' or 'crash: ...'/'hang'."""
    import contextlib
    import io
    import signal

    from axialdeform.cli import main

    def alarm(signum, frame):
        raise _Hang  # a BaseException: nothing in main() catches it

    err, out = io.StringIO(), io.StringIO()
    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    t0 = time.monotonic()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            status = main(argv)
    except _Hang:
        return f"hang: over {timeout:g} s", time.monotonic() - t0
    except SystemExit as exc:  # argparse: usage errors are exit 2 with a usage message
        status = exc.code
        if status == 2:
            return "error", time.monotonic() - t0
    except BaseException as exc:  # noqa: BLE001
        return f"crash: {type(exc).__name__}: {exc}"[:300], time.monotonic() - t0
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    seconds = time.monotonic() - t0
    lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
    noise = [ln for ln in lines if not ln.startswith(f"axialdeform {argv[0]}: ") and "\r" not in ln and "it/s" not in ln
             and "inst/s" not in ln and "mesh/s" not in ln and "%|" not in ln]
    if noise:
        return f"crash: stray stderr: {noise[0]}"[:300], seconds
    errors = [ln for ln in lines if ln.startswith(f"axialdeform {argv[0]}: error")]
    if status == 0:
        return ("ok" if not errors else "crash: error line with exit 0"), seconds
    if status == 2 and len(errors) == 1:
        return "error", seconds
    return f"crash: exit {status} with {len(errors)} error lines: {err.getvalue()[-200:]!r}", seconds


def _bundled_digest() -> str:
    import hashlib

    from axialdeform.core.mesh import BUNDLED_MESHES, bundled_mesh_path

    return hashlib.sha256(b"".join(bundled_mesh_path(n).read_bytes() for n in BUNDLED_MESHES)).hexdigest()


def fuzz_commands(seconds: float, seed: int) -> int:
    import os
    import shutil
    import stat
    import tempfile

    rng = np.random.default_rng(seed)
    outcomes, per_command, failures = Counter(), Counter(), []
    slowest = (0.0, None)
    largest = 0
    mesh_texts: list = []
    end = time.monotonic() + seconds
    tried = 0
    bundled = _bundled_digest()
    with tempfile.TemporaryDirectory(prefix="fuzz-commands-") as tmp:
        prepare_folder(tmp)
        _drive(strategies()["mesh_file"], min(5.0, seconds / 10), seed, mesh_texts.append)
        while time.monotonic() < end:
            case_dir = os.path.join(tmp, f"c{tried % 20}")
            if tried % 20 == 0 or not os.path.isdir(case_dir):
                shutil.rmtree(case_dir, ignore_errors=True)
                os.makedirs(case_dir)
                prepare_folder(case_dir)
            argv, must = _command_case(rng, case_dir, mesh_texts)
            kinds = {p: os.lstat(p).st_mode for p in must["specials"]}
            for a in argv:
                try:
                    st = os.stat(a)
                    if stat.S_ISREG(st.st_mode):
                        largest = max(largest, st.st_size)
                except (OSError, ValueError):
                    pass
            verdict, took = run_command(argv)
            tried += 1
            if _bundled_digest() != bundled:  # an output replaced a file of the package itself
                verdict = "crash: a bundled mesh file was overwritten"
            per_command[argv[0]] += 1
            for p, mode in kinds.items():  # a FIFO or a symlink stays what it was
                if not os.path.lexists(p) or stat.S_IFMT(os.lstat(p).st_mode) != stat.S_IFMT(mode):
                    verdict = f"crash: {p} was replaced"
            if took > slowest[0]:
                slowest = (took, " ".join(argv[:1] + [os.path.basename(a) for a in argv[1:]]))
            outcomes[verdict.split(":")[0]] += 1
            if verdict.startswith(("crash", "hang")):
                failures.append((verdict, argv))
                if "bundled" in verdict:
                    break  # the package is damaged: nothing after this is meaningful
    peak = _peak_rss()
    print(f"fuzz commands: {tried} command lines in {seconds:g} s (seed {seed}; "
          + ", ".join(f"{c} {per_command[c]}" for c in COMMANDS) + f"): {outcomes['ok']} succeeded, "
          f"{outcomes['error']} refused with one error line (exit 2), {outcomes['crash']} crashes, "
          f"{outcomes['hang']} hangs over 30 s; slowest {slowest[0]:.1f} s ({slowest[1]}); "
          f"peak RSS {peak / 2**20:.0f} MB, largest input {largest / 2**20:.2f} MB")
    for verdict, argv in failures[:8]:
        print(f"  {verdict}: {' '.join(argv)}", file=sys.stderr)
    return 1 if failures else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0, help="how long to fuzz each target (default: %(default)s)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--target", choices=("params", "meshes", "commands", "all"), default="params")
    args = ap.parse_args(argv)
    targets = ("params", "meshes", "commands") if args.target == "all" else (args.target,)
    status = 0
    for t in targets:
        fn = {"params": fuzz_params, "meshes": fuzz_meshes, "commands": fuzz_commands}[t]
        status |= fn(args.seconds, args.seed)
    return status


if __name__ == "__main__":
    sys.exit(main())

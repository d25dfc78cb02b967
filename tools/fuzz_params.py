"""Bounded fuzzing of the parameter-file readers, the mesh readers and every command.

    python3 tools/fuzz_params.py --seconds 60 [--seed 1] [--target params|meshes|commands|all]

``params`` (the default, the first fuzzer):

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
export fit demo view bench scatter web`` and scene files given to
``render``/``bake``/``export``/``view``), each command line run in a FORKED
child (``run_isolated``: stdout/stderr captured at the descriptor level, its
own peak RSS from ``wait4`` after resetting the high-water mark through
``/proc/self/clear_refs``), with fuzzed inputs: mutated parameter files,
generated meshes, hypothesis-generated TOML scene files with hostile fields (generated layers'
recipes asking for unbounded work or numbers past the drawable bound, parts lists of 20 000 names),
height and density maps (a decompression bomb among them), outputs that are
inputs, FIFOs, symlinks to ``/dev/null``, folders of stale files, absurd
``-n``, ``--size`` and ``--port``, ``view --headless``, a tiny ``bench``,
``web --serve`` (the page is fetched, then the server gets Ctrl-C; sometimes
on a busy port), and in one case in ten BIG inputs (``--big-mb``, default
20 MB: text and binary parameter files, a binary-PLY torus from
tools/big_mesh.py, a scene file, a 1 500 x 1 500 height map).  A case must
exit 0, or exit 2 with ONE error line on stderr (plus ``warning:`` lines).
A *crash* is an exception escaping ``main``, any other stderr line, another
exit status, a FIFO or device replaced or a bundled mesh overwritten; a
*hang* is over 30 s of CPU, blocked (no CPU for 10 s) past 30 s, or running
120 s; *over the memory bound* is a peak RSS above 3x the largest input or
output (an image counts as 8 bytes a pixel) plus 500 MB.

    python3 tools/fuzz_params.py --target commands --seconds 600 --seed 16 [--commands view,web] [--log cases.txt]

Prints one summary line per target (cases, crashes, hangs, peak RSS and the
largest input) and a few examples of any failure; exit status 1 if anything
failed.
"""

from __future__ import annotations

import argparse
import os
import struct
import sys
import time
import zlib
from collections import Counter
from pathlib import Path

import numpy as np

from axialdeform.core.errors import AxialDeformError
from axialdeform.core.io import params as P
from axialdeform.core.record import is_record_width


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
    """'ok' (finite (n, w) float32 with w a record's width: 16, 19, 22, or
    10·K + 6 (+ 3, + 6) with K axes), 'error' (AxialDeformError) or 'crash: ...'."""
    try:
        out = fn(data, name)
    except AxialDeformError as exc:
        return "error" if str(exc) else "crash: empty message", None
    except BaseException as exc:  # noqa: BLE001 - that is the point of a fuzzer
        return f"crash: {type(exc).__name__}: {exc}"[:200], None
    values = out.values if isinstance(out, P.ParamFile) else out
    if not (isinstance(values, np.ndarray) and values.dtype == np.float32 and values.ndim == 2
            and is_record_width(values.shape[1]) and np.isfinite(values).all()):
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
    from pathlib import Path

    folder = Path(folder)
    if not (folder / "fifo.mtl").exists():
        os.mkfifo(folder / "fifo.mtl")
        os.mkfifo(folder / "fifo.bin")
        (folder / "m.mtl").write_text("newmtl a\nKd 1 0 0\n")


def check_mesh_file(folder, suffix: str, text: str, k: int = 0) -> str:
    """Write one generated mesh file and load it: 'ok', 'error' or 'crash: ...'."""
    from pathlib import Path

    from axialdeform.core.io.mesh import load_mesh

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


def _drive(strategy, seconds: float, seed: int, body) -> int:
    """Call ``body(example)`` for examples of ``strategy`` until ``seconds`` pass."""
    from hypothesis import HealthCheck, Phase, Verbosity, given, settings
    from hypothesis import seed as hseed

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

COMMANDS = ("info", "convert", "random", "render", "bake", "export", "fit", "demo", "view", "bench", "scatter", "web",
            "scene")
#: how often each command is drawn (bench starts fresh processes: a few seconds a case, so rarer)
WEIGHTS = {"bench": 0.25, "scene": 2.0, "scatter": 1.5, "web": 1.2}
#: a case is a hang when it uses more than this many seconds of CPU, or is blocked
#: (no CPU used for BLOCKED_S) after running this long: wall time alone measures
#: the other helpers on a shared machine (load average 8-12 during the runs)
HANG_S = 30.0
BLOCKED_S = 10.0
#: a case still running after this many seconds of wall time is killed and counted a hang
#: whatever its CPU use (``bench`` starts fresh processes and plots with matplotlib:
#: a tiny one took 35-46 s of wall time for 8 s of CPU under that load)
WALL_LIMIT_S = 120.0
#: the memory promise: peak RSS under 3x the largest input (or output) plus this
MEMORY_SLACK = 500 * 2**20


def _scene_strategy():
    """Hypothesis strategy of scene-file text (TOML): valid scenes, and hostile
    fields -- non-finite and huge numbers, wrong types, zero vectors, unknown
    keys, include cycles, FIFOs, devices, missing and big files, huge counts."""
    import json

    from hypothesis import strategies as st

    def num(valid):
        return st.one_of(st.sampled_from(valid), st.sampled_from([float("nan"), float("inf"), -1e308, 1e30, 0, -1,
                                                                   2**64, "x", True, [1, 2]]))

    def vec3(valid):
        return st.one_of(st.just(valid), st.sampled_from([[0, 0, 0], [float("nan"), 0, 1], [1e38, 1e38, 1e38], [1, 2],
                                                          "1,2,3", [1, 2, 3, 4]]))

    # file names resolved in the case folder (see _case_files); BIG_* are the big inputs
    params_file = st.sampled_from(["p.adp", "p.txt", "bad.adp", "fifo.bin", "/dev/null", "missing.adp", "m.obj",
                                   "BIG_PARAMS_TXT", "BIG_PARAMS_ADP", "sub", ""])
    mesh_file = st.sampled_from(["stone", "leaf", "stone", "m.obj", "gen.obj", "fifo.mtl", "/dev/zero", "missing.obj",
                                 "BIG_MESH", "p.adp", 7])
    image = st.sampled_from(["hm.png", "dens.png", "black.png", "bomb.png", "fifo.png", "p.adp", "missing.png",
                             "BIG_HEIGHTMAP", "/dev/zero"])

    @st.composite
    def scatter(draw):
        r = {"count": draw(st.one_of(st.integers(0, 60), st.sampled_from([-1, 2**31, 2**62, 10**30, 1.5, "9"])))}
        for key, s in (("min_distance", num([0.0, 0.05, 0.5, 1e-9])), ("align_to_normal", num([0.0, 0.5, 1.0, 2.0])),
                       ("bend", num([0.05, 0.1])), ("seed", st.sampled_from([0, 1, -1, 2**64, 1.5, "s"])),
                       ("anchor", st.sampled_from(["bottom", "center", "top", "nowhere", 3])),
                       ("scale", st.sampled_from([[0.5, 1.5], 1.0, [2, 1], [0, 1], [1e38, 1e38], [-1, 2], []])),
                       ("allow_fewer", st.sampled_from([True, False, "yes"])),
                       ("lift", st.sampled_from([[0.0, 0.5], 0.2, [1e38, 1e38], [float("inf"), 0]])),
                       ("density", image), ("surface", st.one_of(image, mesh_file)), ("nonsense", st.just(1))):
            if draw(st.integers(0, 4)) == 0:
                r[key] = draw(s)
        return r

    @st.composite
    def generate(draw):
        """A [layer.generate] recipe: sizes that asked for unbounded work (1e12 rate, 1e9 reach, a tile of 1e10),
        numbers past the drawable bound, a world far from the origin, wrong types."""
        g = {"rate": draw(st.sampled_from([1.0, 0.1, 3.0, 1e12, 4e6, 1e-300, 0, -1, "x"])),
             "extent": draw(st.sampled_from([[-8, -8, 8, 8], [-1e300, 0, 1, 1], [1e7, 1e7, 1.00001e7, 1.00001e7],
                                             [0, 0, 1, 1], [1, 1, 0, 0], "x", [-8, -8, 8]]))}
        for key, s in (("tile", st.sampled_from([8.0, 16.0, 1e10, 1e-6, 1e5, 0.5])),
                       ("reach", st.sampled_from([24.0, 2000.0, 1e9, 1e308, -1])),
                       ("bend", st.sampled_from([0.1, 1e30, [0.03, 1e30], [0.03, 0.2], -1])),
                       ("lift", st.sampled_from([[0.0, 0.1], [3e38, 3.4e38], [1, 0]])),
                       ("scale", st.sampled_from([[0.5, 1.0], [1.0, 1e30], [-5, 0]])),
                       ("min_distance", num([0.3, 0.0])), ("seed", st.sampled_from([0, 1, 2**33, -1])),
                       ("density", image), ("altitude", st.sampled_from([[0.0, 2.0], [1e30, -1e30]])),
                       ("weights", st.sampled_from([[1e308, 1e308], [1, 2], [0, 0], [-1, 1]]))):
            if draw(st.integers(0, 2)) == 0:
                g[key] = draw(s)
        return g

    @st.composite
    def layer(draw):
        d = {"mesh": draw(mesh_file)}
        if draw(st.integers(0, 6)) == 0:
            del d["mesh"]
        if draw(st.booleans()):
            d["name"] = draw(st.sampled_from(["a", "b", "a", "with space", "", "x" * 300, "ü"]))
        if draw(st.integers(0, 2)) == 0:
            d["color"] = draw(vec3([0.4, 0.5, 0.3]))
        if draw(st.integers(0, 3)) == 0:
            d["wind"] = draw(st.sampled_from([True, False, "yes"]))
        which = draw(st.integers(0, 7))
        if which <= 2:
            d["params"] = draw(params_file)
        if 2 <= which <= 5:
            d["scatter"] = draw(scatter())
        if which >= 6:  # a generated layer (one mesh, or several by weights)
            d["generate"] = draw(generate())
            if "weights" in d["generate"]:
                d["mesh"] = ["stone", "leaf"]
        if draw(st.integers(0, 6)) == 0:  # a parts list: a few names, or thousands the mesh lacks
            d["parts"] = [f"q{i}" for i in range(draw(st.sampled_from([1, 3, 20_000])))]
        return d

    @st.composite
    def scene(draw):
        top: dict = {}
        if draw(st.integers(0, 3)) == 0:
            top["up"] = draw(st.sampled_from(["x", "y", "z", "w", 1]))
        if draw(st.integers(0, 5)) == 0:
            top["include"] = draw(st.sampled_from(["inc.toml", ["inc.toml"], ["SELF"], ["missing.toml"], ["fifo.toml"],
                                                   [1], "BIG_SCENE"]))
        if draw(st.integers(0, 4)) == 0:
            top["background"] = draw(vec3([0.9, 0.9, 0.9]))
        if draw(st.integers(0, 2)) == 0:
            t = {draw(st.sampled_from(["heightmap", "heightmap", "mesh"])): draw(st.one_of(image, mesh_file))}
            for key, s in (("height_scale", num([1.0, 4.0])), ("extent", st.sampled_from([10.0, [10, 8], [0, 1], -2])),
                           ("color", vec3([0.3, 0.4, 0.2])), ("mesh", mesh_file)):
                if draw(st.integers(0, 3)) == 0:
                    t[key] = draw(s)
            top["terrain"] = t
        if draw(st.integers(0, 3)) == 0:
            top["camera"] = {k: draw(s) for k, s in (("elevation", num([30.0, 90.0, -90.0])), ("azimuth", num([20.0])),
                                                      ("fov", num([35.0, 0.001, 179.9, 180.0])), ("eye", vec3([0, 5, 10])),
                                                      ("target", vec3([0, 0, 0]))) if draw(st.booleans())}
        if draw(st.integers(0, 3)) == 0:
            top["light"] = {"direction": draw(vec3([0.3, 0.8, 0.4])), "ambient": draw(num([0.3, 1.0]))}
        if draw(st.integers(0, 3)) == 0:
            top["wind"] = {k: draw(s) for k, s in (("direction", vec3([1, 0, 0])), ("strength", num([0.1, 1.0])),
                                                    ("gustiness", num([0.2])), ("frequency", num([0.5])),
                                                    ("wavelength", num([4.0, 0.0]))) if draw(st.booleans())}
        top["layer"] = draw(st.lists(layer(), max_size=3))
        if draw(st.integers(0, 8)) == 0:
            top[draw(st.sampled_from(["bogus", "Layer"]))] = 1
        text = _toml(top)
        if draw(st.integers(0, 8)) == 0:  # broken TOML
            text = text[: draw(st.integers(0, len(text)))] + draw(st.sampled_from(["", "[[", "= 1", "\x00", "'''"]))
        return text

    def _value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float):
            return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(v), repr(v))
        if isinstance(v, int):
            return str(v)
        if isinstance(v, str):
            return json.dumps(v)
        return "[" + ", ".join(_value(x) for x in v) + "]"

    def _toml(top):
        lines = [f"{k} = {_value(v)}" for k, v in top.items() if not isinstance(v, dict) and k != "layer"]
        for k, v in top.items():
            if isinstance(v, dict):
                lines += [f"[{k}]"] + [f"{kk} = {_value(vv)}" for kk, vv in v.items()]
        for lay in top.get("layer", []):
            lines.append("[[layer]]")
            lines += [f"{k} = {_value(v)}" for k, v in lay.items() if k not in ("scatter", "generate")]
            for table in ("scatter", "generate"):
                if table in lay:
                    lines.append(f"[layer.{table}]")
                    lines += [f"{k} = {_value(v)}" for k, v in lay[table].items()]
        return "\n".join(lines) + "\n"

    return scene()


def scene_strategy():
    """Hypothesis strategy of scene-file text (TOML, names resolved by :func:`case_files`)."""
    global _SCENES
    if _SCENES is None:
        _SCENES = _scene_strategy()
    return _SCENES


_SCENES = None


def _png(path, array) -> None:
    from PIL import Image

    Image.fromarray(array).save(path)


def make_big_inputs(folder, mb: float = 20.0) -> dict:
    """Big inputs, made once: ``{name: path}`` -- text and binary parameter
    files for the stone of about ``mb`` MB, a torus mesh of about ``mb`` MB
    (binary PLY, tools/big_mesh.py), a scene file of about ``mb`` MB
    (comments and a big array) naming the big parameters, and a height map
    of about 1 500 x 1 500 pixels."""
    import sys as _sys
    from pathlib import Path

    import trimesh

    from axialdeform.core.io.mesh import load_mesh
    from axialdeform.core.io.params import write_params
    from axialdeform.core.variation import random_params

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    stone = load_mesh("stone")
    rows_txt = int(mb * 2**20 / 170)  # ~170 bytes a text row
    out["BIG_PARAMS_TXT"] = folder / "big.txt"
    write_params(out["BIG_PARAMS_TXT"], random_params(stone, rows_txt, seed=5), stone)
    out["BIG_PARAMS_ADP"] = folder / "big.adp"
    write_params(out["BIG_PARAMS_ADP"], random_params(stone, int(mb * 2**20 / 64), seed=6), stone)
    _sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from big_mesh import torus

    pos, faces = torus(int(mb * 2**20 / 20))  # binary PLY: ~20 bytes a face (with its half vertex)
    out["BIG_MESH"] = folder / "big.ply"
    trimesh.Trimesh(pos, faces, process=False).export(out["BIG_MESH"])
    out["BIG_SCENE"] = folder / "big.toml"
    filler = "# " + "x" * 98 + "\n"
    with open(out["BIG_SCENE"], "w") as fh:
        fh.write(filler * int(mb * 2**20 / 2 / len(filler)))
        fh.write("background = [" + ", ".join(["0.5"] * int(mb * 2**20 / 2 / 5)) + "]\n")
        fh.write(f'[[layer]]\nname = "big"\nmesh = "stone"\nparams = "{out["BIG_PARAMS_ADP"]}"\n')
    rng = np.random.default_rng(7)
    out["BIG_HEIGHTMAP"] = folder / "big-hm.png"
    _png(out["BIG_HEIGHTMAP"], (rng.random((1500, 1500)) * 255).astype(np.uint8))
    out["BOMB"] = folder / "bomb.png"  # a decompression bomb: 16 000 x 12 000 black pixels in ~190 kB
    _png(out["BOMB"], np.zeros((12000, 16000), np.uint8))
    return {k: str(v) for k, v in out.items()}


def case_files(folder, big: dict) -> None:
    """The files generated cases and scenes refer to, in ``folder``: small
    valid parameter files, a mesh, height and density maps, FIFOs, a
    decompression-bomb PNG (16 000 x 12 000 black), an include file."""
    from pathlib import Path

    from axialdeform.core.io.mesh import bundled_mesh_path, load_mesh
    from axialdeform.core.io.params import write_params
    from axialdeform.core.variation import random_params

    folder = Path(folder)
    prepare_folder(folder)
    stone = load_mesh("stone")
    v = random_params(stone, 5, seed=1)
    write_params(folder / "p.adp", v, stone)
    write_params(folder / "p.txt", v, stone)
    (folder / "bad.adp").write_bytes(b"ADPARAMS" + b"\x00" * 40)
    (folder / "m.obj").write_bytes(bundled_mesh_path("stone").read_bytes())
    (folder / "gen.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
    rng = np.random.default_rng(3)
    _png(folder / "hm.png", (rng.random((24, 32)) * 255).astype(np.uint8))
    _png(folder / "dens.png", (rng.random((8, 8)) * 255).astype(np.uint8))
    _png(folder / "black.png", np.zeros((4, 4), np.uint8))
    os.link(big["BOMB"], folder / "bomb.png")  # made once (encoding it takes seconds)
    for name in ("fifo.png", "fifo.toml", "fifo.adp"):
        os.mkfifo(folder / name)
    (folder / "sub").mkdir()
    (folder / "inc.toml").write_text('[[layer]]\nname = "inc"\nmesh = "stone"\nparams = "p.adp"\n')


def gltf_with_nodes(path, nodes: list, scene_nodes: list) -> str:
    """A one-triangle glTF (data-URI buffer) with the node graph ``nodes`` and the
    scene's root nodes ``scene_nodes``: hostile graphs for the fuzzer and the tests."""
    import base64
    import json

    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    buf = pos + np.array([0, 1, 2], np.uint16).tobytes() + b"\0\0"
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": scene_nodes}], "nodes": nodes,
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "buffers": [{"byteLength": len(buf),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                           {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                          "min": [0, 0, 0], "max": [1, 1, 0]},
                         {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(json.dumps(doc))
    return str(path)


def _node_graph_gltf(path, kind: str) -> str:
    """A glTF whose node graph is hostile: a chain of 1 500 nested nodes, or a cycle."""
    if kind == "chain":
        nodes = [{"children": [i + 1], "translation": [0.001, 0, 0]} for i in range(1499)] + [{"mesh": 0}]
    else:
        nodes = [{"children": [1]}, {"children": [2], "mesh": 0}, {"children": [1]}]
    return gltf_with_nodes(path, nodes, [0])


def _textured_obj(folder, k: int, texture: str) -> str:
    """An OBJ whose material names ``texture``: an image bomb, or a file outside the model's folder."""
    (folder / f"t{k}.mtl").write_text(f"newmtl T\nKd 1 1 1\nmap_Kd {texture}\n")
    obj = folder / f"t{k}.obj"
    obj.write_text(f"mtllib t{k}.mtl\nv 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                   "usemtl T\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    return str(obj)


def _resolve_scene(text: str, big: dict) -> str:
    for key, path in big.items():
        if key == "BOMB":
            continue
        text = text.replace(f'"{key}"', f'"{path}"')
    return text


def _command_case(rng: np.random.Generator, tmp, mesh_texts: list, scene_texts: list, big: dict,
                  command: str | None = None) -> tuple[list[str], dict]:
    """One fuzzed command line and what must hold afterwards:
    ``{"specials": [paths that must stay FIFOs/symlinks], "inputs": [files read],
    "outputs": [paths it may write], "serve": None | "probe" | port held busy}``."""
    from pathlib import Path

    from axialdeform.core.io.mesh import bundled_mesh_path

    tmp = Path(tmp)
    k = int(rng.integers(1 << 30))
    stone = str(bundled_mesh_path("stone"))
    big_case = rng.random() < 0.1
    inputs: list = []
    axes_file = None
    # a mesh: bundled, copied, generated (possibly hostile), or big
    pick = rng.integers(5)
    if big_case and rng.random() < 0.4:
        mesh = big["BIG_MESH"]
    elif pick == 0 and mesh_texts:
        suffix, text = mesh_texts[int(rng.integers(len(mesh_texts)))]
        mesh = tmp / f"m{k}{suffix}"
        mesh.write_text(text, encoding="utf-8", errors="surrogateescape")
        mesh = str(mesh)
    elif pick == 1:
        mesh = str(tmp / "m.obj")
    elif pick == 2 and rng.random() < 0.5:  # the classes rounds three and four added
        hostile = int(rng.integers(6))
        if hostile < 2:  # node graphs
            mesh = _node_graph_gltf(tmp / f"g{k}.gltf", "chain" if hostile == 0 else "cycle")
        elif hostile < 4:  # image bombs, escapes
            mesh = _textured_obj(tmp, k, "bomb.png" if hostile == 2 else str(rng.choice(["../p.adp", "/etc/hostname"])))
        elif hostile == 4:  # an instanced GLB whose AXIALDEFORM_bend, attributes or instances are corrupted
            import fuzz_specs

            bases = big["EXT_BASES"].split(os.pathsep)
            doc, blob = fuzz_specs.split_glb(Path(bases[int(rng.integers(len(bases)))]).read_bytes())
            doc, blob, _ = fuzz_specs.mutate_extension(doc, blob, rng)
            mesh = tmp / f"x{k}.glb"
            mesh.write_bytes(fuzz_specs.join_glb(doc, blob))
            mesh = str(mesh)
        else:  # the bundled tree with a corrupted --axes file
            import fuzz_specs
            import tomllib

            entries, _ = fuzz_specs.mutate_axes(tomllib.loads(fuzz_specs.TREE_AXES.read_text())["axis"], rng)
            axes_file = tmp / f"ax{k}.toml"
            axes_file.write_text(fuzz_specs.axes_toml(entries))
            mesh = "tree"
    else:
        mesh = str(rng.choice(["stone", "leaf", stone]))
    inputs.append(mesh)
    # parameters: valid, mutated, huge values, big, or a special file
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
    if big_case and rng.random() < 0.7:
        src = big[str(rng.choice(["BIG_PARAMS_TXT", "BIG_PARAMS_ADP"]))]
        if rng.random() < 0.3:  # a big file with one bad token or flipped byte somewhere in it
            blob = bytearray(Path(src).read_bytes())
            i = int(rng.integers(len(blob)))
            blob[i:i + 1] = rng.choice([b"nan", b"\xff", b"x", b"1e39", b"\n\n", b"\x00"])
            params = tmp / f"p{k}{Path(src).suffix}"
            params.write_bytes(bytes(blob))
            del blob
        else:
            params = Path(src)
    elif special < 0.04:
        os.mkfifo(params)
    elif special < 0.08:
        params.symlink_to(str(rng.choice(["/dev/null", "/dev/zero"])))
    elif special < 0.1:
        params.mkdir()
    else:
        params.write_bytes(data)
    params = str(params)
    inputs.append(params)
    outputs: list = []

    # an output: new, an input, a FIFO, a symlink to /dev/null, a folder
    def output(ext):
        o = rng.random()
        if o < 0.06:
            return params
        if o < 0.1:
            return mesh if mesh not in ("stone", "leaf") else params
        path = tmp / f"o{k}{ext}"
        if o < 0.14:
            os.mkfifo(path)
        elif o < 0.18:
            path.symlink_to("/dev/null")
        elif o < 0.2:
            path.mkdir()
        elif o < 0.22:
            return str(tmp / "missing-folder" / f"o{k}{ext}")
        outputs.append(str(path))
        return str(path)

    def pick(*choices):
        return str(choices[int(rng.integers(len(choices)))])

    size = pick("16x16", "24x8", "0x5", "100000x16", "16x16x16", "axb", "1x1", "-4x4")
    # absurd counts are refused before allocating; a count that fits in memory
    # is honoured (20 000 000 takes ~7 GB and ~30 s: legitimate, left out here)
    count = pick(0, 1, 5, -3, 10**12, 2**31, 2**40, 20_000)
    serve = None
    if command is None:
        names = list(COMMANDS)
        w = np.array([WEIGHTS.get(c, 1.0) for c in names])
        command = names[int(rng.choice(len(names), p=w / w.sum()))]
    if command == "info":
        argv = ["info", params]
    elif command == "convert":
        argv = ["convert", params, output(pick(".adp", ".txt", ".csv", ".xyz"))]
        if rng.random() < 0.5:
            argv += ["--mesh", mesh]
        if rng.random() < 0.3:
            argv += ["--quantize"]
    elif command == "random":
        argv = ["random", mesh, "-n", count if rng.random() < 0.3 else str(rng.integers(0, 50)), "-o",
                output(pick(".adp", ".txt")), "--bend", pick(0.1, 1e30, -1, 0)]
        if big_case:
            argv[3] = str(int(rng.integers(100_000, 400_000)))  # a big output
        if rng.random() < 0.2:  # the tree options: a sag toward the world's down
            argv += ["--droop", pick("0.2", "-1", "nan", "1e30", "0")]
    elif command == "render":
        argv = ["render", mesh, params, "-o", output(".png"), "--size", size, "--mode",
                pick("solid", "flat", "wireframe")]
    elif command == "bake":
        if rng.random() < 0.5:
            out = output(".npz")
        else:
            out = str(tmp / f"bk{k % 5}")  # folders that often hold an earlier bake
            outputs.append(out)
        argv = ["bake", mesh, params, "-o", out, "--engine", pick("cpu", "gpu")]
        if rng.random() < 0.3:
            argv += ["--overwrite"]
        if rng.random() < 0.1 and os.path.isdir(out):  # the input mesh is one of the folder's instance files
            import shutil

            own = Path(out) / "instance_000001.obj"
            shutil.copy(stone, own)
            argv[1] = str(own)
            inputs.append(str(own))
            argv += ["--overwrite", "--ignore-mesh-mismatch"]
    elif command == "export":
        argv = ["export", mesh, params, "-o", output(".glb"), pick("--baked", "--instanced")]
    elif command == "fit":
        argv = ["fit", mesh, str(rng.choice([mesh, stone, params])), "-o", output(".adp")]
    elif command == "demo":
        argv = ["demo", "-o", output(".png"), "-n", count if rng.random() < 0.5 else "3", "--size", size]
    elif command == "view":
        argv = ["view", mesh] + ([params] if rng.random() < 0.6 else ["-n", count if rng.random() < 0.3 else "50"])
        argv += ["--headless", "--frames", pick(1, 2, 1, 0, -1), "--size", size if rng.random() < 0.5 else "32x24",
                 "--mode", pick("solid", "flat", "wireframe")]
        for flag, values in (("--screenshot", None), ("--wind", ("0.2", "0.1,0.5,1,3", "nan", "1e30", "a", "1,2,3,4,5")),
                             ("--wind-dir", ("1,0,0", "0,0,0", "nan,0,0", "1,2")), ("--seed", ("0", "-1", str(2**70))),
                             ("--bend", ("0.1", "1e30", "nan")), ("--part", ("nope", "stone", "")),
                             ("--up", ("x", "z")), ("--lod-error", ("1", "0", "-1", "nan"))):
            if rng.random() < 0.2:
                argv += [flag, output(".png") if values is None else pick(*values)]
        for flag in ("--fast", "--no-ground", "--no-lod", "--lod", "--no-cull"):
            if rng.random() < 0.15:
                argv.append(flag)
    elif command == "bench":
        if rng.random() < 0.2:
            src = str(rng.choice([params, str(tmp / "missing.json"), str(tmp / "fifo.bin"), str(tmp / "bench.json")]))
            if src.endswith("bench.json") and not os.path.exists(src):
                Path(src).write_text(str(rng.choice(['{"records": []}', "{", "[]", '{"records": [{"count": "x"}]}'])))
            inputs.append(src)
            argv = ["bench", "--report-from", src] + (["--out", output("")] if rng.random() < 0.5 else [])
        else:
            out = output("") if rng.random() < 0.3 else str(tmp / f"bench{k % 3}")
            outputs.append(out)
            argv = ["bench", "--mesh", mesh if not big_case else "stone", "--counts",
                    pick("10", "10", "0", "-5", "a", "3,7", ","), "--repeats", pick(1, 1, 0, -1), "--frames",
                    pick(1, 1, 0, -2), "--warmup", pick(0, 0, 1, -1), "--size", pick("16x16", "16x16", "0x0", "axb"),
                    "--methods", pick("axial", "axial", "same", "nope", ","), "--modes", pick("solid", "wireframe", "x"),
                    "--samples", pick(0, 0, 4, -1, 1000), "--no-leaf", "--no-throughput", "--no-progress",
                    "--out", out, "--cache", str(tmp / "bench-cache")]
    elif command == "scatter":
        surface = pick("hm.png", "dens.png", "black.png", "bomb.png", "fifo.png", "m.obj", "gen.obj", "p.adp",
                       "missing.png")
        surface = str(tmp / surface) if rng.random() < 0.85 else pick(mesh, big["BIG_HEIGHTMAP"], big["BIG_MESH"], "/dev/zero")
        if big_case:
            surface = pick(big["BIG_HEIGHTMAP"], big["BIG_MESH"])
        inputs.append(surface)
        argv = ["scatter", surface, mesh, "-n", count if rng.random() < 0.3 else pick(0, 1, 20, 200), "-o",
                output(pick(".adp", ".txt"))]
        for flag, values in (("--min-distance", ("0.1", "0", "-1", "nan", "1e-12", "1e30")),
                             ("--density", (str(tmp / "dens.png"), str(tmp / "black.png"), str(tmp / "fifo.png"),
                                            str(tmp / "bomb.png"), params, "/dev/zero")),
                             ("--align-to-normal", ("0.5", "2", "nan", "-1")), ("--scale", ("0.5:2", "2:1", "a", "0:0", "nan:1")),
                             ("--bend", ("0.1", "1e30", "nan")), ("--seed", ("0", "-1", str(2**64))),
                             ("--up", ("x", "z")), ("--height-scale", ("2", "0", "-1", "1e30", "nan")),
                             ("--extent", ("10", "10,5", "0", "-1,2", "nan", "1,2,3")),
                             ("--anchor", ("bottom", "top", "center"))):
            if rng.random() < 0.25:
                argv += [flag, pick(*values)]
        for flag in ("--allow-fewer", "--quantize"):
            if rng.random() < 0.3:
                argv.append(flag)
    elif command == "web" and rng.random() < 0.15:  # the inputs live in the output folder (round three)
        import shutil

        site = tmp / f"site{k}"
        site.mkdir(exist_ok=True)
        if os.path.isfile(params):
            shutil.copy(params, site / "params.adp")
            params = str(site / "params.adp")
            inputs.append(params)
        if rng.random() < 0.5:
            (site / "index.html").write_text("<h1>the user's own page</h1>")
            inputs.append(str(site / "index.html"))
        argv = ["web", mesh, params, "-o", str(site)] + (["--overwrite"] if rng.random() < 0.5 else [])
    elif command == "web":
        if rng.random() < 0.15:
            argv = ["web", "-o", pick(str(tmp / "w-served"), str(tmp / "missing"), params, str(tmp / "fifo.bin"))]
        else:
            argv = ["web", mesh, params, "-o", output(pick("", ".html", ".htm", ".png"))]
        argv += ["--size", size if rng.random() < 0.3 else "64x48"]
        for flag, values in (("--up", ("x", "z")), ("--mode", ("flat",))):
            if rng.random() < 0.2:
                argv += [flag, pick(*values)]
        for flag in ("--float32", "--ignore-mesh-mismatch"):
            if rng.random() < 0.3:
                argv.append(flag)
        if rng.random() < 0.35:
            argv += ["--serve", "--port", pick(0, 0, "BUSY", 70000, -1, 80)]
            serve = "probe"
            if "BUSY" in argv:
                serve = "busy"
    else:  # a scene file given to render, bake, export or view
        text = scene_texts[int(rng.integers(len(scene_texts)))] if scene_texts else "[[layer]]\nmesh = \"stone\"\n"
        if big_case and rng.random() < 0.5:
            scene = big["BIG_SCENE"]
        elif rng.random() < 0.1:  # bounded structure (round three): an include chain of 40, or 600 nested arrays
            if rng.random() < 0.5:
                for i in range(40):
                    (tmp / f"chain{k}-{i}.toml").write_text(f'include = ["chain{k}-{i + 1}.toml"]\n' if i < 39 else
                                                            '[[layer]]\nname = "a"\nmesh = "stone"\nparams = "p.adp"\n')
                scene = str(tmp / f"chain{k}-0.toml")
            else:
                scene = tmp / f"deep{k}.toml"
                scene.write_text("x = " + "[" * 600 + "]" * 600 + "\n")
                scene = str(scene)
        else:
            scene = tmp / f"s{k}.toml"
            scene.write_text(_resolve_scene(text, big).replace('"SELF"', f'"{scene.name}"'), encoding="utf-8",
                             errors="surrogateescape")
            scene = str(scene)
        inputs.append(scene)
        for name in ("BIG_PARAMS_TXT", "BIG_PARAMS_ADP", "BIG_MESH", "BIG_HEIGHTMAP", "BIG_SCENE"):
            if f'"{name}"' in text:
                inputs.append(big[name])
        sub = pick("render", "render", "bake", "export", "view")
        if sub == "render":
            argv = ["render", scene, "-o", output(".png"), "--size", size if rng.random() < 0.3 else "32x24",
                    "--mode", pick("solid", "flat", "wireframe")]
        elif sub == "bake":
            argv = ["bake", scene, "-o", output(pick(".npz", ".npz", ""))]
        elif sub == "export":
            argv = ["export", scene, "-o", output(".glb")] + (["--instanced"] if rng.random() < 0.1 else [])
        else:
            argv = ["view", scene, "--headless", "--frames", "1", "--size", "32x24"]
        if sub in ("render", "bake") and rng.random() < 0.2:
            argv += ["--time", pick("1.5", "nan", "1e30")]
        if sub in ("render", "bake", "view") and rng.random() < 0.15:
            argv += ["--wind", pick("0.2", "nan", "1e30")]
        command = f"scene-{sub}"
    if command in ("render", "bake", "export") and rng.random() < 0.5:
        argv.append("--ignore-mesh-mismatch")
    if command in ("random", "render", "bake", "export", "view", "web", "info") and rng.random() < 0.1:
        argv += ["--parts", pick("trunk", "nope", ",", "trunk,branch1", "stone", "\u00eele,water")]  # parts at load
    if axes_file is not None and command in ("random", "render", "bake", "export", "fit", "view", "web"):
        argv += ["--axes", str(axes_file)]
        inputs.append(str(axes_file))
    argv = [str(a) for a in argv]
    specials = [p for p in argv if _special(p)]
    return argv, {"command": command, "specials": specials, "inputs": [i for i in inputs if i],
                  "outputs": outputs, "serve": serve, "big": big_case}


def _special(path) -> bool:
    import stat

    try:
        st = os.lstat(path)
    except (OSError, ValueError):
        return False
    return stat.S_ISFIFO(st.st_mode) or stat.S_ISLNK(st.st_mode)


def input_bytes(path) -> int:
    """What an input holds: a regular file's size; an image's decoded grey
    pixels (8 bytes each: the float64 height grid it claims to hold); else 0."""
    import stat

    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return 0
    if not stat.S_ISREG(st.st_mode):
        return 0
    if str(path).lower().endswith((".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")):
        try:
            from PIL import Image

            with Image.open(path) as img:
                return max(st.st_size, img.size[0] * img.size[1] * 8)
        except Exception:  # noqa: BLE001 - not an image: its bytes
            return st.st_size
    return st.st_size


def output_bytes(path) -> int:
    """Bytes written at ``path`` (a file, or the files of a folder)."""

    if os.path.isfile(path) and not os.path.islink(path):
        return os.path.getsize(path)
    if os.path.isdir(path) and not os.path.islink(path):
        return sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(path) for f in fs
                   if os.path.isfile(os.path.join(d, f)))
    return 0


def _rss_of(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status", "rb") as fh:
            for line in fh:
                if line.startswith(b"VmRSS:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError):
        pass
    return 0


def _group_cpu(pgid: int) -> float:
    """Seconds of CPU used so far by the processes of group ``pgid`` (a child and its children)."""

    tick = os.sysconf("SC_CLK_TCK")
    total = 0
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as fh:
                fields = fh.read().rsplit(b")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid:  # fields after the name: state ppid pgrp ... utime(11) stime(12)
            total += int(fields[11]) + int(fields[12])
    return total / tick


def _child(argv: list[str], result_path: str) -> None:
    """In the forked child: run ``main(argv)``; never returns."""
    import json
    import signal
    import traceback

    code, how = 70, "exception"
    try:
        os.setpgid(0, 0)  # its own process group: a hang takes bench's children with it
        # what the command prints goes to fds 1 and 2 (pytest's or anyone's capture objects are not inherited)
        sys.stdout = open(1, "w", encoding="utf-8", errors="backslashreplace", closefd=False)
        sys.stderr = open(2, "w", encoding="utf-8", errors="backslashreplace", closefd=False)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        try:
            with open("/proc/self/clear_refs", "w") as fh:
                fh.write("5")  # peak RSS from here on, not the fuzzer's own
        except OSError:
            pass
        from axialdeform.cli import main

        try:
            code, how = main(argv), "returned"
        except SystemExit as exc:  # argparse: usage errors are exit 2 with a usage message
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            how = "argparse"
        except BaseException:  # noqa: BLE001
            traceback.print_exc()
        with open(result_path, "w") as fh:
            json.dump({"code": code, "how": how}, fh)
    finally:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(0)


def run_isolated(argv: list[str], timeout: float = HANG_S, serve: str | None = None, rss_cap: int = 8 * 2**30,
                 wall_limit: float = WALL_LIMIT_S) -> dict:
    """Run ``axialdeform ARGV`` in a forked child with stdin from /dev/null and
    stdout/stderr captured at the file-descriptor level (so any library's
    stray output is seen).  Returns ``{"verdict", "seconds", "peak_rss",
    "stdout", "stderr"}``; the verdict is 'ok' (exit 0), 'error' (exit 2 and
    ONE error line on stderr, or an argparse usage error), 'hang: ...'
    (killed after ``timeout`` s) or 'crash: ...' (an exception out of
    ``main``, a stray stderr line, any other exit, a kill by a signal, RSS
    over ``rss_cap``).  Call it from a process that holds no GL context
    (llvmpipe's threads do not survive ``fork``: a child that makes its own
    context can block forever) -- the fuzzer's own process never makes one;
    tests run the fuzzer in a fresh process.  A hang: over ``timeout`` s of CPU, blocked (no CPU
    for :data:`BLOCKED_S`) after ``timeout`` s, or running ``wall_limit`` s.  With ``serve`` ('probe' or 'busy'), the page is
    fetched once the URL is printed, then the server is stopped with SIGINT
    (Ctrl-C), which must end it with exit 0."""
    import json
    import signal
    import socket
    import tempfile
    import urllib.request

    busy = None
    if serve == "busy":
        busy = socket.socket()
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        argv = [str(busy.getsockname()[1]) if a == "BUSY" else a for a in argv]
    fd_out, out_path = tempfile.mkstemp(prefix="fuzz-out-")
    fd_err, err_path = tempfile.mkstemp(prefix="fuzz-err-")
    result_path = out_path + ".json"
    sys.stdout.flush()
    sys.stderr.flush()
    t0 = time.monotonic()
    pid = os.fork()
    if pid == 0:
        null = os.open(os.devnull, os.O_RDONLY)
        os.dup2(null, 0)
        os.dup2(fd_out, 1)
        os.dup2(fd_err, 2)
        _child(argv, result_path)
    os.close(fd_out)
    os.close(fd_err)
    verdict, killed, fetched, peak_seen = None, False, None, 0
    cpu, cpu_at, next_sample = 0.0, t0, t0 + 1.0
    try:
        while True:
            done, status, usage = os.wait4(pid, os.WNOHANG)
            if done:
                break
            now = time.monotonic()
            took = now - t0
            peak_seen = max(peak_seen, _rss_of(pid))
            if now >= next_sample:
                used = _group_cpu(pid)
                if used > cpu + 0.05:
                    cpu, cpu_at = used, now
                next_sample = now + 1.0
            hang = None
            if cpu > timeout:
                hang = f"hang: over {timeout:g} s of CPU"
            elif took > timeout and now - cpu_at > BLOCKED_S:
                hang = f"hang: blocked (no CPU for {BLOCKED_S:g} s) after {took:.0f} s"
            elif took > wall_limit:
                hang = f"hang: still running after {wall_limit:g} s"
            if peak_seen > rss_cap and not killed:
                verdict, killed = f"crash: RSS over {rss_cap / 2**30:.0f} GB", True
                os.killpg(pid, signal.SIGKILL)
            elif hang and not killed:
                verdict, killed = hang, True
                os.killpg(pid, signal.SIGKILL)
            elif serve and fetched is None:
                with open(out_path, encoding="utf-8", errors="replace") as fh:
                    text = fh.read()
                url = next((w for w in text.split() if w.startswith("http://127.0.0.1:")), None)
                if url:
                    try:
                        with urllib.request.urlopen(url, timeout=10) as resp:
                            fetched = f"HTTP {resp.status}, {len(resp.read())} bytes"
                    except Exception as exc:  # noqa: BLE001
                        fetched = f"failed: {exc}"
                    os.kill(pid, signal.SIGINT)
            time.sleep(0.02)
        seconds = time.monotonic() - t0
        with open(out_path, encoding="utf-8", errors="replace") as fh:
            stdout = fh.read()
        with open(err_path, encoding="utf-8", errors="replace") as fh:
            stderr = fh.read()
        try:
            with open(result_path) as fh:
                result = json.load(fh)
        except (OSError, ValueError):
            result = None
    finally:
        for p in (out_path, err_path, result_path):
            try:
                os.unlink(p)
            except OSError:
                pass
        if busy is not None:
            busy.close()
    peak = usage.ru_maxrss * 1024
    out = {"seconds": seconds, "cpu": usage.ru_utime + usage.ru_stime, "peak_rss": peak, "stdout": stdout,
           "stderr": stderr}
    if verdict is None:
        verdict = _verdict(argv, status, result, stderr)
    if verdict == "ok" and serve and (fetched is None or not fetched.startswith("HTTP 200")):
        verdict = f"crash: --serve printed a URL but the page was not served ({fetched})"
    out["verdict"] = verdict
    return out


def _verdict(argv, status, result, stderr) -> str:

    if os.WIFSIGNALED(status):
        return f"crash: killed by signal {os.WTERMSIG(status)}: {stderr[-200:]!r}"
    if result is None:
        return f"crash: no result (exit {os.WEXITSTATUS(status)}): {stderr[-200:]!r}"
    if result["how"] == "exception":
        last = [ln for ln in stderr.splitlines() if ln.strip()][-1:] or ["?"]
        return f"crash: {last[0]}"[:300]
    if result["how"] == "argparse":
        return "error" if result["code"] == 2 else ("ok" if result["code"] == 0 else f"crash: argparse exit {result['code']}")
    code = result["code"] or 0
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    noise = [ln for ln in lines if not ln.startswith(f"axialdeform {argv[0]}: ") and "\r" not in ln and "it/s" not in ln
             and "inst/s" not in ln and "mesh/s" not in ln and "%|" not in ln]
    if noise:
        return f"crash: stray stderr: {noise[0]}"[:300]
    errors = [ln for ln in lines if ln.startswith(f"axialdeform {argv[0]}: error")]
    if code == 0:
        return "ok" if not errors else "crash: error line with exit 0"
    if code == 2 and len(errors) == 1:
        return "error"
    return f"crash: exit {code} with {len(errors)} error lines: {stderr[-200:]!r}"


def _read_inputs(argv: list, inputs: list) -> list:
    """The inputs this command line reads: named in it, and not as its output
    (``-o``, or convert's second file); files a command only writes may change."""
    outs = set()
    for flag in ("-o", "--screenshot"):  # what a command writes (view's --screenshot too)
        if flag in argv:
            outs.add(argv[argv.index(flag) + 1])
    if argv and argv[0] == "convert" and len(argv) > 2:
        outs.add(argv[2])
    return [p for p in inputs if p in argv and p not in outs]


def _digests(paths, limit: int = 64 << 20) -> dict:
    """SHA-256 of each regular input file up to ``limit`` bytes (None: gone)."""
    import hashlib
    import stat as st

    out = {}
    for p in paths:
        try:
            info = os.stat(p)
        except OSError:
            if p in out or os.path.lexists(p):
                out[p] = None
            continue
        if st.S_ISREG(info.st_mode) and info.st_size <= limit:
            with open(p, "rb") as fh:
                out[p] = hashlib.sha256(fh.read()).hexdigest()
    return out


def run_command(argv: list[str], timeout: float = HANG_S) -> tuple[str, float]:
    """``(verdict, seconds)`` of one command line run in a forked child (see :func:`run_isolated`)."""
    r = run_isolated(argv, timeout)
    return r["verdict"], r["seconds"]


def _bundled_digest() -> str:
    import hashlib

    from axialdeform.core.io.mesh import BUNDLED_MESHES, bundled_mesh_path

    return hashlib.sha256(b"".join(bundled_mesh_path(n).read_bytes() for n in BUNDLED_MESHES)).hexdigest()


def fuzz_commands(seconds: float, seed: int, only: tuple = (), big_mb: float = 20.0, log=None,
                  cases: int | None = None, cycle: bool = False) -> int:
    """Fuzz every command (or ``only`` these) for ``seconds`` (or until ``cases``
    command lines ran); ``cycle``: the commands in turn, else drawn at random
    (:data:`WEIGHTS`).  Prints the figures per command; returns 1 if any case failed."""
    import shutil
    import stat
    import tempfile

    import trimesh  # noqa: F401

    # what the children use, imported once here (the fork shares it); no GL context in this process
    import axialdeform.cli  # noqa: F401
    import axialdeform.cli._common  # noqa: F401
    import axialdeform.gl.renderer  # noqa: F401

    rng = np.random.default_rng(seed)
    stats: dict = {}
    failures = []
    mesh_texts: list = []
    scene_texts: list = []
    end = time.monotonic() + seconds
    tried = 0
    bundled = _bundled_digest()
    with tempfile.TemporaryDirectory(prefix="fuzz-commands-") as tmp:
        big = make_big_inputs(os.path.join(tmp, "big"), big_mb)
        import fuzz_specs  # round four: instanced GLBs to corrupt

        big["EXT_BASES"] = os.pathsep.join(str(p) for p in fuzz_specs.make_bases(Path(tmp) / "ext-bases"))
        _drive(strategies()["mesh_file"], min(3.0, seconds / 20), seed, mesh_texts.append)
        _drive(scene_strategy(), min(3.0, seconds / 20), seed, scene_texts.append)
        while time.monotonic() < end and (cases is None or tried < cases):
            case_dir = os.path.join(tmp, f"c{tried % 20}")
            if tried % 20 == 0 or not os.path.isdir(case_dir):
                shutil.rmtree(case_dir, ignore_errors=True)
                os.makedirs(case_dir)
                case_files(case_dir, big)
            pool = only or COMMANDS
            command = pool[tried % len(pool)] if cycle else (str(rng.choice(only)) if only else None)
            argv, must = _command_case(rng, case_dir, mesh_texts, scene_texts, big, command=command)
            kinds = {p: os.lstat(p).st_mode for p in must["specials"]}
            before = _digests(_read_inputs(argv, must["inputs"]))  # nothing lost: no input changes (round three)
            largest_in = max([input_bytes(p) for p in must["inputs"]] + [0])
            r = run_isolated(argv, serve=must["serve"])
            verdict = r["verdict"]
            tried += 1
            largest_out = max([output_bytes(p) for p in must["outputs"]] + [0])
            if _bundled_digest() != bundled:  # an output replaced a file of the package itself
                verdict = "crash: a bundled mesh file was overwritten"
            changed = [p for p, d in _digests(list(before)).items() if d != before[p]]
            if changed:
                verdict = f"crash: an input was changed or removed: {os.path.basename(changed[0])}"
            for p, mode in kinds.items():  # a FIFO or a symlink stays what it was
                if not os.path.lexists(p) or stat.S_IFMT(os.lstat(p).st_mode) != stat.S_IFMT(mode):
                    verdict = f"crash: {p} was replaced"
            bound = 3 * max(largest_in, largest_out) + MEMORY_SLACK
            if r["peak_rss"] > bound and not verdict.startswith(("crash", "hang")):
                verdict = (f"memory: peak RSS {r['peak_rss'] / 2**20:.0f} MB over 3 x {max(largest_in, largest_out) / 2**20:.1f}"
                           f" MB + 500 MB")
            s = stats.setdefault(must["command"], Counter(cases=0))
            s["cases"] += 1
            s[verdict.split(":")[0]] += 1
            s["big"] += bool(must["big"])
            s["most_cpu"] = max(s["most_cpu"], r["cpu"])
            if r["seconds"] > s["slowest"]:
                s["slowest"] = r["seconds"]
                s["slowest_case"] = " ".join(argv[:1] + [os.path.basename(a) for a in argv[1:]])
            s["largest_in"] = max(s["largest_in"], largest_in)
            s["largest_out"] = max(s["largest_out"], largest_out)
            s["peak_rss"] = max(s["peak_rss"], r["peak_rss"])
            if log is not None:
                last = ([ln for ln in r["stderr"].splitlines() if ln.strip()] or [""])[-1][:200]
                print(f"{verdict[:60]!s:60} {r['seconds']:6.1f} s {r['peak_rss'] / 2**20:6.0f} MB  {' '.join(argv)}"
                      f"\n    {last}", file=log, flush=True)
            if verdict.startswith(("crash", "hang", "memory")):
                failures.append((verdict, argv))
                if "bundled" in verdict:
                    break  # the package is damaged: nothing after this is meaningful
    totals = Counter()
    for s in stats.values():
        totals.update({k: s[k] for k in ("cases", "ok", "error", "crash", "hang", "memory")})
    print(f"fuzz commands: {tried} command lines in {seconds:g} s (seed {seed}): {totals['ok']} succeeded, "
          f"{totals['error']} refused with one error line (exit 2), {totals['crash']} crashes, "
          f"{totals['hang']} hangs (over {HANG_S:g} s of CPU, blocked past {HANG_S:g} s, or running {WALL_LIMIT_S:g} s), "
          f"{totals['memory']} over the memory bound (3 x the largest input or output + 500 MB)")
    print("| command | cases | succeeded | refused | crashes | hangs | over memory bound | big-input cases | "
          "slowest (wall) | most CPU | largest input | largest output | peak RSS |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for c in sorted(stats, key=lambda c: (COMMANDS.index(c.split("-")[0]), c)):
        s = stats[c]
        print(f"| {c} | {s['cases']} | {s['ok']} | {s['error']} | {s['crash']} | {s['hang']} | {s['memory']} | {s['big']} | "
              f"{s['slowest']:.1f} s | {s['most_cpu']:.1f} s | {s['largest_in'] / 2**20:.1f} MB | {s['largest_out'] / 2**20:.1f} MB | "
              f"{s['peak_rss'] / 2**20:.0f} MB |")
    for verdict, argv in failures[:40]:
        print(f"  {verdict}: {' '.join(argv)}", file=sys.stderr)
    return 1 if failures else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0, help="how long to fuzz each target (default: %(default)s)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--target", choices=("params", "meshes", "commands", "all"), default="params")
    ap.add_argument("--commands", default="", help="with --target commands: comma-separated subset of "
                                                   + ", ".join(COMMANDS) + " (default: all)")
    ap.add_argument("--big-mb", type=float, default=20.0, help="size of the big inputs, MB (default: %(default)s)")
    ap.add_argument("--log", default=None, help="write every command case with its verdict here (default: none)")
    ap.add_argument("--cases", type=int, default=None, help="stop after this many command lines (default: --seconds only)")
    ap.add_argument("--cycle", action="store_true", help="the commands in turn (default: drawn at random)")
    args = ap.parse_args(argv)
    targets = ("params", "meshes", "commands") if args.target == "all" else (args.target,)
    only = tuple(c for c in args.commands.split(",") if c)
    bad = [c for c in only if c not in COMMANDS]
    if bad:
        ap.error(f"--commands: unknown {', '.join(bad)}; expected some of {', '.join(COMMANDS)}")
    status = 0
    log = open(args.log, "w") if args.log else None
    try:
        for t in targets:
            if t == "commands":
                status |= fuzz_commands(args.seconds, args.seed, only, args.big_mb, log, args.cases, args.cycle)
            else:
                status |= {"params": fuzz_params, "meshes": fuzz_meshes}[t](args.seconds, args.seed)
    finally:
        if log is not None:
            log.close()
    return status


if __name__ == "__main__":
    sys.exit(main())

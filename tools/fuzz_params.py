"""Bounded fuzzing of the parameter-file readers.

    python3 tools/fuzz_params.py --seconds 60 [--seed 1]

Mutates valid parameter files (float32 binary, quantized binary, text) --
bit flips, byte overwrites, truncation, splices of two files, inserted and
deleted runs, header fields set to extreme values with the CRC-32 made to
match -- and feeds each to ``decode_binary`` and ``parse_text`` (in memory;
nothing is written).  Every input must either decode to finite ``(n, 16)
float32`` values or raise an ``AxialDeformError``.  A *crash* is any other
exception (or a MemoryError); *undetected* is a binary input whose bytes were
changed without fixing the CRC that still decoded to different values.

Prints one summary line (and a few examples of any failure); exit status 1
if crashes or undetected corruptions were found.
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0, help="how long to fuzz (default: %(default)s)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
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


if __name__ == "__main__":
    sys.exit(main())

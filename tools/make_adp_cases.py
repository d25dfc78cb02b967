"""Write js/test/cases/adp/: mutated .adp files and what the Python reader answers to each.

The Python reader (``axialdeform.core.io.adp.decode_binary``) and the npm module's ``parseADP``
must accept and refuse exactly the same bytes, with the same message: both test suites read this
corpus (``tests/core/test_params_files.py``, ``js/test/adp.test.mjs``) and compare with
``verdicts.json``.  The mutations start from js/test/fixtures/*.adp: numbers set to what the
record refuses (a scale <= 0, a taper >= 1, a tint out of 0..1, NaN, infinities; CRC-32 fixed
so that the checks after it are reached), quantization tables that decode to infinity, and seeded
byte flips (CRC fixed, or not).  Rerun after changing the format or its checks:

    .venv/bin/python tools/make_adp_cases.py
"""

from __future__ import annotations

import json
import struct
import sys
import zlib
from pathlib import Path

import numpy as np

from axialdeform.core.errors import AxialDeformError
from axialdeform.core.io.adp import HEADER_SIZE, TRAILER, decode_binary, read_binary_header
from axialdeform.core.record import tree_shape

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "js" / "test" / "fixtures"
OUT = ROOT / "js" / "test" / "cases" / "adp"


def fix_crc(data: bytearray) -> bytearray:
    data[-TRAILER.size:] = TRAILER.pack(zlib.crc32(bytes(data[:-TRAILER.size])))
    return data


def set_number(data: bytes, instance: int, column: int, value: float) -> bytearray:
    """A float32 file with one number replaced (CRC fixed)."""
    h = read_binary_header(bytes(data), "x")
    out = bytearray(data)
    struct.pack_into("<f", out, HEADER_SIZE + 4 * (instance * h.columns + column), value)
    return fix_crc(out)


def verdict(data: bytes, name: str) -> str:
    try:
        decode_binary(data, name)
    except AxialDeformError as exc:
        return str(exc)
    return "ok"


def cases():
    rng = np.random.default_rng(2026)
    for src in sorted(FIXTURES.glob("*.adp")):
        data = src.read_bytes()
        h = read_binary_header(data, src.name)
        k, level = tree_shape(h.columns)
        if h.encoding == 0 and level >= 1:
            scale, taper = 10 * k + 6, 10 * k + 8  # s tw tp after every axis's offsets, p and r
            for label, col, value in (("scale0", scale, 0.0), ("scaleneg", scale, -1.5), ("taper1", taper, 1.0),
                                      ("taper5", taper, 5.0)):
                yield f"{src.stem}-{label}", set_number(data, 1, col, value)
            if level == 2:  # tinted: tr tg tb after them
                for label, value in (("tintneg", -0.1), ("tint2", 1.5)):
                    yield f"{src.stem}-{label}", set_number(data, 0, 10 * k + 10, value)
        if h.encoding == 0:
            for label, value in (("nan", float("nan")), ("inf", float("inf")), ("ninf", float("-inf"))):
                yield f"{src.stem}-{label}", set_number(data, 0, 3, value)
        else:  # a quantization table whose step sends the largest level to infinity, or whose minimum is refused
            out = bytearray(data)
            struct.pack_into("<f", out, HEADER_SIZE + 4 * (h.columns + 2), 3e38)
            yield f"{src.stem}-stepinf", fix_crc(out)
            if level >= 1:
                out = bytearray(data)
                struct.pack_into("<f", out, HEADER_SIZE + 4 * (10 * k + 6), -1.0)  # the scale's minimum
                yield f"{src.stem}-qscaleneg", fix_crc(out)
            if level == 2:
                out = bytearray(data)
                struct.pack_into("<f", out, HEADER_SIZE + 4 * (10 * k + 9), -0.5)  # the first tint's minimum
                yield f"{src.stem}-qtintneg", fix_crc(out)
        for k in range(8):  # seeded byte flips: in the header, the numbers or the trailer
            out = bytearray(data)
            at = int(rng.integers(0, len(out)))
            out[at] ^= 1 << int(rng.integers(0, 8))
            yield f"{src.stem}-flip{k}", fix_crc(out) if k % 2 else out


def main(out: Path = OUT) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob("*.adp"):
        old.unlink()
    verdicts = {}
    for name, data in cases():
        (out / f"{name}.adp").write_bytes(bytes(data))
        verdicts[f"{name}.adp"] = verdict(bytes(data), f"{name}.adp")
    (out / "verdicts.json").write_text(json.dumps(verdicts, indent=1, sort_keys=True) + "\n")
    print(f"wrote {len(verdicts)} cases to {out} ({sum(v != 'ok' for v in verdicts.values())} refused)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else OUT)

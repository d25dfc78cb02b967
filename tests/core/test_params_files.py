"""Parameter files: text and binary round trips, the quantized bound, the
base-mesh check, checksum and truncation."""

import struct
from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.io import params as P
from axialdeform.core.quantize import quantization_error_bound


@pytest.fixture
def values(stone):
    return ad.random_params(stone, 257, seed=9, variation=ad.Variation(bend=0.15), placement="disc")


def test_text_round_trip_is_lossless(tmp_path, values, stone):
    path = ad.write_params(tmp_path / "p.txt", values, stone)
    assert np.array_equal(ad.read_params(path), values)
    text = path.read_text()
    assert text.startswith("#") and len(text.splitlines()) == 257 + 3


def test_text_accepts_commas_spaces_and_comments(tmp_path):
    row = list(range(16))
    text = "# a comment\n\n" + ",".join(map(str, row)) + "\n  # indented comment\n" + " \t".join(map(str, row)) + "\n" \
        + ", ".join(map(str, row)) + "\n"
    (tmp_path / "p.csv").write_text(text)
    got = ad.read_params(tmp_path / "p.csv")
    assert got.shape == (3, 16) and np.array_equal(got, np.tile(np.arange(16, dtype=np.float32), (3, 1)))


@pytest.mark.parametrize("line,message", [
    ("1 2 3", "line 2: expected 16 numbers, found 3"),
    (" ".join(["1"] * 17), "line 2: expected 16 numbers, found 17"),
    (" ".join(["1"] * 15 + ["x"]), "field rz: expected a number, found 'x'"),
    (" ".join(["1"] * 12 + ["nan"] + ["1"] * 3), "field pz: expected a finite number"),
    (" ".join(["1"] * 13 + ["inf"] + ["1"] * 2), "field rx: expected a finite number"),
    (" ".join(["1e39"] + ["1"] * 15), "line 2, field d1u: .*expected a finite number"),
])
def test_text_errors_name_file_line_and_field(tmp_path, line, message):
    path = tmp_path / "bad.txt"
    path.write_text("# header\n" + line + "\n")
    with pytest.raises(ad.core.ParamFileError) as err:
        ad.read_params(path)
    import re

    assert str(path) in str(err.value) and re.search(message, str(err.value)), str(err.value)


def test_non_utf8_text_is_refused(tmp_path):
    path = tmp_path / "bad.txt"
    path.write_bytes(b"1 2 3 \xff\xfe\n")
    with pytest.raises(ad.core.ParamFileError, match="not UTF-8"):
        ad.read_params(path)


def test_binary_round_trip_is_bit_exact(tmp_path, values, stone):
    path = ad.write_params(tmp_path / "p.adp", values, stone)
    assert path.stat().st_size == P.HEADER_SIZE + 64 * len(values) + 4
    pf = ad.core.read_param_file(path)
    assert pf.values.tobytes() == values.tobytes()
    assert pf.encoding == "float32" and pf.mesh_fingerprint == stone.fingerprint
    assert pf.axis.index == stone.axis.index and pf.axis.lo == stone.axis.lo and pf.axis.length == stone.axis.length


def test_quantized_is_32_bytes_and_within_its_bound(tmp_path, values, stone):
    path = ad.write_params(tmp_path / "q.adp", values, stone, quantize=True)
    per_instance = (path.stat().st_size - P.HEADER_SIZE - 128 - 4) / len(values)
    assert per_instance == 32
    got = ad.read_params(path, stone)
    bound = quantization_error_bound(values)
    err = np.abs(got.astype(np.float64) - values.astype(np.float64)).max(axis=0)
    assert (err <= bound).all(), (err, bound)
    # the bound is tight enough to matter: about range / 131070
    assert bound[0] < 0.2 * stone.axis.length * 4 / 65535
    # min and max of each column are exact
    assert np.array_equal(got.min(axis=0), values.min(axis=0))


def test_quantized_constant_columns_are_exact(tmp_path):
    v = np.zeros((10, 16), np.float32)
    v[:, 10] = np.linspace(-5, 5, 10)
    v[:, 3] = 0.25
    got = ad.read_params(ad.write_params(tmp_path / "c.adp", v, quantize=True))
    assert np.array_equal(got[:, 3], v[:, 3]) and np.array_equal(got[:, 0], v[:, 0])


def test_text_binary_text_conversion_changes_nothing(tmp_path, values, stone):
    ad.write_params(tmp_path / "a.txt", values)
    b = ad.write_params(tmp_path / "b.adp", ad.read_params(tmp_path / "a.txt"), stone)
    c = ad.write_params(tmp_path / "c.txt", ad.read_params(b))
    assert np.array_equal(ad.read_params(c), values)


def test_wrong_mesh_is_an_error_unless_overridden(tmp_path, values, stone, leaf):
    path = ad.write_params(tmp_path / "p.adp", values, stone)
    with pytest.raises(ad.core.MeshMismatchError, match="different base mesh"):
        ad.read_params(path, leaf)
    assert np.array_equal(ad.read_params(path, leaf, allow_mesh_mismatch=True), values)
    assert np.array_equal(ad.read_params(path, stone), values)


def test_every_flipped_byte_is_detected(tmp_path, stone):
    values = ad.random_params(stone, 3, seed=1)
    data = bytearray(P.encode_binary(values, axis=stone.axis, mesh_fingerprint=stone.fingerprint))
    for i in range(len(data)):
        bad = bytearray(data)
        bad[i] ^= 0x40
        with pytest.raises(ad.core.ParamFileError):
            P.decode_binary(bytes(bad), "x.adp")


def test_corrupt_checksum_and_truncation(tmp_path, values, stone):
    path = ad.write_params(tmp_path / "p.adp", values, stone)
    data = path.read_bytes()
    (tmp_path / "flip.adp").write_bytes(data[:200] + bytes([data[200] ^ 1]) + data[201:])
    with pytest.raises(ad.core.ParamFileError, match="checksum"):
        ad.read_params(tmp_path / "flip.adp")
    for cut in (0, 10, P.HEADER_SIZE, len(data) - 1):
        (tmp_path / "cut.adp").write_bytes(data[:cut])
        with pytest.raises(ad.core.ParamFileError, match="truncated|count") as err:
            ad.read_params(tmp_path / "cut.adp")
        assert "cut.adp" in str(err.value)


def test_huge_declared_count_allocates_nothing(tmp_path):
    data = bytearray(P.encode_binary(np.zeros((1, 16), np.float32)))
    struct.pack_into("<Q", data, 16, 2**60)
    with pytest.raises(ad.core.ParamFileError, match="declares 1152921504606846976 instances"):
        P.decode_binary(bytes(data), "huge.adp")


def test_wrong_magic_and_version(values):
    data = bytearray(P.encode_binary(values))
    data[1] = ord("X")
    with pytest.raises(ad.core.ParamFileError, match="magic"):
        P.decode_binary(bytes(data))
    data = bytearray(P.encode_binary(values))
    struct.pack_into("<H", data, 8, 99)
    with pytest.raises(ad.core.ParamFileError, match=r"version: expected 1 \(16 numbers\), 2 \(19 numbers\), 3 \(22 numbers\), found 99"):
        P.decode_binary(bytes(data))


def test_unknown_extension_and_missing_file(tmp_path, values):
    with pytest.raises(ad.core.ParamFileError, match="unknown parameter file type"):
        ad.write_params(tmp_path / "p.xyz", values)
    with pytest.raises(ad.core.ParamFileError, match="no such parameter file"):
        ad.read_params(tmp_path / "missing.adp")


def test_as_params_validates_shape_and_finiteness():
    with pytest.raises(ad.core.ParamError, match=r"shape \(n, 16\), \(n, 19\) or \(n, 22\), found \(3, 15\)"):
        ad.core.as_params(np.zeros((3, 15)))
    bad = np.zeros((2, 16))
    bad[1, 14] = np.inf
    with pytest.raises(ad.core.ParamError, match="instance 1, field ry"):
        ad.core.as_params(bad)
    assert ad.core.as_params(np.arange(16)).shape == (1, 16)


def test_write_is_atomic_and_keeps_the_old_file_on_error(tmp_path, values):
    path = ad.write_params(tmp_path / "p.adp", values)
    before = path.read_bytes()
    bad = values.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ad.core.ParamError):
        ad.write_params(path, bad)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["p.adp"]  # no temporary files left


def test_atomic_writes_get_ordinary_permissions(tmp_path, values):
    import os

    path = ad.write_params(tmp_path / "p.adp", values)
    mask = os.umask(0)
    os.umask(mask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~mask
    os.chmod(path, 0o640)
    ad.write_params(path, values)
    assert path.stat().st_mode & 0o777 == 0o640  # a replaced file keeps its mode


@pytest.mark.parametrize("quantize, record", [(False, 64), (True, 32)])
def test_header_says_the_record_bytes(tmp_path, stone, quantize, record):
    from axialdeform.core.io.params import read_binary_header

    for n in (0, 1, 777):
        path = ad.write_params(tmp_path / f"p{n}.adp", ad.random_params(stone, n, seed=1), stone, quantize=quantize)
        h = read_binary_header(path.read_bytes(), str(path))
        assert h.count == n and h.size == path.stat().st_size
        assert h.payload_bytes == record * n


CASES = Path(__file__).resolve().parents[2] / "js" / "test" / "cases" / "adp"


def test_the_shared_adp_corpus_gets_the_same_answers_in_both_readers(tmp_path):
    """js/test/cases/adp: mutated files and the Python reader's answers (tools/make_adp_cases.py,
    rerun here: the committed corpus is what it writes); the npm module's parseADP is held to the same
    answers, word for word, by js/test/adp.test.mjs."""
    import json
    import subprocess
    import sys

    from axialdeform.core.io.adp import decode_binary

    verdicts = json.loads((CASES / "verdicts.json").read_text())
    assert len(verdicts) > 50 and sum(v != "ok" for v in verdicts.values()) > 30
    for name, want in verdicts.items():
        try:
            decode_binary((CASES / name).read_bytes(), name)
            got = "ok"
        except ad.AxialDeformError as exc:
            got = str(exc)
        assert got == want, name
    subprocess.run([sys.executable, str(Path(__file__).resolve().parents[2] / "tools" / "make_adp_cases.py"),
                    str(tmp_path)], check=True, capture_output=True)
    assert json.loads((tmp_path / "verdicts.json").read_text()) == verdicts
    for name in verdicts:
        assert (tmp_path / name).read_bytes() == (CASES / name).read_bytes(), name

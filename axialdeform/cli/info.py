"""``axialdeform info``: describe a parameter file."""

from __future__ import annotations

import sys
from pathlib import Path

from ..core.io.params import (
    ParamFile,
    decode_binary,
    parse_text,
    read_binary_header,
    read_param_bytes,
)
from ..core.record import describe_record


def add_parser(sub) -> None:
    i = sub.add_parser("info", help="describe a parameter file", description="Header, count and checksum verdict of PARAMS.")
    i.add_argument("params", help="parameter file (.adp binary, .txt/.csv/.dat text)")
    i.set_defaults(handler=run)


def run(args) -> int | None:
    """Header, count and checksum verdict; a corrupt binary file still shows
    its header, then the verdict fails with status 2."""

    path = Path(args.params)
    data, binary = read_param_bytes(path)  # a regular file, read with a bound
    if binary:
        h = read_binary_header(data, str(path))  # structural errors: one line, exit 2
        record = h.axis_record(str(path))
        axis = "not recorded" if record is None else record.describe()
        rows = [("file", f"{path} ({h.size} bytes)"), ("format", f"binary v{h.version}, {h.encoding_name}"),
                ("instances", f"{h.count}" + (f" ({h.size / h.count:.1f} bytes each)" if h.count else "")),
                ("record", describe_record(h.columns)),
                ("axis", axis),
                ("mesh", "sha256 " + h.fingerprint.hex() if any(h.fingerprint) else "not recorded"),
                ("checksum", f"CRC-32 {h.stored_crc:08x} " + ("OK" if h.checksum_ok else
                                                               f"MISMATCH (computed {h.computed_crc:08x})"))]
        for key, value in rows:
            print(f"{key + ':':<11}{value}")
        if not h.checksum_ok:
            print(f"axialdeform info: error: {path}: checksum: the file is corrupt", file=sys.stderr)
            return 2
        decode_binary(data, str(path))  # the values too: finite numbers, valid axis
        return None
    pf = ParamFile(values=parse_text(data, str(path)), format="text", encoding="text", size=len(data))
    print(f"file:      {path} ({pf.size} bytes)")
    print(f"format:    text, {pf.count} lines of {pf.values.shape[1]} numbers")
    print(f"instances: {pf.count}" + (f" ({pf.size / pf.count:.1f} bytes each)" if pf.count else ""))
    print(f"record:    {describe_record(pf.values.shape[1])}")
    print("axis:      not recorded (text form)")
    print("mesh:      not recorded (text form)")
    print("checksum:  none (text form)")
    return None

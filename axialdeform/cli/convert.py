"""``axialdeform convert``: parameter files text <-> binary."""

from __future__ import annotations

from ..core.io.params import check_mesh, read_param_file, write_params
from ..core.io.safeio import check_output_path
from ._common import add_axis, add_overwrite, load_base, mesh_file


def add_parser(sub) -> None:
    c = sub.add_parser("convert", help="convert parameter files (text <-> binary)", description=(
        "Convert SRC to DST by extension (.adp binary; .txt/.csv/.dat text)."))
    c.add_argument("src", help="parameter file to read")
    c.add_argument("dst", help="parameter file to write (never SRC itself)")
    c.add_argument("--mesh", help="record the axis and fingerprint of this base mesh (default: keep what SRC records)")
    add_axis(c)
    c.add_argument("--quantize", action="store_true", help="write the compact 32-byte form (default: 64 bytes, lossless)")
    add_overwrite(c)
    c.set_defaults(handler=run)


def run(args) -> None:
    check_output_path(args.dst, (args.src, mesh_file(args.mesh)), "parameter file")
    pf = read_param_file(args.src)
    mesh = load_base(args, args.mesh) if args.mesh else None
    # the files the mesh names too; then an output that exists, only with --overwrite
    check_output_path(args.dst, () if mesh is None else mesh.sources, "parameter file", overwrite=args.overwrite)
    if mesh is not None:
        check_mesh(pf, mesh, args.src)
    path = write_params(args.dst, pf.values, mesh, quantize=args.quantize,
                        axis=pf.axis, mesh_fingerprint=pf.mesh_fingerprint)
    print(f"wrote {path} ({pf.count} instances, {path.stat().st_size} bytes)")

"""``axialdeform fit``: parameters recovered from existing variant meshes."""

from __future__ import annotations

import sys
from pathlib import Path

from tqdm import tqdm

from ..core.fit import DEFAULT_MAX_RESIDUAL, fit_files, variant_paths
from ..core.io.params import write_params
from ..core.io.safeio import check_output_path
from ._common import add_axis, add_overwrite, fraction, load_base, positive_int


def add_parser(sub) -> None:
    f = sub.add_parser("fit", help="recover parameters from existing variant meshes", description=(
        "Fit the 16 numbers of each variant of BASE: VARIANTS are mesh files with BASE's vertices in the same "
        "order, or ONE folder whose mesh files, sorted by name, are instances 0, 1, 2, ... The output is binary "
        "for .adp, text for .txt/.csv/.dat. Exit 2 if a fit's largest vertex distance exceeds --max-residual."))
    f.add_argument("base", help="base mesh file, or 'stone' / 'leaf' / 'leafcard' / 'tree'")
    add_axis(f)
    f.add_argument("variants", nargs="+", help="variant mesh files, or one folder of them")
    f.add_argument("-o", "--output", required=True, help="parameter file to write (required, no default)")
    f.add_argument("--max-residual", type=fraction, default=DEFAULT_MAX_RESIDUAL,
                   help="largest allowed vertex distance, fraction of L (default: %(default)g)")
    f.add_argument("--allow-residual", action="store_true",
                   help="write the parameters even if fits exceed --max-residual (they are still reported; default: refuse)")
    f.add_argument("--max-iterations", type=positive_int, default=100, help="alternation rounds per variant (default: %(default)s)")
    f.add_argument("--extended", action="store_true",
                   help="fit the 19 numbers of extended instances: scale, twist and taper too (default: the 16)")
    add_overwrite(f)
    f.set_defaults(handler=run)


def run(args) -> None:
    """``axialdeform fit BASE VARIANTS... -o PARAMS``."""

    out = Path(args.output)
    mesh = load_base(args, args.base, textures=False)
    is_folder = len(args.variants) == 1 and Path(args.variants[0]).is_dir()
    paths = variant_paths(args.variants)

    check_output_path(out, (*mesh.sources, *paths), "parameter file", overwrite=args.overwrite)
    with tqdm(total=len(paths), desc="fitting", unit="mesh", file=sys.stderr, disable=None) as bar:
        result = fit_files(mesh, paths, max_residual=args.max_residual, max_iterations=args.max_iterations,
                           progress=bar, extended=args.extended)
    if not args.allow_residual:
        result.check()
    path = write_params(out, result.params, mesh)
    k = result.worst
    print(f"wrote {path} ({len(paths)} instances, {path.stat().st_size} bytes)")
    print(f"worst residual: max {result.max[k]:.3g} L, rms {result.rms[k]:.3g} L ({result.names[k]})")
    bad = int(result.exceeds.sum())
    if bad:
        print(f"warning: {bad} of {len(paths)} fits exceed the residual limit {result.max_residual:g} L", file=sys.stderr)
    if is_folder:
        variant_bytes = sum(p.stat().st_size for p in paths)
        print(f"size ratio: {variant_bytes} bytes of variants / {path.stat().st_size} bytes of parameters "
              f"= {variant_bytes / path.stat().st_size:.1f}x")

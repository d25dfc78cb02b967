"""The ``axialdeform`` command (also ``python -m axialdeform``).

User errors print one line to stderr and exit with status 2, no traceback.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ..core.errors import AxialDeformError
from ..core.safeio import check_count, check_output_path, quiet_numpy

__all__ = ["main", "build_parser"]

DEMO_COUNT = 2500
#: peak bytes per instance of ``random`` (random_params' temporaries, the
#: result and its encoding; measured with tracemalloc: about 700) and of
#: ``demo`` (plus the GPU buffer and camera bounds), for the -n check
_RANDOM_BYTES_EACH = 768
_DEMO_BYTES_EACH = 1024

#: modules that add sub-commands: each defines ``add_parser(subparsers)``
#: (which calls ``subparsers.add_parser(NAME, ...)`` and
#: ``set_defaults(handler=run)``) and ``run(args) -> None``.
PLUGINS: tuple[str, ...] = ("axialdeform.core.export", "axialdeform.core.fit", "axialdeform.viewer", "axialdeform.bench")


def _angle_range(text: str) -> tuple[float, float]:
    try:
        parts = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected MIN,MAX in radians, found {text!r}") from None
    if len(parts) == 1:
        return (-abs(parts[0]), abs(parts[0]))
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"expected MIN,MAX in radians, found {text!r}")
    return (parts[0], parts[1])


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__
    from ..core.bake import ENGINES, MESH_FORMATS
    from ..gl.renderer import MODES
    from ..core.variation import PLACEMENTS

    p = argparse.ArgumentParser(
        prog="axialdeform",
        description="Thousands of individually different shapes from one base mesh and 16 numbers per instance.",
    )
    p.add_argument("--version", action="version", version=f"axialdeform {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)

    d = sub.add_parser("demo", help="render the default stone scene to a PNG", description=(
        f"Render {DEMO_COUNT} bundled stones, each bent by its own control axis, solid and wireframe side by side."))
    d.add_argument("-o", "--output", default="axialdeform-demo.png", help="PNG to write (default: %(default)s)")
    d.add_argument("-n", "--count", type=int, default=DEMO_COUNT, help="number of stones (default: %(default)s)")
    d.add_argument("--size", default="800x600", help="size of each panel, WIDTHxHEIGHT (default: %(default)s)")
    d.add_argument("--seed", type=int, default=2003, help="random seed (default: %(default)s)")

    r = sub.add_parser("random", help="write random parameters for a mesh", description=(
        "Write COUNT random parameter records for MESH (a file, or 'stone' / 'leaf'); "
        "the output is binary for .adp, text for .txt/.csv/.dat."))
    r.add_argument("mesh")
    r.add_argument("-n", "--count", type=int, required=True)
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--bend", type=float, default=0.08, help="offset amplitude as a fraction of the axis length L (default: %(default)s)")
    r.add_argument("--placement", choices=PLACEMENTS, default="grid")
    r.add_argument("--spacing", type=float, default=None, help="distance between neighbours, world units (default: 1.1 L)")
    r.add_argument("--up", choices=("x", "y", "z"), default="y", help="world up axis (default: %(default)s)")
    r.add_argument("--yaw", type=_angle_range, default=(0.0, 2 * math.pi), help="MIN,MAX radians about the up axis")
    r.add_argument("--tilt", type=_angle_range, default=(-0.25, 0.25), help="MIN,MAX radians about the other two axes")
    r.add_argument("--quantize", action="store_true", help="write the compact 32-byte form (binary only)")
    r.add_argument("-o", "--output", required=True)

    rd = sub.add_parser("render", help="render instances to a PNG", description="Render MESH deformed by PARAMS, framed automatically.")
    rd.add_argument("mesh")
    rd.add_argument("params")
    rd.add_argument("-o", "--output", required=True)
    rd.add_argument("--mode", choices=MODES, default="solid")
    rd.add_argument("--size", default="800x600", help="WIDTHxHEIGHT (default: %(default)s)")
    rd.add_argument("--up", choices=("x", "y", "z"), default="y")
    rd.add_argument("--ignore-mesh-mismatch", action="store_true", help="use PARAMS even if made for another mesh")

    b = sub.add_parser("bake", help="write every deformed instance out", description=(
        "Deform every instance and write OUT: an .npz with arrays 'positions' and 'normals', each "
        "(instances, vertices, 3) float32 in world space and the mesh file's vertex order; or a folder "
        "with one mesh file per instance."))
    b.add_argument("mesh")
    b.add_argument("params")
    b.add_argument("-o", "--output", required=True)
    b.add_argument("--engine", choices=ENGINES, default="cpu")
    b.add_argument("--format", choices=MESH_FORMATS, default="obj", help="mesh file type when OUT is a folder")
    b.add_argument("--ignore-mesh-mismatch", action="store_true")
    b.add_argument("--overwrite", action="store_true", help=(
        "OUT may be a folder of an earlier bake: new files are written first, then the old instance_* files "
        "not rewritten are removed (other files are kept); without it a folder holding files is refused"))

    i = sub.add_parser("info", help="describe a parameter file", description="Header, count and checksum verdict of PARAMS.")
    i.add_argument("params")

    c = sub.add_parser("convert", help="convert parameter files (text <-> binary)", description=(
        "Convert SRC to DST by extension (.adp binary; .txt/.csv/.dat text)."))
    c.add_argument("src")
    c.add_argument("dst")
    c.add_argument("--mesh", help="record the axis and fingerprint of this base mesh")
    c.add_argument("--quantize", action="store_true", help="write the compact 32-byte form")

    import importlib

    for module in PLUGINS:
        importlib.import_module(module).add_parser(sub)
    return p


def _progress(total: int, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="inst", disable=total < 2000 and not sys.stderr.isatty(), file=sys.stderr)


def cmd_demo(args) -> None:
    from ..gl.camera import frame_instances
    from ..gl.image import parse_size, render_image, save_png
    from ..core.mesh import load_mesh, mesh_source_path
    from ..core.variation import random_params

    check_output_path(args.output, (mesh_source_path("stone"),), "PNG")  # the bundled mesh is an input too
    check_count(args.count, _DEMO_BYTES_EACH, "-n/--count")
    mesh = load_mesh("stone")
    params = random_params(mesh, args.count, seed=args.seed, bend=0.14, placement="disc",
                           spacing=0.9 * mesh.axis.length, tilt=(-0.2, 0.2))
    size = parse_size(args.size)
    camera = frame_instances(mesh, params, size[0] / size[1], elevation=30.0, azimuth=20.0, margin=-1.2)
    image = render_image(mesh, params, size, ("solid", "wireframe"), camera=camera)
    save_png(args.output, image)
    print(f"wrote {Path(args.output).resolve()} ({args.count} stones, solid | wireframe, {image.shape[1]}x{image.shape[0]})")


def cmd_random(args) -> None:
    from ..core.mesh import load_mesh
    from ..core.params import write_params
    from ..core.variation import random_params

    check_output_path(args.output, (_mesh_file(args.mesh),), "parameter file")
    check_count(args.count, _RANDOM_BYTES_EACH, "-n/--count")
    mesh = load_mesh(args.mesh)
    params = random_params(mesh, args.count, args.seed, bend=args.bend, placement=args.placement,
                           spacing=args.spacing, up=args.up, yaw=args.yaw, tilt=args.tilt)
    path = write_params(args.output, params, mesh, quantize=args.quantize)
    print(f"wrote {path} ({len(params)} instances, {path.stat().st_size} bytes)")


def _mesh_file(source):
    """The file a mesh argument names (a bundled name: the package's file), or None."""
    from ..core.mesh import mesh_source_path

    return None if source is None else mesh_source_path(source)


def _load(args, what: str = "output", allow_folder: bool = False):
    """The mesh and parameters of a command, after checking that its output
    is neither one of them nor a device, FIFO or socket."""
    from ..core.mesh import load_mesh
    from ..core.params import read_params

    check_output_path(args.output, (_mesh_file(args.mesh), args.params), what, allow_folder=allow_folder)
    mesh = load_mesh(args.mesh)
    params = read_params(args.params, mesh, allow_mesh_mismatch=args.ignore_mesh_mismatch)
    warn_ranges(args, mesh, params)
    return mesh, params


def warn(args, message: str) -> None:
    """One warning line on stderr."""
    print(f"axialdeform {args.command}: warning: {message}", file=sys.stderr)


def warn_ranges(args, mesh, params) -> None:
    """Warn (once) when a parameter file goes past the float32-safe ranges."""
    from ..core.params import range_warning

    message = range_warning(mesh, params, args.params)
    if message:
        warn(args, message)


def cmd_render(args) -> None:
    from ..gl.image import parse_size, render_image, save_png

    mesh, params = _load(args, "PNG")
    image = render_image(mesh, params, parse_size(args.size), args.mode, up=args.up)
    save_png(args.output, image)
    print(f"wrote {args.output} ({len(params)} instances, {args.mode}, {image.shape[1]}x{image.shape[0]})")


def cmd_bake(args) -> None:
    from ..core.bake import bake, check_bake_folder, write_mesh_folder, write_npz

    out = Path(args.output)
    mesh, params = _load(args, "bake output", allow_folder=out.suffix.lower() != ".npz")
    if out.suffix.lower() != ".npz":  # refuse a folder of stale files before the work, not after
        check_bake_folder(out, args.overwrite)
    with _progress(len(params), f"deforming ({args.engine})") as bar:
        positions, normals = bake(mesh, params, args.engine, progress=bar, source=args.params)
    if out.suffix.lower() == ".npz":
        write_npz(out, positions, normals)
        print(f"wrote {out}: positions and normals {positions.shape} float32 ({args.engine})")
    else:
        with _progress(len(positions), "writing meshes") as bar:
            files = write_mesh_folder(out, mesh, positions, normals, args.format, progress=bar,
                                      overwrite=args.overwrite)
        print(f"wrote {len(files)} {args.format} files to {out}/ ({args.engine})")


def cmd_info(args) -> int | None:
    """Header, count and checksum verdict; a corrupt binary file still shows
    its header, then the verdict fails with status 2."""
    from ..core.axis import ControlAxis
    from ..core.errors import ParamFileError
    from ..core.params import ParamFile, decode_binary, parse_text, read_binary_header, read_param_bytes

    path = Path(args.params)
    data, binary = read_param_bytes(path)  # a regular file, read with a bound
    if binary:
        h = read_binary_header(data, str(path))  # structural errors: one line, exit 2
        try:
            axis = ControlAxis(h.axis_index, h.lo, h.length).describe() if h.axis_index >= 0 else "not recorded"
        except AxialDeformError as exc:
            raise ParamFileError(f"{path}: axis: {exc}") from None
        rows = [("file", f"{path} ({h.size} bytes)"), ("format", f"binary v{h.version}, {h.encoding_name}"),
                ("instances", f"{h.count}" + (f" ({h.size / h.count:.1f} bytes each)" if h.count else "")),
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
    print(f"format:    text, {pf.count} lines of 16 numbers")
    print(f"instances: {pf.count}" + (f" ({pf.size / pf.count:.1f} bytes each)" if pf.count else ""))
    print("axis:      not recorded (text form)")
    print("mesh:      not recorded (text form)")
    print("checksum:  none (text form)")
    return None


def cmd_convert(args) -> None:
    from ..core.mesh import load_mesh
    from ..core.params import check_mesh, read_param_file, write_params

    check_output_path(args.dst, (args.src, _mesh_file(args.mesh)), "parameter file")
    pf = read_param_file(args.src)
    mesh = load_mesh(args.mesh) if args.mesh else None
    if mesh is not None:
        check_mesh(pf, mesh, args.src)
    path = write_params(args.dst, pf.values, mesh, quantize=args.quantize,
                        axis=pf.axis, mesh_fingerprint=pf.mesh_fingerprint)
    print(f"wrote {path} ({pf.count} instances, {path.stat().st_size} bytes)")


COMMANDS = {
    "demo": cmd_demo,
    "random": cmd_random,
    "render": cmd_render,
    "bake": cmd_bake,
    "info": cmd_info,
    "convert": cmd_convert,
}


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        handler = getattr(args, "handler", None) or COMMANDS[args.command]
        with quiet_numpy():  # floating-point trouble is checked and reported, never printed as warnings
            status = handler(args)
        if status:
            return int(status)
    except AxialDeformError as exc:
        print(f"axialdeform {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"axialdeform {args.command}: error:{where} {exc.strerror or exc}", file=sys.stderr)
        return 2
    except MemoryError:
        print(f"axialdeform {args.command}: error: out of memory (the input asks for more than this machine has; "
              "use fewer instances or a smaller --size)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"axialdeform {args.command}: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

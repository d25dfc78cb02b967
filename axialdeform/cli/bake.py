"""``axialdeform bake``: every deformed instance written out."""

from __future__ import annotations

from pathlib import Path

from ..core.bake import MESH_FORMATS
from ..core.errors import ArgumentError
from ..core.io.bake import check_bake_folder, write_mesh_folder, write_npz_pieces
from ..core.io.mesh import mesh_source_path
from ..core.io.safeio import check_disk_space
from ..core.options import RenderOptions
from ..core.wind import apply_wind
from ..gl.bake import ENGINES, bake, bake_pieces
from . import scenes
from ._common import (
    MAX_BAKE_FILES,
    add_max_baked,
    add_mesh_and_params,
    add_mesh_mismatch,
    add_overwrite,
    add_wind_args,
    check_baked_triangles,
    load,
    positive_int,
    progress_bar,
    wind_arg,
)


def add_parser(sub) -> None:
    b = sub.add_parser("bake", help="write every deformed instance out", description=(
        "Deform every instance and write OUT: an .npz with arrays 'positions' and 'normals', each "
        "(instances, vertices, 3) float32 in world space and the mesh file's vertex order; or a folder "
        "with one mesh file per instance."))
    add_mesh_and_params(b)
    b.add_argument("-o", "--output", required=True, help="an .npz file or a folder (required, no default)")
    b.add_argument("--engine", choices=ENGINES, default="cpu", help="who deforms: numpy or the GPU (default: %(default)s)")
    b.add_argument("--format", choices=MESH_FORMATS, default="obj", help="mesh file type when OUT is a folder (default: %(default)s)")
    add_mesh_mismatch(b)
    b.add_argument("--max-files", type=positive_int, default=MAX_BAKE_FILES, metavar="N", help=(
        "refuse to write more than N mesh files into a folder (one an instance; -o OUT.npz has no such limit) "
        "(default: %(default)s)"))
    add_max_baked(b)
    add_wind_args(b)
    add_overwrite(b, " (a folder of an earlier bake: new files are written first, then the old instance_* files "
                     "not rewritten are removed, other files kept)")
    b.set_defaults(handler=run)


def run(args) -> None:
    scene = scenes.scene_of(args)
    if scene is not None:  # the scene's [wind] moves with --time; --wind replaces it
        return scenes.bake(scene, args, progress_bar, wind_arg(args) if args.wind is not None else None)
    wind = wind_arg(args)
    out = Path(args.output)
    mesh, params = load(args, "bake output", allow_folder=out.suffix.lower() != ".npz")
    check_baked_triangles(args, [(f"{args.mesh} x {args.params}", len(params), len(mesh.faces))], "")
    if out.suffix.lower() == ".npz":  # made and written in pieces: bounded by the disk, not memory
        return _bake_npz_in_pieces(args, out, mesh, params, wind)
    check_file_count(args, out, len(params))  # before anything is deformed or written
    inputs = (mesh_source_path(args.mesh), args.params)
    check_bake_folder(out, args.overwrite, inputs)  # refuse stale files, or an input to replace, before the work
    with progress_bar(len(params), f"deforming ({args.engine})") as bar:
        positions, normals = bake(mesh, params, args.engine, progress=bar, source=args.params,
                                  options=RenderOptions(wind=wind, time=args.time or 0.0))
    with progress_bar(len(positions), "writing meshes") as bar:
        bent = params
        if wind is not None:  # the tangents of a glb bend with the same wind-moved control points

            bent = apply_wind(wind, mesh.axis, params, args.time or 0.0)
        files = write_mesh_folder(out, mesh, (positions, normals), args.format, progress=bar,
                                  overwrite=args.overwrite, params=bent, inputs=inputs)
    meshes = [f for f in files if f.suffix == "." + args.format]
    beside = f" + {len(files) - len(meshes)} material/texture files" if len(files) > len(meshes) else ""
    print(f"wrote {len(meshes)} {args.format} files{beside} to {out}/ ({args.engine})")


def check_file_count(args, out: Path, count: int) -> None:
    """Refuse a bake into a folder of more than ``--max-files`` mesh files."""

    if count > args.max_files:
        raise ArgumentError(
            f"{out}: {args.params} holds {count} instances, one {args.format} file each: {count} files, over the "
            f"limit of {args.max_files} files a folder; expected at most {args.max_files} instances, or raise the "
            f"limit with --max-files N, or bake to -o OUT.npz (one archive, no such limit)")


def _bake_npz_in_pieces(args, out: Path, mesh, params, wind) -> None:
    """``bake -o OUT.npz``: :func:`~axialdeform.gl.bake.bake_pieces` (either
    engine) into :func:`~axialdeform.core.io.bake.write_npz_pieces`; the disk
    must hold the archive and, meanwhile, a spooled copy of the normals."""

    n, v = len(params), mesh.vertex_count
    array = n * v * 12
    check_disk_space(out, 3 * array + (1 << 16), f"bake of {n} instances x {v} vertices (the .npz and, while "
                     "it is written, a spooled copy of the normals)", ArgumentError)
    with progress_bar(n, f"deforming ({args.engine})") as bar:
        pieces = bake_pieces(mesh, params, args.engine, progress=bar, options=RenderOptions(wind=wind, time=args.time or 0.0),
                             source=args.params)
        try:
            write_npz_pieces(out, pieces, n, v)
        finally:
            pieces.close()  # the GPU engine's context is released even when a piece is refused
    print(f"wrote {out}: positions and normals {(n, v, 3)} float32 ({args.engine})")

"""``axialdeform info``: describe a parameter file, a mesh file and the axes it gets, or a scene file."""

from __future__ import annotations

import sys
from pathlib import Path

from ..core.errors import BRIEF_NAMES, AxialDeformError
from ..core.io.mesh import BUNDLED_MESHES, MESH_SUFFIXES, load_mesh, write_axes_file
from ..core.io.params import (
    ParamFile,
    decode_binary,
    parse_text,
    read_binary_header,
    read_param_bytes,
)
from ..core.io.safeio import check_output_path
from ..core.record import describe_record
from ..core.scene import Scene, is_scene_file
from ..core.shape_axes import skeleton_and_branches
from ._common import add_axis, add_overwrite, load_base


def add_parser(sub) -> None:
    i = sub.add_parser("info", help="describe a parameter file, a mesh file and its axes, or a scene file", description=(
        "Header, count and checksum verdict of a parameter file; or a mesh file's parts, its axis and, with "
        "--axes, the tree it gets (axes=parts: the trunk and attachments the heuristic found); or a scene "
        "file's layers (a generated layer's recipe)."))
    i.add_argument("params", metavar="FILE", help="parameter file (.adp binary, .txt/.csv/.dat text), a mesh file "
                   f"({', '.join(MESH_SUFFIXES)}) or bundled name, or a scene file (.toml)")
    add_axis(i)
    i.add_argument("--save-axes", metavar="FILE.toml", help="with --axes skeleton: write the branches found as an axes "
                   "file of [[branch]] tables, to edit by hand and give again as --axes FILE.toml (default: none written)")
    add_overwrite(i)
    i.set_defaults(handler=run)


def _mesh_info(args) -> None:
    if args.save_axes:  # said before any work
        if args.axes != "skeleton":
            raise AxialDeformError(f"--save-axes: writes the branches of a skeleton; give --axes skeleton, found --axes "
                                   f"{args.axes}")
        check_output_path(args.save_axes, [args.params], "--save-axes", overwrite=args.overwrite)
    if args.save_axes:  # the skeleton computed once: its branches are written, its tree described
        plain = load_mesh(args.params, textures=False, axis=args.axis, parts=getattr(args, "parts", None))
        tree, branches = skeleton_and_branches(plain)
        mesh = plain.with_axes(tree)
    else:
        mesh = load_base(args, args.params, textures=False)
    print(f"mesh:      {mesh.name} ({mesh.vertex_count} vertices, {len(mesh.faces)} triangles)")
    shown = ", ".join(f"{str(p.name)[:40]!r} ({p.count} triangles)" for p in mesh.parts[:BRIEF_NAMES])
    more = f", ... ({len(mesh.parts)} in all)" if len(mesh.parts) > BRIEF_NAMES else ""
    print(f"parts:     {len(mesh.parts)}: {shown}{more}")
    print(f"axis:      {mesh.axis.describe()}")
    tree = mesh.tree
    if tree is not None:
        print(f"axes:      {tree.describe()}")
    print(f"mesh:      sha256 {mesh.fingerprint.hex()}")
    if args.save_axes:
        write_axes_file(args.save_axes, branches, mesh.name)
        print(f"wrote {args.save_axes} ({len(branches)} branches)")


def _scene_info(args) -> None:
    """A scene file: its layers, each with its mesh and where its instances come from (a generated
    layer: its recipe and how many instances its extent holds)."""
    if args.axes is not None or args.parts is not None or args.axis != "auto":
        raise AxialDeformError(f"--axis/--axes/--parts: describe a mesh file; {args.params} is a scene file")
    scene = Scene.load(args.params)
    print(f"scene:     {args.params} ({len(scene.layers)} layers, {scene.count} instances"
          + (", a terrain" if scene.terrain is not None else "") + ")")
    for layer in scene.layers:
        g = layer.generate
        source = (f"generated: rate {g.generate.rate:g}, tiles of {g.generate.tile:g}, min_distance "
                  f"{g.generate.min_distance:g}, seed {g.generate.seed}, extent {list(g.extent)}, reach {g.reach:g}"
                  + _generated_extras(g) if g is not None else describe_record(layer.params.shape[1]))
        print(f"layer:     {layer.name}: {layer.mesh.name}, {len(layer.params)} instances ({source})")


def _generated_extras(g) -> str:
    """What else a generated layer's recipe says: its ground maps, bands, share, anchor, lean, lift, tint."""
    r, out = g.generate, []
    if g.density is not None:
        out.append(f"density {g.density.name}")
    for name in ("altitude", "slope", "lift"):
        if getattr(r, name) is not None:
            out.append(f"{name} {list(getattr(r, name))}")
    if r.choice != (0.0, 1.0):
        out.append(f"share [{r.choice[0]:g}, {r.choice[1]:g})")
    if r.anchor != "bottom":
        out.append(f"anchor {r.anchor}")
    if r.align_to_normal:
        out.append(f"align_to_normal {r.align_to_normal:g}")
    if r.tint is not None:
        out.append(f"tint {r.tint:g}")
    if getattr(g.maps, "heights", None) is not None:
        out.append("on the height map")
    return "".join(f", {x}" for x in out)


def run(args) -> int | None:
    """Header, count and checksum verdict; a corrupt binary file still shows
    its header, then the verdict fails with status 2.  A mesh: its parts, axis and axes."""

    if args.params in BUNDLED_MESHES or Path(args.params).suffix.lower() in MESH_SUFFIXES:
        return _mesh_info(args)
    if is_scene_file(args.params):
        return _scene_info(args)
    if args.axes is not None or args.parts is not None or args.axis != "auto":
        raise AxialDeformError(f"--axis/--axes/--parts: describe a mesh file; {args.params} is a parameter file")
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

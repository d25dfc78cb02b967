"""``axialdeform export``: instances as a glTF binary (.glb)."""

from __future__ import annotations

from ..core.errors import ArgumentError
from ..core.io.gltf import check_glb_path, export_glb
from . import scenes
from ._common import (
    MAX_EXPORT_MESHES,
    add_max_baked,
    add_mesh_and_params,
    add_mesh_mismatch,
    add_overwrite,
    check_baked_triangles,
    load,
    positive_int,
)


def add_parser(sub) -> None:
    e = sub.add_parser("export", help="write instances as a glTF binary (.glb)", description=(
        "Write MESH deformed by PARAMS to a .glb. --baked (default): one mesh per instance with its deformed "
        "world positions and normals; opens in any glTF viewer. --instanced: the base mesh once plus "
        "EXT_mesh_gpu_instancing (TRANSLATION, ROTATION and the offsets as _AXIAL_* attributes); "
        "a scene file (SCENE.toml, no PARAMS): one node per layer. "
        "See docs/interop.md. Coordinates are written as they are (no re-orientation to glTF's +Y up)."))
    add_mesh_and_params(e)
    e.add_argument("-o", "--output", required=True, help="the .glb to write (required, no default)")
    layout = e.add_mutually_exclusive_group()
    layout.add_argument("--baked", dest="layout", action="store_const", const="baked",
                        help="one deformed mesh per instance (the default)")
    layout.add_argument("--instanced", dest="layout", action="store_const", const="instanced",
                        help="base mesh once + EXT_mesh_gpu_instancing (default: --baked)")
    layout.add_argument("--generated", dest="layout", action="store_const", const="generated",
                        help="a scene file: its generated layers as their recipe (AXIALDEFORM_bend generate: "
                             "made around the camera by a reader that knows it; a small plain fallback for others), "
                             "the rest as --instanced (docs/generate.md; default: --baked)")
    e.set_defaults(layout="baked")
    add_mesh_mismatch(e)
    e.add_argument("--max-meshes", type=positive_int, default=MAX_EXPORT_MESHES, metavar="N", help=(
        "with --baked: refuse more than N instances (one glTF mesh and node each; --instanced and scene files "
        "have no such limit) (default: %(default)s)"))
    add_max_baked(e)
    add_overwrite(e)
    e.set_defaults(handler=run)


def run(args) -> None:
    """``axialdeform export MESH PARAMS -o OUT.glb [--baked | --instanced]``."""

    out = check_glb_path(args.output)  # before the (slow) reading
    if args.layout == "generated" and not str(args.mesh).lower().endswith(".toml"):
        raise ArgumentError(f"{out}: --generated writes a scene file's generated layers; expected SCENE.toml, "
                            "or --instanced / --baked for MESH PARAMS")
    scene = scenes.scene_of(args)
    if scene is not None:
        return scenes.export(scene, args)
    mesh, params = load(args, "exported .glb")
    if args.layout == "baked":  # before anything is deformed
        check_baked_triangles(args, [(f"{args.mesh} x {args.params}", len(params), len(mesh.faces))],
                              ", or use --instanced (the base mesh once, no such limit)")
    if args.layout == "baked" and len(params) > args.max_meshes:  # before anything is deformed

        raise ArgumentError(
            f"{out}: {args.params} holds {len(params)} instances; --baked writes one glTF mesh and node each, "
            f"over the limit of {args.max_meshes}; expected at most {args.max_meshes} instances, or raise the "
            f"limit with --max-meshes N, or use --instanced (the base mesh once, no such limit)")
    path = export_glb(out, mesh, params, args.layout, source=args.params)
    print(f"wrote {path} ({len(params)} instances, {args.layout}, {path.stat().st_size} bytes)")

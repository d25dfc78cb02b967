"""Scene files on the command line: ``render``, ``bake``, ``export`` and
``view`` take ``SCENE.toml`` where they take ``MESH PARAMS``.  Each command
calls :func:`scene_of` first and hands a scene to the matching function here."""

from __future__ import annotations

import sys
from pathlib import Path

from ..core.errors import ArgumentError, AxialDeformError, ParamError
from ..core.io.bake import write_npz_layers
from ..core.io.gltf import export_scene
from ..core.io.image import save_png
from ..core.io.safeio import check_disk_space, check_output_path
from ..core.options import RenderOptions
from ..core.scene import is_scene_file, load_scene
from ..gl.bake import bake_pieces
from ._common import check_baked_triangles, view_args
from ._common import check_triangles as check

__all__ = ["scene_of", "render", "bake", "export", "scene_time"]


def scene_of(args, *, params_optional: bool = False):
    """The loaded scene when ``args.mesh`` is a scene file (and PARAMS is left out), else None.

    A MESH without PARAMS is an error unless ``params_optional`` (``view``: random parameters).
    """

    if not is_scene_file(args.mesh):
        if args.params is None and not params_optional:
            raise AxialDeformError(f"PARAMS: expected a parameter file after MESH {args.mesh} (or a scene file .toml as MESH)")
        return None
    if args.params is not None:
        raise AxialDeformError(f"PARAMS: a scene file ({args.mesh}) names its own parameters; expected no PARAMS, found {args.params}")
    if getattr(args, "axis", "auto") != "auto" or getattr(args, "axes", None) is not None:
        raise AxialDeformError(f"--axis/--axes: a scene file ({args.mesh}) names each layer's axis (axis = ..., "
                               "axes = ...); expected neither")
    scene = load_scene(args.mesh)
    if getattr(args, "output", None) is not None:  # every file the scene read: never replaced
        check_output_path(args.output, scene.sources, "output", allow_folder=True, overwrite=args.overwrite)
    return scene


def _check_output(args, what: str) -> None:
    """Refuse an output that is the scene file itself, a device, FIFO or socket."""

    check_output_path(args.output, (args.mesh,), what)


def check_triangles(scene, args, mode: str, fast: bool = False, frames: int = 1) -> None:
    """The CLI's per-frame triangle budget (:func:`._common.check_triangles`)
    over every layer and the terrain, before anything is drawn."""

    items = [(f"{scene.path}: layer {layer.name}", len(layer.params), len(layer.mesh.faces)) for layer in scene.layers]
    if scene.terrain is not None:
        items.append((f"{scene.path}: terrain", 1, len(scene.terrain.faces)))
    check(items, mode, args.max_triangles, fast, frames)


def scene_time(scene, args) -> float:
    """``--time`` for a scene: it moves the scene's wind, so a scene without one refuses it."""
    t = getattr(args, "time", None)
    if t is None:
        return 0.0
    if scene.wind is None:

        raise ParamError(f"--time: {scene.path} has no [wind] and no --wind is given; expected a wind for the time to move")
    return float(t)


def render(scene, args, wind=None, options=None) -> None:
    """``render SCENE -o OUT.png``; ``--wind`` replaces the scene's [wind];
    ``options``: ``--no-cull``, ``--lod``, ``--lod-error`` (:func:`._common.cull_options`)."""
    from ..gl.image import parse_size, render_image

    _check_output(args, "PNG")
    fast = bool(getattr(args, "fast", False))
    check_triangles(scene, args, args.mode, fast)
    if wind is not None:
        scene.wind = wind
    _camera_args(scene, args, parse_size(args.size))
    image = render_image(scene, size=parse_size(args.size), modes=args.mode, look=scene.look.replace(fast=fast),
                         options=RenderOptions(time=scene_time(scene, args), **(options or {})))
    save_png(args.output, image)
    print(f"wrote {args.output} ({len(scene.layers)} layers, {scene.count} instances, {args.mode}, "
          f"{image.shape[1]}x{image.shape[0]})")


def _camera_args(scene, args, size) -> None:
    """``--eye``, ``--target`` and ``--fov`` put in the scene's camera where given (the scene's own framing
    fills the rest), checked as for a mesh and parameters (:func:`._common.view_args`)."""
    import dataclasses

    from ..gl.scene import scene_camera

    if args.eye is None and args.target is None and args.fov is None:
        return
    with_fov = lambda fov: dataclasses.replace(scene, camera=dataclasses.replace(scene.camera, fov=fov))  # noqa: E731
    eye, target, fov, _ = view_args(args, lambda fov: scene_camera(with_fov(fov), size[0] / size[1]), scene.up)
    scene.camera = dataclasses.replace(scene.camera, fov=fov, **({} if args.eye is None and args.target is None else
                                       {"eye": tuple(map(float, eye)), "target": tuple(map(float, target))}))


def bake(scene, args, progress, wind=None) -> None:
    """``bake SCENE -o OUT.npz``: arrays ``positions_LAYER`` and ``normals_LAYER``."""

    out = Path(args.output)
    if out.suffix.lower() != ".npz":
        raise AxialDeformError(f"{out}: a scene bakes to one .npz (arrays positions_LAYER, normals_LAYER); "
                               f"expected a .npz file name")
    _check_output(args, "bake output")
    check_baked_triangles(args, [(f"layer {layer.name}", len(layer.params), len(layer.mesh.faces))
                                 for layer in scene.layers], "")
    if wind is not None:
        scene.wind = wind
    t = scene_time(scene, args)
    # made and written in pieces, layer after layer: bounded by the disk, not memory
    shapes = {layer.name: (len(layer.params), layer.mesh.vertex_count, 3) for layer in scene.layers}
    needed = sum(36 * n * v for n, v, _ in shapes.values()) + (1 << 16)
    check_disk_space(out, needed, f"bake of {scene.count} instances (the .npz and, while it is written, a spooled "
                     "copy of a layer's normals)", ArgumentError)
    with progress(scene.count, f"{len(scene.layers)} layers ({args.engine})") as bar:
        pieces = [bake_pieces(layer.mesh, layer.params, args.engine, progress=bar,
                              options=RenderOptions(wind=scene.wind if layer.wind else None, time=t,
                                                    position_ids=layer.generate is not None), source=f"{scene.path}: {layer.name}")
                  for layer in scene.layers]
        try:
            write_npz_layers(out, [(f"_{layer.name}", p, len(layer.params), layer.mesh.vertex_count)
                                   for layer, p in zip(scene.layers, pieces)])
        finally:
            for p in pieces:
                p.close()
    print(f"wrote {out}: {', '.join(f'{k} {v}' for k, v in shapes.items())} float32 ({args.engine})")


def export(scene, args) -> None:
    """``export SCENE -o OUT.glb [--instanced]``: the terrain and one mesh per
    layer (baked), or per layer its base mesh once on a node with
    EXT_mesh_gpu_instancing (instanced)."""

    _check_output(args, "exported .glb")
    if args.layout == "baked":  # the layers' instances baked (the terrain is written once, as it is)
        check_baked_triangles(args, [(f"layer {layer.name}", len(layer.params), len(layer.mesh.faces))
                                     for layer in scene.layers], ", or use --instanced (no such limit)")
    path = export_scene(args.output, scene, args.layout)
    what = f"{scene.count} instances"
    if args.layout == "generated":
        gen = [layer.name for layer in scene.layers if getattr(layer, "generate", None) is not None]
        what = f"{', '.join(gen)} as their recipe with a small fallback"
    print(f"wrote {path} ({len(scene.layers)} layers, {what}, {args.layout}, "
          f"{path.stat().st_size} bytes)")


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use: axialdeform render|bake|export|view SCENE.toml")

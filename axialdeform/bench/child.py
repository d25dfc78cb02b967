"""One measurement of ``axialdeform bench``, in its own fresh process.

The parent (:func:`axialdeform.bench.run_bench`) starts ``python -c`` with a JSON spec;
this module sets up one method (``same``, ``loaded``, ``axial``,
``axial-quantized``), prints ``FIRST`` as soon as its first frame is finished
(``ctx.finish()``), then draws the warm-up and timed frames and prints one
``RESULT {json}`` line.  It imports only what a measurement needs, so the
harness adds as little as it can to the time of every method alike.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import moderngl
import numpy as np

from ..core.io.image import save_png
from ..core.io.mesh import load_mesh
from ..core.io.params import read_params
from ..core.options import RenderOptions
from ..core.variation import random_params
from ..gl.context import Offscreen, create_context
from ..gl.renderer import AxialRenderer
from .baked import BakedMeshes
from .plan import obj_name, scene_kwargs


def main(spec_text: str) -> None:
    """Entry point of one measurement process (``python -c``); prints
    ``FIRST`` when its first frame is finished, then one ``RESULT {json}`` line."""
    stamps = {"imported": time.time()}  # the interpreter and axialdeform (this module's package) are loaded
    spec = json.loads(spec_text)
    ctx, target, view, proj = _open(spec)
    stamps["context"] = time.time()
    draw, info = _setup(ctx, spec, view, proj, spec["mode"], stamps)
    stamps["uploaded"] = time.time()
    target.use()
    draw()
    ctx.finish()
    stamps["first_frame"] = time.time()
    _say("FIRST")
    frames = []
    for k in range(spec["warmup"] + spec["frames"]):
        t = time.perf_counter()
        target.use()
        draw()
        ctx.finish()
        if k >= spec["warmup"]:
            frames.append(time.perf_counter() - t)
    if spec.get("image"):

        save_png(spec["image"], target.read())
    info["trimesh_imported"] = "trimesh" in sys.modules
    info["gl_error"] = ctx.error
    _say("RESULT " + json.dumps({"stamps": stamps, "frames": frames, "info": info}))


def interleaved(spec_text: str) -> None:
    """Entry point of the frame-time process of one count x mode: every
    method is set up in this one process, then the frames go round the
    methods (A B C D A B C D ...), each ``clear + draw + ctx.finish()``
    timed, so that load from elsewhere on the machine hits all methods
    alike.  Prints one ``RESULT {json}`` line with each method's frame times
    (the warm-up rounds left out)."""
    spec = json.loads(spec_text)
    ctx, target, view, proj = _open(spec)
    setups = [(sub["method"], *_setup(ctx, sub, view, proj, spec["mode"], {})) for sub in spec["methods"]]
    frames = {name: [] for name, _, _ in setups}
    for k in range(spec["warmup"] + spec["frames"]):
        for name, draw, _ in setups:
            t = time.perf_counter()
            target.use()
            draw()
            ctx.finish()
            if k >= spec["warmup"]:
                frames[name].append(time.perf_counter() - t)
    info = {name: i for name, _, i in setups}
    _say("RESULT " + json.dumps({"frames": frames, "info": info, "gl_error": ctx.error}))


def _say(line: str) -> None:
    """One line of the protocol with the parent (stdout, flushed at once)."""
    sys.stdout.write(line + "\n")
    sys.stdout.flush()


def _open(spec: dict):
    """The context, the offscreen target and the camera of a measurement."""

    ctx = create_context()
    target = Offscreen(ctx, tuple(spec["size"]), samples=spec["samples"])
    return ctx, target, np.asarray(spec["view"], dtype=np.float32), np.asarray(spec["proj"], dtype=np.float32)


def _setup(ctx, spec: dict, view, proj, mode: str, stamps: dict):
    """``(draw, info)`` of the method ``spec["method"]``, set up in ``ctx``."""

    return _SETUPS[spec["method"]](ctx, spec, view, proj, mode, moderngl, stamps)


def _setup_same(ctx, spec, view, proj, mode, moderngl, stamps):
    mesh = load_mesh(spec["mesh"])
    # the placement is computed, not read: the thesis's "all the same" reads one mesh only
    params = random_params(mesh, spec["count"], spec["seed"], **scene_kwargs(mesh, spec["scene"]))
    stamps["read"] = time.time()
    r = AxialRenderer(ctx, mesh, params, options=RenderOptions(bend=False))
    return (lambda: r.render(view, proj, mode)), {"cull_back_faces": r.cull_back_faces}


def _setup_axial(ctx, spec, view, proj, mode, moderngl, stamps):
    mesh = load_mesh(spec["mesh"])
    params = read_params(spec["params"], mesh)
    stamps["read"] = time.time()
    # the quantized method keeps its 32 bytes an instance on the GPU too
    r = AxialRenderer(ctx, mesh, params, options=RenderOptions(quantized=spec["method"] == "axial-quantized"))
    return (lambda: r.render(view, proj, mode)), {"gpu_quantized": r.quantized, "cull_back_faces": r.cull_back_faces}


def _setup_loaded(ctx, spec, view, proj, mode, moderngl, stamps):
    """Read every pre-deformed OBJ file with load_mesh, one VBO/IBO/VAO each."""

    folder = Path(spec["folder"])
    meshes = None
    for i in range(spec["count"]):  # one file, one upload, one VAO per instance: what this method is
        mesh = load_mesh(folder / obj_name(i))
        if meshes is None:  # the same shading and culling as the instanced methods
            meshes = BakedMeshes(ctx, mesh, mode)
        meshes.add(mesh)
    stamps["read"] = time.time()
    return (lambda: meshes.render(view, proj)), {"cull_back_faces": meshes.cull_back_faces}


_SETUPS = {"same": _setup_same, "loaded": _setup_loaded, "axial": _setup_axial, "axial-quantized": _setup_axial}
